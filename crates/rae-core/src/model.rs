//! The architecture a weights file declares, and what follows from it (tensor shapes, cost).
//!
//! The same fields are written by `weights-tool` (`rae_weights/arch.py`) as JSON under the
//! safetensors metadata key [`ARCH_KEY`]; unknown fields are an error, so a file from a newer
//! writer is refused rather than misread.

use serde::Deserialize;

use crate::error::{Error, Result};

/// Metadata key holding the architecture JSON.
pub const ARCH_KEY: &str = "rae.arch";

/// A buffer a renderer hands over for each frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum InputBuffer {
    /// Noisy radiance, RGB.
    Color,
    /// First-hit albedo, RGB.
    Albedo,
    /// First-hit shading normal, world-space xyz.
    Normal,
    /// Distance along the primary ray.
    Depth,
    /// First-hit roughness.
    Roughness,
}

impl InputBuffer {
    /// All buffers, in the order rae lists them.
    pub const ALL: [InputBuffer; 5] = [Self::Color, Self::Albedo, Self::Normal, Self::Depth, Self::Roughness];

    /// Values per pixel.
    pub fn channels(self) -> usize {
        match self {
            Self::Color | Self::Albedo | Self::Normal => 3,
            Self::Depth | Self::Roughness => 1,
        }
    }

    /// The name used in files and metadata.
    pub fn name(self) -> &'static str {
        match self {
            Self::Color => "color",
            Self::Albedo => "albedo",
            Self::Normal => "normal",
            Self::Depth => "depth",
            Self::Roughness => "roughness",
        }
    }
}

/// Where the decoder takes its skip connections from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Skip {
    /// Reference code: pooled encoder output, concatenated before upsampling.
    Pooled,
    /// Paper: encoder output before pooling, concatenated after upsampling.
    Prepool,
}

/// Activation after the network's last convolution.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum OutputActivation {
    /// LeakyReLU, like every other layer (reference code).
    Lrelu,
    /// None (paper).
    Linear,
}

/// HDR transfer function applied to (demodulated) color before the network, inverted after.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Transfer {
    /// Identity.
    None,
    /// `log(1 + x)`, inverted by `exp(y) - 1`.
    Log1p,
}

/// Architecture of a recurrent denoising autoencoder, as declared by its weights file.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Arch {
    format: String,
    version: u32,
    /// Buffers packed into the network input, in channel order; `color` first.
    pub inputs: Vec<InputBuffer>,
    /// Color is divided by `albedo + albedo_eps` before the network and multiplied back after.
    pub demodulate: bool,
    /// Keeps demodulation finite where albedo is 0.
    pub albedo_eps: f32,
    /// Transfer function on color.
    pub transfer: Transfer,
    /// Widths of encoder blocks `d1..dN`.
    pub encoder: Vec<usize>,
    /// Width of the bottleneck block.
    pub bottleneck: usize,
    /// Skip-connection variant.
    pub skip: Skip,
    /// Activation of the last layer.
    pub output_activation: OutputActivation,
    /// Output channels (3: RGB).
    pub out_channels: usize,
    /// LeakyReLU slope.
    pub negative_slope: f32,
}

impl Arch {
    /// The reference code's network (8 inputs, widths 32-43-57-76-101, pooled skips).
    pub fn reference() -> Self {
        Self {
            format: "rae".into(),
            version: 1,
            inputs: vec![InputBuffer::Color, InputBuffer::Normal, InputBuffer::Depth, InputBuffer::Roughness],
            demodulate: true,
            albedo_eps: 1e-3,
            transfer: Transfer::Log1p,
            encoder: vec![32, 43, 57, 76, 101],
            bottleneck: 101,
            skip: Skip::Pooled,
            output_activation: OutputActivation::Lrelu,
            out_channels: 3,
            negative_slope: 0.1,
        }
    }

    /// Parse and validate the JSON stored under [`ARCH_KEY`]; `origin` names the file in errors.
    pub fn from_json(json: &str, origin: &str) -> Result<Self> {
        let arch: Arch = serde_json::from_str(json).map_err(|e| Error::Arch { origin: origin.into(), reason: e.to_string() })?;
        arch.validate(origin)?;
        Ok(arch)
    }

    fn validate(&self, origin: &str) -> Result<()> {
        let fail = |reason: String| Err(Error::Arch { origin: origin.into(), reason });
        if self.format != "rae" || self.version != 1 {
            return fail(format!("format {:?} version {} (this build reads rae version 1)", self.format, self.version));
        }
        if self.inputs.first() != Some(&InputBuffer::Color) {
            return fail("inputs must start with color".into());
        }
        for (i, b) in self.inputs.iter().enumerate() {
            if self.inputs[..i].contains(b) {
                return fail(format!("input `{}` listed twice", b.name()));
            }
        }
        if self.encoder.is_empty() || self.encoder.len() > 8 {
            return fail(format!("{} encoder levels (1 to 8 supported)", self.encoder.len()));
        }
        if self.encoder.iter().chain([&self.bottleneck]).any(|&w| w == 0 || w > 1024) {
            return fail(format!("widths {:?} / bottleneck {} out of range 1..=1024", self.encoder, self.bottleneck));
        }
        if self.out_channels != 3 {
            return fail(format!("out_channels {} (rae outputs RGB: 3)", self.out_channels));
        }
        if !(self.albedo_eps > 0.0 && self.albedo_eps.is_finite()) {
            return fail(format!("albedo_eps {} must be positive", self.albedo_eps));
        }
        if !self.negative_slope.is_finite() {
            return fail("negative_slope is not finite".into());
        }
        Ok(())
    }

    /// Encoder levels (pooling steps); frames are padded to a multiple of `2^levels`.
    pub fn levels(&self) -> usize {
        self.encoder.len()
    }

    /// Channels of the packed network input.
    pub fn in_channels(&self) -> usize {
        self.inputs.iter().map(|b| b.channels()).sum()
    }

    /// Which of the buffers the model reads tell a miss (a pixel whose camera ray hit nothing,
    /// see [`crate::frame`]): (depth, normal). Where it reads neither, no pixel is a miss.
    pub fn miss_by(&self) -> (bool, bool) {
        (self.inputs.contains(&InputBuffer::Depth), self.inputs.contains(&InputBuffer::Normal))
    }

    /// Buffers each frame must carry: the network inputs, and albedo when demodulating.
    pub fn required_buffers(&self) -> Vec<InputBuffer> {
        let mut need = self.inputs.clone();
        if self.demodulate && !need.contains(&InputBuffer::Albedo) {
            need.push(InputBuffer::Albedo);
        }
        need
    }

    /// Output width of decoder block `u{k}` (k = 1..=levels).
    pub fn decoder_width(&self, k: usize) -> usize {
        if k == 1 { self.out_channels } else { self.encoder[k - 2] }
    }

    /// Every convolution as (PyTorch module name, input channels, output channels), in the order
    /// the network runs them.
    pub fn convs(&self) -> Vec<(String, usize, usize)> {
        let mut v = Vec::new();
        let mut cin = self.in_channels();
        for (i, &w) in self.encoder.iter().enumerate() {
            let k = i + 1;
            v.push((format!("d{k}.l1.0"), cin, w));
            v.push((format!("d{k}.l2.0"), 2 * w, w));
            v.push((format!("d{k}.l2.2"), w, w));
            cin = w;
        }
        let b = self.bottleneck;
        v.push(("bottleneck.l1.0".into(), cin, b));
        v.push(("bottleneck.l2.0".into(), 2 * b, b));
        v.push(("bottleneck.l2.2".into(), b, b));
        let mut prev = b;
        for k in (1..=self.levels()).rev() {
            let out = self.decoder_width(k);
            v.push((format!("u{k}.l1.1"), prev + self.encoder[k - 1], out));
            v.push((format!("u{k}.l1.3"), out, out));
            prev = out;
        }
        v
    }

    /// Every tensor the weights file must hold, with its shape (`.weight` OIHW, `.bias`).
    pub fn tensor_shapes(&self) -> Vec<(String, Vec<usize>)> {
        self.convs()
            .into_iter()
            .flat_map(|(name, cin, cout)| [(format!("{name}.weight"), vec![cout, cin, 3, 3]), (format!("{name}.bias"), vec![cout])])
            .collect()
    }

    /// Number of parameters.
    pub fn parameter_count(&self) -> usize {
        self.tensor_shapes().iter().map(|(_, s)| s.iter().product::<usize>()).sum()
    }
}

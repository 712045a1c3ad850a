//! A frame's buffers as host slices, and the input policy applied to them.
//!
//! # Input policy
//! The renderer's buffers are tightly packed f32, row-major, top row first: RGB for color,
//! albedo and normal, one value per pixel for depth and roughness. Before anything else every
//! value is made finite and bounded, on the GPU, in `shaders/input_policy.wgsl` (shared by
//! `prep.wgsl` and `output.wgsl`; identically in [`crate::cpu`] and the PyTorch model of
//! weights-tool):
//!
//! | buffer | NaN | +Inf | -Inf | clamped to |
//! |---|---|---|---|---|
//! | color | 0 | 1e8 | 0 | [0, 1e8] |
//! | albedo | 0 | 0 | 0 | [0, 1e3] |
//! | normal | 0 | 0 | -1 | [-1, 1] |
//! | depth | 1e6 | 1e6 | 1e6 | (0, 1e6], a value <= 0 becomes 1e6; then log1p |
//! | roughness | 0 | 0 | 0 | [0, 1] |
//!
//! A depth of 1e6 is a miss, whatever the renderer wrote for it (+inf, 0, a huge value).
//!
//! # Misses
//! A pixel whose camera ray hit nothing is a *miss*, told from the buffers the model reads
//! ([`crate::Arch::miss_by`]): depth 1e6 as above, or a normal of zero (rae-trace and Cycles
//! write 0 there). At a miss albedo counts as 1, for the network's input and for demodulation
//! alike (renderers write 0, the sky's colour or anything else there; dividing a background by
//! 0 + eps would make it a thousand times brighter than it is, for the network to spread into
//! the geometry beside it), and the output is the input color: the renderer looks the
//! background up, it does not estimate it.
//!
//! Demodulation divides by `albedo + albedo_eps` (never by zero); the output is
//! `(exp(clamp(y, 0, L)) - 1) * (albedo + albedo_eps)` with `L = min(80, log1p(2 M))`, `M` the
//! frame's largest demodulated input radiance: finite, non-negative, and at most
//! `(albedo + eps) * 2 M` (docs/STABILITY.md, [`crate::cpu::output_limit`]).

use crate::error::{Error, Result};
use crate::model::InputBuffer;

/// Motion beyond this many times the frame's larger side is invalid: that pixel keeps no history
/// (weights-tool's `warp.ABSURD`).
pub const MOTION_ABSURD: f32 = 4.0;

/// A frame size written `WxH` (`1920x1080`), as the command lines (rae-cli, rae-trace) take
/// it: both whole numbers, both positive.
pub fn parse_size(text: &str) -> Result<(u32, u32)> {
    let bad = |reason| Error::SizeText { text: text.to_string(), reason };
    let (w, h) = text.split_once('x').ok_or_else(|| bad("not WxH"))?;
    let w: u32 = w.parse().map_err(|_| bad("the width is not a whole number"))?;
    let h: u32 = h.parse().map_err(|_| bad("the height is not a whole number"))?;
    if w == 0 || h == 0 {
        return Err(bad("empty"));
    }
    Ok((w, h))
}

/// One frame's buffers on the host. `color` is required; the others are used when the model
/// declares them (see [`crate::Arch::required_buffers`]).
#[derive(Debug, Clone, Copy, Default)]
pub struct FrameInputs<'a> {
    /// Noisy radiance, RGB.
    pub color: &'a [f32],
    /// First-hit albedo, RGB.
    pub albedo: Option<&'a [f32]>,
    /// First-hit shading normal, RGB = xyz.
    pub normal: Option<&'a [f32]>,
    /// Distance along the primary ray, one value per pixel.
    pub depth: Option<&'a [f32]>,
    /// First-hit roughness, one value per pixel.
    pub roughness: Option<&'a [f32]>,
    /// Motion, two values per pixel: where the pixel's surface point was in the previous frame
    /// minus where it is now, in pixels, x right, y down. Used by a [`crate::Denoiser`] built
    /// with [`crate::Options::motion`] to reproject its hidden state; `None` leaves the state as
    /// it is. NaN, infinite or absurd motion (beyond 4 x the frame's larger side) drops the
    /// pixel's history.
    pub motion: Option<&'a [f32]>,
}

impl<'a> FrameInputs<'a> {
    /// The slice of a buffer, if present.
    pub fn get(&self, buffer: InputBuffer) -> Option<&'a [f32]> {
        match buffer {
            InputBuffer::Color => Some(self.color),
            InputBuffer::Albedo => self.albedo,
            InputBuffer::Normal => self.normal,
            InputBuffer::Depth => self.depth,
            InputBuffer::Roughness => self.roughness,
        }
    }

    /// Check that every buffer in `needed` is present with `width * height * channels` values.
    pub fn validate(&self, needed: &[InputBuffer], width: u32, height: u32) -> Result<()> {
        for &b in needed {
            let data =
                self.get(b).ok_or_else(|| Error::MissingInput { buffer: b.name(), needed: needed.iter().map(|b| b.name()).collect() })?;
            let expected = width as usize * height as usize * b.channels();
            if data.len() != expected {
                return Err(Error::InputSize { buffer: b.name(), found: data.len(), expected, width, height, channels: b.channels() });
            }
        }
        if let Some(m) = self.motion {
            let expected = width as usize * height as usize * 2;
            if m.len() != expected {
                return Err(Error::InputSize { buffer: "motion", found: m.len(), expected, width, height, channels: 2 });
            }
        }
        Ok(())
    }
}

/// Host-side wall time of one frame, split by phase.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameTimings {
    /// Copying the input buffers to the GPU.
    pub upload: std::time::Duration,
    /// From submit until the GPU finished the frame.
    pub gpu: std::time::Duration,
    /// Mapping and copying the output back.
    pub download: std::time::Duration,
}

#[cfg(test)]
mod tests {
    use super::parse_size;

    #[test]
    fn sizes_parse_and_bad_ones_say_why() {
        assert_eq!(parse_size("1920x1080").unwrap(), (1920, 1080));
        for (text, why) in [("1920", "not WxH"), ("x5", "width"), ("5x-1", "height"), ("0x8", "empty"), ("8x0", "empty")] {
            let err = parse_size(text).unwrap_err().to_string();
            assert!(err.contains(&format!("`{text}`")) && err.contains(why), "{text}: {err}");
        }
    }
}

//! Golden sequences written by weights-tool (`python -m rae_weights golden`): input frames and
//! PyTorch's output for each, in one safetensors file with a `rae.golden` metadata entry.

use std::collections::HashMap;
use std::path::Path;

use crate::error::{Error, Result};
use crate::frame::FrameInputs;

/// Metadata key of a golden file.
pub const GOLDEN_KEY: &str = "rae.golden";

/// A golden sequence.
#[derive(Debug, Clone)]
pub struct Golden {
    /// File name of the weights it was made with (beside the golden file).
    pub weights: String,
    /// Frame width.
    pub width: u32,
    /// Frame height.
    pub height: u32,
    /// Per frame: buffer name -> values; `"output"` is PyTorch's result.
    pub frames: Vec<HashMap<String, Vec<f32>>>,
}

/// What "close" means against PyTorch: `|a - b| <= rel * max(1, |b|)` for every value.
#[derive(Debug, Clone, Copy)]
pub struct Tolerance {
    /// Relative bound (absolute below 1).
    pub rel: f32,
}

impl Tolerance {
    /// The bound wgpu is held to against PyTorch.
    pub const GOLDEN: Tolerance = Tolerance { rel: 1e-4 };

    /// Largest ratio error / allowed over all values (<= 1 passes; non-finite is infinite),
    /// with its index, and the largest absolute error.
    pub fn worst(&self, actual: &[f32], expected: &[f32]) -> (f32, usize, f32) {
        assert_eq!(actual.len(), expected.len(), "lengths differ");
        let (mut ratio, mut at, mut max_abs) = (0.0f32, 0usize, 0.0f32);
        for (i, (a, e)) in actual.iter().zip(expected).enumerate() {
            let err = (a - e).abs();
            let r = if err.is_finite() { err / (self.rel * e.abs().max(1.0)) } else { f32::INFINITY };
            if r > ratio {
                (ratio, at) = (r, i);
            }
            max_abs = max_abs.max(if err.is_finite() { err } else { f32::INFINITY });
        }
        (ratio, at, max_abs)
    }
}

impl Golden {
    /// Read a golden file.
    pub fn load(path: impl AsRef<Path>) -> Result<Golden> {
        let path = path.as_ref();
        let bytes = std::fs::read(path).map_err(|source| Error::Io { path: path.into(), source })?;
        Self::from_bytes(&bytes, &path.display().to_string())
    }

    /// Read a golden file held in memory; `origin` names it in errors.
    pub fn from_bytes(bytes: &[u8], origin: &str) -> Result<Golden> {
        let bad = |reason: String| Error::WeightsFormat { origin: origin.to_string(), reason };
        let (_, meta) = safetensors::SafeTensors::read_metadata(bytes).map_err(|e| bad(e.to_string()))?;
        let st = safetensors::SafeTensors::deserialize(bytes).map_err(|e| bad(e.to_string()))?;
        let info: serde_json::Value = meta
            .metadata()
            .as_ref()
            .and_then(|m| m.get(GOLDEN_KEY))
            .and_then(|s| serde_json::from_str(s).ok())
            .ok_or_else(|| bad(format!("no `{GOLDEN_KEY}` metadata: not a golden file")))?;
        let field = |k: &str| info[k].as_u64().ok_or_else(|| bad(format!("golden metadata lacks `{k}`")));
        let n = field("frames")? as usize;
        let mut frames = vec![HashMap::new(); n];
        for name in st.names() {
            let Some((frame, buffer)) = name.strip_prefix("frame").and_then(|r| r.split_once('.')) else { continue };
            let i: usize = frame.parse().map_err(|_| bad(format!("tensor `{name}`")))?;
            let t = st.tensor(name).map_err(|e| bad(e.to_string()))?;
            if t.dtype() != safetensors::Dtype::F32 || i >= n {
                return Err(bad(format!("tensor `{name}` is not an F32 tensor of frames 0..{n}")));
            }
            let v = t.data().chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
            frames[i].insert(buffer.to_string(), v);
        }
        if let Some(i) = frames.iter().position(|f| !f.contains_key("color") || !f.contains_key("output")) {
            return Err(bad(format!("frame {i} lacks color or output")));
        }
        Ok(Golden {
            weights: info["weights"].as_str().ok_or_else(|| bad("golden metadata lacks `weights`".into()))?.to_string(),
            width: field("width")? as u32,
            height: field("height")? as u32,
            frames,
        })
    }

    /// Frame `i` as denoiser inputs.
    pub fn inputs(&self, i: usize) -> FrameInputs<'_> {
        let f = &self.frames[i];
        let get = |k: &str| f.get(k).map(|v| v.as_slice());
        FrameInputs {
            color: &f["color"],
            albedo: get("albedo"),
            normal: get("normal"),
            depth: get("depth"),
            roughness: get("roughness"),
            motion: get("motion"),
        }
    }

    /// PyTorch's output for frame `i`.
    pub fn expected(&self, i: usize) -> &[f32] {
        &self.frames[i]["output"]
    }
}

//! Loading a weights file: safetensors with the architecture in its metadata.
//!
//! Every tensor the declared architecture needs is checked for name, dtype (F32, or F16/BF16
//! widened on load), shape and finiteness; extra tensors are refused, so a file written for
//! another network is an error naming the tensor, never a silent misread or a panic.

use std::collections::HashMap;
use std::path::Path;

use safetensors::{Dtype, SafeTensors};

use crate::error::{Error, Result};
use crate::model::{ARCH_KEY, Arch};

/// A tensor as f32 values with its shape.
#[derive(Debug, Clone, PartialEq)]
pub struct Tensor {
    /// Shape, outermost first (OIHW for conv weights).
    pub shape: Vec<usize>,
    /// Values in row-major order.
    pub data: Vec<f32>,
}

/// A validated weights file: the architecture and every tensor it needs, by PyTorch name.
#[derive(Debug, Clone)]
pub struct Weights {
    /// The declared architecture.
    pub arch: Arch,
    tensors: HashMap<String, Tensor>,
    origin: String,
}

impl Weights {
    /// Read and validate a weights file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let bytes = std::fs::read(path).map_err(|source| Error::Io { path: path.into(), source })?;
        Self::from_bytes(&bytes, &path.display().to_string())
    }

    /// Validate weights held in memory; `origin` names them in errors.
    pub fn from_bytes(bytes: &[u8], origin: &str) -> Result<Self> {
        let format_err = |reason: String| Error::WeightsFormat { origin: origin.into(), reason };
        let (_, meta) = SafeTensors::read_metadata(bytes).map_err(|e| format_err(e.to_string()))?;
        let st = SafeTensors::deserialize(bytes).map_err(|e| format_err(e.to_string()))?;
        let json = meta
            .metadata()
            .as_ref()
            .and_then(|m| m.get(ARCH_KEY))
            .ok_or_else(|| Error::Arch { origin: origin.into(), reason: format!("no `{ARCH_KEY}` in the metadata") })?;
        let arch = Arch::from_json(json, origin)?;

        let shapes = arch.tensor_shapes();
        let mut tensors = HashMap::with_capacity(shapes.len());
        for (name, expected) in &shapes {
            let view = st.tensor(name).map_err(|_| Error::MissingTensor {
                origin: origin.into(),
                name: name.clone(),
                expected: expected.clone(),
            })?;
            if view.shape() != expected.as_slice() {
                return Err(Error::TensorShape {
                    origin: origin.into(),
                    name: name.clone(),
                    expected: expected.clone(),
                    found: view.shape().to_vec(),
                });
            }
            let data = to_f32(view.dtype(), view.data()).ok_or_else(|| Error::TensorDtype {
                origin: origin.into(),
                name: name.clone(),
                found: format!("{:?}", view.dtype()),
            })?;
            if data.iter().any(|v| !v.is_finite()) {
                return Err(Error::NonFiniteTensor { origin: origin.into(), name: name.clone() });
            }
            tensors.insert(name.clone(), Tensor { shape: expected.clone(), data });
        }
        if let Some(extra) = st.names().into_iter().find(|n| !tensors.contains_key(*n)) {
            return Err(Error::UnexpectedTensor { origin: origin.into(), name: extra.to_string() });
        }
        Ok(Self { arch, tensors, origin: origin.into() })
    }

    /// A tensor by PyTorch name (`"d1.l1.0.weight"`); every name of the architecture is present.
    pub fn get(&self, name: &str) -> Option<&Tensor> {
        self.tensors.get(name)
    }

    /// Where these weights came from (file name).
    pub fn origin(&self) -> &str {
        &self.origin
    }
}

/// Little-endian tensor bytes -> f32; None for dtypes rae does not read.
fn to_f32(dtype: Dtype, bytes: &[u8]) -> Option<Vec<f32>> {
    match dtype {
        Dtype::F32 => Some(bytes.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect()),
        Dtype::F16 => Some(bytes.chunks_exact(2).map(|c| half::f16::from_le_bytes([c[0], c[1]]).to_f32()).collect()),
        Dtype::BF16 => Some(bytes.chunks_exact(2).map(|c| half::bf16::from_le_bytes([c[0], c[1]]).to_f32()).collect()),
        _ => None,
    }
}

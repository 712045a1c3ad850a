//! rae-core: the Recurrent Denoising Autoencoder (Chaitanya et al., SIGGRAPH 2017) on wgpu.
//!
//! Load a weights file ([`Weights::load`]), open a GPU ([`Gpu::new`]), build a [`Denoiser`]
//! for a frame size, then denoise frame after frame: from host slices ([`Denoiser::denoise`])
//! or inside a renderer's own command encoder on its own buffers ([`Denoiser::record`]). The
//! hidden state stays on the GPU between frames; [`Denoiser::reset`] starts a new sequence.

pub mod accumulate;
pub mod cpu;
pub mod denoiser;
pub mod error;
pub mod frame;
pub mod golden;
pub mod gpu;
pub mod graph;
pub mod io;
pub mod kernels;
pub mod metrics;
pub mod model;
pub mod weights;

pub use denoiser::{Denoiser, Finalist, GpuFrameIo, IoBinding, Options, TileChoice};
pub use error::{Error, Result};
pub use frame::{FrameInputs, FrameTimings};
pub use gpu::Gpu;
pub use kernels::{Method, Precision, SourceAccess, Tile, WeightMemory};
pub use model::{Arch, InputBuffer};
pub use weights::Weights;

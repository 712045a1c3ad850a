//! The one error type of rae-core.

use std::path::PathBuf;

/// Everything that can go wrong in rae-core, with the file, tensor or buffer it concerns.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the OS said.
        #[source]
        source: std::io::Error,
    },
    /// The weights file is not a readable safetensors file (truncated, corrupt header, ...).
    #[error("{origin}: not a valid weights file: {reason}")]
    WeightsFormat {
        /// File name or other origin of the bytes.
        origin: String,
        /// What is wrong.
        reason: String,
    },
    /// The declared architecture is missing, unknown or inconsistent.
    #[error("{origin}: architecture: {reason}")]
    Arch {
        /// File name or other origin.
        origin: String,
        /// What is wrong.
        reason: String,
    },
    /// A tensor the architecture needs is not in the file.
    #[error("{origin}: tensor `{name}` is missing (expected shape {expected:?})")]
    MissingTensor {
        /// File name.
        origin: String,
        /// PyTorch name of the tensor.
        name: String,
        /// Shape the architecture implies.
        expected: Vec<usize>,
    },
    /// A tensor is stored with a dtype rae cannot use.
    #[error("{origin}: tensor `{name}` has dtype {found}, expected F32")]
    TensorDtype {
        /// File name.
        origin: String,
        /// PyTorch name of the tensor.
        name: String,
        /// The dtype found.
        found: String,
    },
    /// A tensor's shape does not match the architecture.
    #[error("{origin}: tensor `{name}` has shape {found:?}, expected {expected:?}")]
    TensorShape {
        /// File name.
        origin: String,
        /// PyTorch name of the tensor.
        name: String,
        /// Shape the architecture implies.
        expected: Vec<usize>,
        /// Shape in the file.
        found: Vec<usize>,
    },
    /// A tensor holds NaN or infinity.
    #[error("{origin}: tensor `{name}` holds non-finite values")]
    NonFiniteTensor {
        /// File name.
        origin: String,
        /// PyTorch name of the tensor.
        name: String,
    },
    /// The file holds a tensor the architecture does not use (a mislabelled file).
    #[error("{origin}: tensor `{name}` is not part of the declared architecture")]
    UnexpectedTensor {
        /// File name.
        origin: String,
        /// PyTorch name of the tensor.
        name: String,
    },
    /// No adapter matched; says how to get one.
    #[error(
        "no GPU adapter found{wanted}; adapters seen: [{seen}]. For a CPU Vulkan driver install \
         lavapipe (Debian/Ubuntu: `apt-get install mesa-vulkan-drivers`); WGPU_BACKEND and \
         WGPU_ADAPTER_NAME choose among adapters"
    )]
    NoAdapter {
        /// " matching WGPU_ADAPTER_NAME=...", or empty.
        wanted: String,
        /// Adapters that were found but not chosen.
        seen: String,
    },
    /// The adapter refused to give a device.
    #[error("could not open the GPU device: {0}")]
    RequestDevice(#[from] wgpu::RequestDeviceError),
    /// A frame lacks a buffer the model needs.
    #[error("frame lacks the `{buffer}` buffer, which the model needs (it declares inputs {needed:?})")]
    MissingInput {
        /// The buffer.
        buffer: &'static str,
        /// All buffers the model needs.
        needed: Vec<&'static str>,
    },
    /// A buffer has the wrong number of values for the frame size.
    #[error("`{buffer}` buffer holds {found} values, expected {expected} ({width}x{height}x{channels})")]
    InputSize {
        /// The buffer.
        buffer: &'static str,
        /// Values found.
        found: usize,
        /// Values expected.
        expected: usize,
        /// Frame width.
        width: u32,
        /// Frame height.
        height: u32,
        /// Channels of the buffer.
        channels: usize,
    },
    /// A GPU buffer handed in is too small or lacks a usage, or one the denoiser needs is past
    /// the device's limits.
    #[error("GPU buffer `{buffer}`: {reason}")]
    GpuBuffer {
        /// The buffer.
        buffer: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// The frame size is zero or beyond the device's limits.
    #[error("frame size {width}x{height}: {reason}")]
    FrameSize {
        /// Width.
        width: u32,
        /// Height.
        height: u32,
        /// What is wrong.
        reason: String,
    },
    /// A memory cap below what the smallest tiles of a frame need.
    #[error("a memory cap of {} MiB is too small for {width}x{height} frames: the smallest tiles need {} MiB", cap / (1 << 20), smallest.div_ceil(1 << 20))]
    MemoryCap {
        /// Width.
        width: u32,
        /// Height.
        height: u32,
        /// The cap, in bytes.
        cap: u64,
        /// The smallest cap that works, in bytes.
        smallest: u64,
    },
    /// What a tiled denoiser cannot do.
    #[error("tiled frames: {0}")]
    Tiled(&'static str),
    /// An input frame file or folder is unusable.
    #[error("{path}: {reason}")]
    Input {
        /// The file or folder.
        path: PathBuf,
        /// What is wrong and, where it helps, what to do.
        reason: String,
    },
    /// An output file or folder cannot be written.
    #[error("{path}: {reason}")]
    Output {
        /// The file or folder.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// Motion given to a denoiser built without it, or a motion buffer that does not fit.
    #[error("motion: {0}")]
    Motion(String),
    /// The GPU failed while running or reading back a frame.
    #[error("GPU: {0}")]
    Gpu(String),
    /// A frame size on a command line that is not `WxH` with both positive.
    #[error("size `{text}`: {reason}")]
    SizeText {
        /// The text as given.
        text: String,
        /// What is wrong with it.
        reason: &'static str,
    },
    /// A tile or tile choice given as text that names none the kernels have.
    #[error("tile `{text}`: {reason}")]
    TileText {
        /// The text.
        text: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A conv tile this device cannot run.
    #[error("tile {tile}: {reason}")]
    UnsupportedTile {
        /// The tile as written (`lanes16x4`).
        tile: String,
        /// What the device lacks.
        reason: String,
    },
}

/// Result with rae-core's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

//! The WGSL kernels and how a device runs them: storage precision, where a conv reads its
//! weights and sources, what the device can run ([`lanes_supported`], [`matrix_units_supported`],
//! ...), and the submodules:
//! - [`shaders`]: the table of WGSL sources and the text rewrites a module is made with;
//! - [`tile`]: a conv's register tile ([`Tile`], [`Method`]) and the CPU drivers' choice of it;
//! - [`packing`]: the weight layouts the kernels read (direct, Winograd, matrix units);
//! - [`pipelines`]: bind-group layouts, uniform blocks and the pipeline cache ([`Kernels`]);
//! - [`plan`]: a network's convs planned on one device ([`ConvPlan`]).

pub mod packing;
pub mod pipelines;
pub mod plan;
pub mod shaders;
pub mod tile;

pub use packing::*;
pub use pipelines::*;
pub use plan::*;
pub use shaders::*;
pub use tile::*;

/// Where a conv finds a value carved into the cells of an arena ([`crate::graph::Place`]): its
/// first cell, its level and the level's size, as conv_common.wgsl's `carved` reads them;
/// [`Carve::NONE`] for a value read as its view binds it.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Carve {
    /// The value's first cell, in cells of its level.
    pub first: u32,
    /// Its level (0: not carved).
    pub level: u32,
    /// The level's width: a cell's.
    pub width: u32,
    /// The level's height.
    pub height: u32,
}

impl Carve {
    /// Not carved.
    pub const NONE: Carve = Carve { first: 0, level: 0, width: 0, height: 0 };

    /// The carve of a value placed at `p` in arenas of `pwidth` x `pheight`.
    pub fn of(p: &crate::graph::Place, pwidth: u32, pheight: u32) -> Self {
        Carve { first: p.first, level: p.level as u32, width: pwidth >> p.level, height: pheight >> p.level }
    }

    /// Whether the value is carved (below the arena's resolution).
    pub fn is_carved(&self) -> bool {
        self.level > 0
    }
}

/// vec4s in one weight chunk (`CHUNK` in conv3x3.wgsl): a 64 KiB uniform binding, the limit
/// every WebGPU device guarantees.
pub const WEIGHT_CHUNK: u32 = 4096;
/// Bytes of one weight-chunk binding.
pub const WEIGHT_CHUNK_BYTES: u64 = WEIGHT_CHUNK as u64 * 16;
/// Storage precision of activations and hidden state (arithmetic is f32 in both).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Precision {
    /// rgba32float textures.
    #[default]
    F32,
    /// rgba16float textures: half the memory and bandwidth. Every stored value is clamped to
    /// [-F16_MAX, F16_MAX] by the kernel that writes it, so f16 storage never holds an infinity.
    F16,
}

/// Largest finite f16, the clamp of every value stored in f16.
pub const F16_MAX: f32 = 65504.0;

impl Precision {
    /// Texture format of activations in this precision: a layer holds 4 channels.
    pub fn format(self) -> wgpu::TextureFormat {
        match self {
            Precision::F32 => wgpu::TextureFormat::Rgba32Float,
            Precision::F16 => wgpu::TextureFormat::Rgba16Float,
        }
    }

    /// Bytes of one texel.
    pub fn texel_bytes(self) -> u64 {
        match self {
            Precision::F32 => 16,
            Precision::F16 => 8,
        }
    }

    /// Largest magnitude a kernel stores.
    pub fn store_max(self) -> f32 {
        match self {
            Precision::F32 => f32::MAX,
            Precision::F16 => F16_MAX,
        }
    }

    /// Name for tables and command lines.
    pub fn name(self) -> &'static str {
        match self {
            Precision::F32 => "f32",
            Precision::F16 => "f16",
        }
    }
}

/// Where the conv kernel reads its weights from. The tiles of the lanes module (two-column
/// lanes, Winograd lanes: CPU drivers) read the plan's weight texture whatever this says
/// ([`TEXEL_WEIGHTS`]), and their pipelines take storage.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum WeightMemory {
    /// 64 KiB uniform chunks, bound by dynamic offset: as many output-block groups per dispatch
    /// as fit one chunk. On lavapipe a uniform load is one load and a broadcast, 2.5x faster
    /// than the storage version (docs/PERF.md), so CPU adapters use this on large levels.
    Uniform,
    /// One read-only storage buffer: every group of a conv in one dispatch. Discrete GPUs,
    /// whose deep levels are too small to fill the machine one 64 KiB group at a time, and the
    /// small levels on CPU drivers ([`WeightMemory::for_conv`]).
    Storage,
}

/// The most pixels of a level whose convs read storage weights on CPU drivers
/// ([`WeightMemory::for_conv`]): 32 x 32.
pub const CPU_STORAGE_WEIGHTS_MAX_PIXELS: u32 = 32 * 32;

impl WeightMemory {
    /// The kind that suits an adapter: uniform chunks on CPU drivers, storage elsewhere.
    pub fn for_device_type(t: wgpu::DeviceType) -> Self {
        if t == wgpu::DeviceType::Cpu { WeightMemory::Uniform } else { WeightMemory::Storage }
    }

    /// The kind that suits a conv on a `width` x `height` level of an adapter: storage on GPUs;
    /// on CPU drivers storage up to [`CPU_STORAGE_WEIGHTS_MAX_PIXELS`], uniform chunks above.
    ///
    /// Lavapipe runs a conv's dispatches one after another, and a uniform-chunk conv takes one
    /// dispatch per 64 KiB of weights. A deep conv (202 -> 101 channels: 12 chunks) on an 8 x 8
    /// level is then 12 dispatches of a workgroup or two each, which leave a core idle and
    /// pay each dispatch's start; one storage dispatch takes about half the time. On large
    /// levels every dispatch fills both cores, and the uniform loads win
    /// (`docs/perf/lavapipe-2026-11-24-s20.log`).
    ///
    /// The tiles of the lanes module (two-column lanes, Winograd lanes) read the plan's weight
    /// texture whatever this says ([`TEXEL_WEIGHTS`]): on lavapipe the deep levels' two-column
    /// convs take 0.75-0.85x the time of their storage loads
    /// (`docs/perf/lavapipe-2026-12-03-s33.log`). It still decides for
    /// the direct tiles and the one-column lanes ones (1-pixel-wide levels).
    pub fn for_conv(t: wgpu::DeviceType, width: u32, height: u32) -> Self {
        if t == wgpu::DeviceType::Cpu && width * height > CPU_STORAGE_WEIGHTS_MAX_PIXELS {
            WeightMemory::Uniform
        } else {
            WeightMemory::Storage
        }
    }

    /// Name for tables and command lines.
    pub fn name(self) -> &'static str {
        match self {
            WeightMemory::Uniform => "uniform",
            WeightMemory::Storage => "storage",
        }
    }
}

/// Storage textures a conv binds with storage sources: its two sources, the lanes tiles'
/// weight texture, its output and its pooled output (with sampled sources, the last two).
pub const STORAGE_SOURCE_TEXTURES: u32 = 5;

/// How the conv reads its two sources (the activations it convolves).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SourceAccess {
    /// Sampled textures, `textureLoad` at level 0: GPUs, where both paths go through the
    /// texture units (the H100 numbers in docs/PERF.md were measured so).
    Sampled,
    /// Read-only storage textures ([`STORAGE_SOURCES`]): CPU drivers. Lavapipe's sampler sets
    /// up every texel fetch with per-lane mip-level offsets; its storage-image load does not,
    /// and the default tile's fastest 256x256 frames take 0.82x the time (`docs/perf/lavapipe-2026-11-23-s10.log`).
    Storage,
}

impl SourceAccess {
    /// The kind that suits an adapter: storage textures on CPU drivers, sampled elsewhere.
    pub fn for_device_type(t: wgpu::DeviceType) -> Self {
        if t == wgpu::DeviceType::Cpu { SourceAccess::Storage } else { SourceAccess::Sampled }
    }

    /// The kind that suits a device: [`Self::for_device_type`], but sampled where the device
    /// binds fewer storage textures to a stage than storage sources take
    /// ([`STORAGE_SOURCE_TEXTURES`]): WebGPU's default limit is 4, and a browser's software
    /// adapter (SwiftShader) reports itself a CPU.
    pub fn for_device(device: &wgpu::Device) -> Self {
        match Self::for_device_type(device.adapter_info().device_type) {
            SourceAccess::Storage if !Self::storage_fits(device) => SourceAccess::Sampled,
            kind => kind,
        }
    }

    /// Whether a device binds enough storage textures to a stage for storage sources.
    pub fn storage_fits(device: &wgpu::Device) -> bool {
        device.limits().max_storage_textures_per_shader_stage >= STORAGE_SOURCE_TEXTURES
    }

    /// Name for tables and command lines.
    pub fn name(self) -> &'static str {
        match self {
            SourceAccess::Sampled => "sampled",
            SourceAccess::Storage => "storage",
        }
    }
}

/// Whether the staged outputs ([`Kernels::stage_outputs`]) are stored in 64-bit words
/// (conv3x3_stage64.wgsl): on CPU drivers whose device has [`wgpu::Features::SHADER_INT64`]
/// enabled ([`crate::Gpu`] asks for it where the adapter has it).
///
/// Lavapipe stores a buffer word by word in a loop over the subgroup's lanes, one loop per
/// store of up to four words; two floats to a word halve the loops for the same bytes. The
/// staged F(4x4) convs took 0.89-0.95x the time with them, the staged stores being 25-60% of
/// such a conv (`docs/perf/lavapipe-2026-12-02-s29.log`). GPUs store vectors and keep the 32-bit words.
pub fn wide_staged_stores(device: &wgpu::Device) -> bool {
    device.features().contains(wgpu::Features::SHADER_INT64) && device.adapter_info().device_type == wgpu::DeviceType::Cpu
}

/// Whether the Winograd lanes kernels take conv3x3_gather8.wgsl's gathers on `device`: its
/// subgroups may have fewer than 16 lanes (lavapipe without AVX-512: 8). A gather of 16 vec4s
/// is then two loads of 8; on 16 lanes or more one ([`LanesModule::gathers8`]).
pub fn narrow_gathers(device: &wgpu::Device) -> bool {
    device.adapter_info().subgroup_min_size < 16
}

/// Whether a device runs [`Method::Lanes`]: it has subgroups, and of at least 8 lanes (a tap's
/// weights are spread over lanes 0 to 7).
pub fn lanes_supported(device: &wgpu::Device) -> bool {
    device.features().contains(wgpu::Features::SUBGROUP) && device.adapter_info().subgroup_min_size >= 8
}

/// Whether a device runs [`Method::WinogradLanes`] and [`Method::Winograd4Lanes`]: it has
/// subgroups of at least 8 lanes (one input block's transformed weights are loaded 16 vec4s at a
/// time, in two loads where the subgroups have fewer than 16 lanes: [`narrow_gathers`]).
pub fn winograd_lanes_supported(device: &wgpu::Device) -> bool {
    lanes_supported(device)
}

/// Whether a device reads zero at a texel outside a texture, so that the conv kernels read
/// their zero padding without testing each pixel (conv_common.wgsl's OOB_ZERO): lavapipe.
///
/// WGSL lets an out-of-bounds `textureLoad` return any texel of the texture or zero, and wgpu
/// clamps the coordinates unless the device has Vulkan's robustImageAccess2, which lavapipe
/// (Mesa's llvmpipe) has: there wgpu leaves the loads unchecked and the driver returns zero.
/// Other devices keep the test (GPUs: not timed without it). `tests/engine/kernels.rs` reads
/// outside both source kinds' textures on the test device and holds this to what it finds.
/// A plan reads its padding so only where its caller asks ([`Kernels::pad_from_bounds`]).
pub fn out_of_bounds_reads_zero(device: &wgpu::Device) -> bool {
    let info = device.adapter_info();
    info.backend == wgpu::Backend::Vulkan && info.device_type == wgpu::DeviceType::Cpu && info.driver == "llvmpipe"
}

/// Whether a device runs [`Method::Mma`] in matrix units: it has wgpu's cooperative matrices
/// ([`crate::Gpu`] enables them only where [`crate::gpu::has_matrix_units`]: 16 x 16 x 16
/// f16 -> f32 and 32-lane subgroups; a device opened elsewhere with the feature must have the
/// same) and SHADER_F16. Elsewhere, with SHADER_F16, Mma tiles run `mma_emulated`.
pub fn matrix_units_supported(device: &wgpu::Device) -> bool {
    device.features().contains(wgpu::Features::EXPERIMENTAL_COOPERATIVE_MATRIX | wgpu::Features::SHADER_F16 | wgpu::Features::SUBGROUP)
}

/// Texture format of activations at f32 (weights-independent tests upload in it).
pub const ACTIVATION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// Channel blocks (texture layers) needed for `channels`.
pub fn blocks(channels: usize) -> u32 {
    channels.div_ceil(4) as u32
}

/// Conv `i`'s entry of a plan's choices: one entry for every conv, or one per conv.
pub(crate) fn per_conv<T: Copy>(choices: &[T], i: usize) -> T {
    choices[if choices.len() == 1 { 0 } else { i }]
}

//! The WGSL kernels: one table of sources, their bind-group layouts, pipelines specialised by
//! override constants, the uniform parameter blocks, and the weight layout the conv reads.

use std::collections::HashMap;

use bytemuck::{Pod, Zeroable};

use crate::graph::Read;

/// Every shader of rae, by name; the only place WGSL enters the crate.
pub const SHADERS: &[(&str, &str)] = &[
    ("conv3x3", include_str!("../../../shaders/conv3x3.wgsl")),
    ("conv3x3_rows", include_str!("../../../shaders/conv3x3_rows.wgsl")),
    ("conv3x3_wino", include_str!("../../../shaders/conv3x3_wino.wgsl")),
    ("conv3x3_wino4", include_str!("../../../shaders/conv3x3_wino4.wgsl")),
    ("conv3x3_gather16", include_str!("../../../shaders/conv3x3_gather16.wgsl")),
    ("conv3x3_gather8", include_str!("../../../shaders/conv3x3_gather8.wgsl")),
    ("conv3x3_stage64", include_str!("../../../shaders/conv3x3_stage64.wgsl")),
    ("conv3x3_mma", include_str!("../../../shaders/conv3x3_mma.wgsl")),
    ("conv3x3_mma_coop", include_str!("../../../shaders/conv3x3_mma_coop.wgsl")),
    ("conv_common", include_str!("../../../shaders/conv_common.wgsl")),
    ("prep", include_str!("../../../shaders/prep.wgsl")),
    ("output", include_str!("../../../shaders/output.wgsl")),
    ("pool", include_str!("../../../shaders/pool.wgsl")),
];

/// Most output rows per conv invocation (the tile of conv3x3.wgsl; `ROWS` picks up to it).
pub const CONV_ROWS: u32 = 16;
/// vec4s in one weight chunk (`CHUNK` in conv3x3.wgsl): a 64 KiB uniform binding, the limit
/// every WebGPU device guarantees.
pub const WEIGHT_CHUNK: u32 = 4096;
/// Bytes of one weight-chunk binding.
pub const WEIGHT_CHUNK_BYTES: u64 = WEIGHT_CHUNK as u64 * 16;
/// Workgroup size in x and y of every kernel (the conv's default shape; [`Tile::group_x`]).
pub const WORKGROUP: u32 = 8;
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

/// The most pixels of a level whose convs run 4-row lanes tiles on CPU drivers
/// ([`Tile::cpu_for`]): 8 x 8.
pub const CPU_SHORT_TILE_MAX_PIXELS: u32 = 8 * 8;

/// The fewest input blocks (4 channels each) of a conv that runs [`Tile::CPU_WINOGRAD`] on CPU
/// drivers ([`Tile::cpu_for`]): 8 (32 channels). The frame's 3-channel conv ran slower in it,
/// its 8-channel one as fast (docs/PERF.md, session 22).
pub const CPU_WINOGRAD_MIN_BLOCKS: u32 = 8;

/// The fewest pixels of a level whose convs run [`Tile::CPU_WINOGRAD4`] on CPU drivers that
/// run it (32 x 32): every conv there, down to one input block (the 256x256 frame's first conv,
/// 2 input blocks, took 0.82x the time of `lanes8x2w2`'s; docs/PERF.md, session 23).
pub const CPU_WINOGRAD4_MIN_PIXELS: u32 = 32 * 32;

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
    /// pay each dispatch's start; one storage dispatch took about half the time. On large
    /// levels every dispatch fills both cores, and the uniform loads win (docs/PERF.md,
    /// session 20).
    ///
    /// The tiles of the lanes module (two-column lanes, Winograd lanes) read the plan's weight
    /// texture whatever this says ([`TEXEL_WEIGHTS`]): on lavapipe the deep levels' two-column
    /// convs took 0.75-0.85x the time of their storage loads (session 33). It still decides for
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

/// How the conv reads its two sources (the activations it convolves).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SourceAccess {
    /// Sampled textures, `textureLoad` at level 0: GPUs, where both paths go through the
    /// texture units (the H100 numbers in docs/PERF.md were measured so).
    Sampled,
    /// Read-only storage textures ([`STORAGE_SOURCES`]): CPU drivers. Lavapipe's sampler sets
    /// up every texel fetch with per-lane mip-level offsets; its storage-image load does not,
    /// and the default tile's fastest 256x256 frames take 0.82x the time (docs/PERF.md, session 10).
    Storage,
}

impl SourceAccess {
    /// The kind that suits an adapter: storage textures on CPU drivers, sampled elsewhere.
    pub fn for_device_type(t: wgpu::DeviceType) -> Self {
        if t == wgpu::DeviceType::Cpu { SourceAccess::Storage } else { SourceAccess::Sampled }
    }

    /// Name for tables and command lines.
    pub fn name(self) -> &'static str {
        match self {
            SourceAccess::Sampled => "sampled",
            SourceAccess::Storage => "storage",
        }
    }
}

/// The weight declaration of conv3x3.wgsl (uniform chunks).
pub const UNIFORM_WEIGHTS: &str = "var<uniform> weights: array<vec4<f32>, CHUNK>;";
/// What [`UNIFORM_WEIGHTS`] becomes for [`WeightMemory::Storage`].
pub const STORAGE_WEIGHTS: &str = "var<storage, read> weights: array<vec4<f32>>;";

/// The rewrites of conv3x3.wgsl for [`SourceAccess::Storage`]: the sources' type alias and the
/// one function that reads them (a storage texture is read without a level).
pub const STORAGE_SOURCES: [(&str, &str); 2] = [
    ("alias Source = texture_2d_array<f32>;", "alias Source = texture_storage_2d_array<rgba32float, read>;"),
    ("return textureLoad(t, p, layer, 0);", "return textureLoad(t, p, layer);"),
];

/// conv3x3.wgsl's empty `accumulate_rows`, which the conv module that runs two-column lanes
/// tiles has replaced by conv3x3_rows.wgsl (and no other module: its unrolled body costs the
/// driver's front end seconds per pipeline even where no call reaches it).
pub const ROWS_STUB: &str = "fn accumulate_rows(acc0: ptr<function, Tile>, acc1: ptr<function, Tile>, acc2: ptr<function, Tile>, acc3: ptr<function, Tile>, acc4: ptr<function, Tile>, acc5: ptr<function, Tile>, acc6: ptr<function, Tile>, acc7: ptr<function, Tile>, cb: u32, w: u32, x: i32, y0: i32) {}";

/// The rewrite of conv3x3_wino4.wgsl where the sources are read-only storage textures: its
/// weight texture is read as one too (rgba32float whatever the activations' precision).
pub const STORAGE_WEIGHT_TEXELS: [(&str, &str); 2] = [
    ("alias WeightTexels = texture_2d<f32>;", "alias WeightTexels = texture_storage_2d<rgba32float, read>;"),
    (
        "textureLoad(weight_texels, vec2<u32>(i % WEIGHT_TEXELS_WIDTH, i / WEIGHT_TEXELS_WIDTH), 0)",
        "textureLoad(weight_texels, vec2<u32>(i % WEIGHT_TEXELS_WIDTH, i / WEIGHT_TEXELS_WIDTH))",
    ),
];

/// The rewrite of conv3x3.wgsl in the module of the two-column lanes and Winograd lanes tiles
/// ([`lanes_module_source`]): `weight` reads the plan's weight texture (conv3x3_wino4.wgsl's
/// `weight_texel`, from the group's first texel `params.weight_texel`), which holds the weights
/// of every conv those tiles run ([`ConvPlan`]).
///
/// A two-column lanes tile loads each input block's 36 x OB weight vec4s spread over the
/// subgroup's lanes. From a storage buffer lavapipe loads them lane by lane, from a uniform
/// chunk it gathers them but the conv takes a dispatch per 64 KiB chunk; from the texture it is
/// one gather, and one dispatch.
pub const TEXEL_WEIGHTS: [(&str, &str); 1] = [(
    "fn weight(i: u32) -> vec4<f32> {\n    return weights[i];\n}",
    "fn weight(i: u32) -> vec4<f32> {\n    return weight_texel(params.weight_texel + i);\n}",
)];

/// Texels per row of a [`ConvPlan`]'s weight texture (conv3x3_wino4.wgsl's
/// `WEIGHT_TEXELS_WIDTH`): within every device's 2D limit, and a row holds a few input blocks.
pub const WEIGHT_TEXELS_WIDTH: u32 = 4096;

/// The rewrite of conv3x3_wino4.wgsl whose staged stores are 64-bit words
/// ([`wide_staged_stores`]): its one call of `stage_row` becomes conv3x3_stage64.wgsl's
/// `stage_row64`, which the module then holds.
pub const WIDE_STAGED_STORES: [(&str, &str); 1] = [("        stage_row(", "        stage_row64(")];

/// Whether the staged outputs ([`Kernels::stage_outputs`]) are stored in 64-bit words
/// (conv3x3_stage64.wgsl): on CPU drivers whose device has [`wgpu::Features::SHADER_INT64`]
/// enabled ([`crate::Gpu`] asks for it where the adapter has it).
///
/// Lavapipe stores a buffer word by word in a loop over the subgroup's lanes, one loop per
/// store of up to four words; two floats to a word halve the loops for the same bytes. The
/// staged F(4x4) convs took 0.89-0.95x the time with them, the staged stores being 25-60% of
/// such a conv (docs/PERF.md, session 29). GPUs store vectors and keep the 32-bit words.
pub fn wide_staged_stores(device: &wgpu::Device) -> bool {
    device.features().contains(wgpu::Features::SHADER_INT64) && device.adapter_info().device_type == wgpu::DeviceType::Cpu
}

/// The rewrite of conv3x3_wino4.wgsl for convs of two sources: `wino4_step` takes whether
/// its block is source b's as an argument, a constant at each of its two calls, one loop per
/// source, where the kernel as written runs one loop over both sources' blocks and chooses the
/// window per block.
///
/// Lavapipe runs both sides of an `if` under a mask, so the one loop fetched both windows for
/// every block; two loops fetch one, and LLVM compiles the step's body twice (the 8x4 tile's
/// two-source pipeline in 9.2 s instead of 7.1). The two-source L0 convs took 0.90-0.96x the
/// time (docs/PERF.md, session 29). Convs of one source keep the kernel as written: their
/// module is another ([`Kernels`] makes one of each).
pub const TWO_SOURCE_LOOPS: [(&str, &str); 3] = [
    (
        "m13: ptr<function, Wino6>, cb: u32, w: u32, x: i32, y0: i32) {",
        "m13: ptr<function, Wino6>, cb: u32, w: u32, x: i32, y0: i32, from_b: bool) {",
    ),
    ("    if !SOURCE_B || cb < params.cin4_a {\n        k = window6(src_a", "    if !from_b {\n        k = window6(src_a"),
    (
        "    for (var c = 0u; c < blocks; c++) {\n        wino4_step(&m00, &m01, &m02, &m03, &m10, &m11, &m12, &m13, c, w, xi, yi);\n    }",
        "    for (var c = 0u; c < params.cin4_a; c++) {\n        wino4_step(&m00, &m01, &m02, &m03, &m10, &m11, &m12, &m13, c, w, xi, yi, false);\n    }\n    for (var c = params.cin4_a; c < blocks; c++) {\n        wino4_step(&m00, &m01, &m02, &m03, &m10, &m11, &m12, &m13, c, w, xi, yi, true);\n    }",
    ),
];

/// Which lanes module a conv's pipeline is made from ([`lanes_module_source`]): what the
/// device and the conv take beyond the source access.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct LanesModule {
    /// Staged stores in 64-bit words ([`WIDE_STAGED_STORES`], [`wide_staged_stores`]).
    pub wide_stores: bool,
    /// For convs of two sources: a loop per source ([`TWO_SOURCE_LOOPS`]).
    pub two_sources: bool,
    /// The Winograd kernels' gathers for 8-lane subgroups (conv3x3_gather8.wgsl) instead of 16
    /// (conv3x3_gather16.wgsl): [`narrow_gathers`].
    pub gathers8: bool,
    /// The two-column lanes tiles read their weights from the weight texture
    /// ([`TEXEL_WEIGHTS`]).
    pub texel_weights: bool,
}

/// The conv module `conv` (conv3x3.wgsl as [`Kernels`] rewrites it for sources read as
/// `access` says) as the lanes tiles run it: its [`ROWS_STUB`] replaced by conv3x3_rows.wgsl
/// (two-column lanes tiles), conv3x3_wino.wgsl (`winograd_lanes`), conv3x3_wino4.wgsl
/// (`winograd4_lanes`, its weight texture read as the sources are, [`STORAGE_WEIGHT_TEXELS`])
/// and the two Winograd kernels' gathers (conv3x3_gather16.wgsl, or conv3x3_gather8.wgsl with
/// `variant.gathers8`); with `variant.wide_stores`, the staged stores in 64-bit words
/// ([`WIDE_STAGED_STORES`]); with `variant.two_sources`, for convs of two sources,
/// [`TWO_SOURCE_LOOPS`].
pub fn lanes_module_source(conv: &str, access: SourceAccess, variant: LanesModule) -> String {
    assert!(conv.contains(ROWS_STUB), "conv3x3.wgsl has kernels::ROWS_STUB");
    let wino4 = shader_source("conv3x3_wino4").to_string();
    let wino4 = if access == SourceAccess::Storage { rewrite(wino4, "conv3x3_wino4.wgsl", &STORAGE_WEIGHT_TEXELS) } else { wino4 };
    let wino4 = if variant.two_sources { rewrite(wino4, "conv3x3_wino4.wgsl", &TWO_SOURCE_LOOPS) } else { wino4 };
    let wino4 = if variant.wide_stores {
        format!("{}\n{}", rewrite(wino4, "conv3x3_wino4.wgsl", &WIDE_STAGED_STORES), shader_source("conv3x3_stage64"))
    } else {
        wino4
    };
    let gathers = shader_source(if variant.gathers8 { "conv3x3_gather8" } else { "conv3x3_gather16" });
    let conv = if variant.texel_weights { rewrite(conv.to_string(), "conv3x3.wgsl", &TEXEL_WEIGHTS) } else { conv.to_string() };
    conv.replace(ROWS_STUB, &format!("{}\n{}\n{}\n{}", shader_source("conv3x3_rows"), shader_source("conv3x3_wino"), gathers, wino4))
}

/// Whether the Winograd lanes kernels take conv3x3_gather8.wgsl's gathers on `device`: its
/// subgroups may have fewer than 16 lanes (lavapipe without AVX-512: 8). A gather of 16 vec4s
/// is then two loads of 8; on 16 lanes or more one ([`LanesModule::gathers8`]).
pub fn narrow_gathers(device: &wgpu::Device) -> bool {
    device.adapter_info().subgroup_min_size < 16
}

/// The rewrites of conv3x3.wgsl for devices without [`wgpu::Features::SUBGROUP`] (naga refuses
/// subgroup operations anywhere in a module there): its subgroup operations become plain
/// functions and the `lanes` entry point's subgroup builtin another builtin. [`Method::Lanes`]
/// never runs on such a device ([`lanes_supported`]).
pub const WITHOUT_SUBGROUPS: [(&str, &str); 3] = [
    ("subgroupBroadcast(", "no_subgroups("),
    ("subgroupAny(", "no_subgroups_any("),
    ("@builtin(subgroup_invocation_id)", "@builtin(local_invocation_index)"),
];

/// The rewrite of prep.wgsl for devices without [`wgpu::Features::SUBGROUP`]: the frame's
/// maximum skips the subgroup step, every invocation testing its own value against it.
pub const PREP_WITHOUT_SUBGROUPS: [(&str, &str); 1] = [("subgroupMax(", "no_subgroup_max(")];

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

/// The enable directive of conv3x3_mma.wgsl that [`mma_source`] extends.
pub const MMA_ENABLE: &str = "enable f16;";

/// conv3x3_mma.wgsl as a device runs it: with conv3x3_mma_coop.wgsl's entry point `mma` and
/// the cooperative-matrix enable where `matrix_units` ([`matrix_units_supported`]), else as
/// written (only `mma_emulated`: naga refuses cooperative matrix types in a module on a device
/// without the feature).
pub fn mma_source(matrix_units: bool) -> String {
    let base = conv_module_source("conv3x3_mma");
    if !matrix_units {
        return base;
    }
    assert!(base.contains(MMA_ENABLE), "conv3x3_mma.wgsl has kernels::MMA_ENABLE");
    format!("{}\n{}", base.replacen(MMA_ENABLE, "enable f16;\nenable wgpu_cooperative_matrix;", 1), shader_source("conv3x3_mma_coop"))
}

/// Workgroup memory of conv3x3_mma.wgsl's entry points: the input window, sized for the larger
/// of 6 x 66 pixels x 16 f16 channels ([`Method::Mma`], 64-pixel rows) and twice 6 x 34 x 16
/// ([`Method::MmaSplit`]: 32-pixel rows, the remainders beside the window), and one 16 x 16 f32
/// tile per subgroup (4). More than WebGPU's default limit (16 KiB), so a device opened with
/// default limits cannot run Mma tiles ([`crate::Gpu`] asks for the adapter's).
pub const MMA_WORKGROUP_BYTES: u32 = 2 * 6 * 34 * 16 * 2 + 4 * 256 * 4;
#[allow(clippy::assertions_on_constants)]
const _: () = assert!(6 * 66 * 16 <= 2 * 6 * 34 * 16, "the plain tiles' window fits the split tiles'");

/// Window texels (4 channels) each of the 128 invocations of a split Mma workgroup holds with
/// [`Method::MmaSplitPrefetch`] (the members of conv3x3_mma.wgsl's `Prefetch`): the window of 6 rows x
/// ([`MMA_SPLIT_PIXELS`] + 2) pixels x 4 texels, shared out and rounded up.
pub const MMA_PREFETCH_TEXELS: u32 = (6 * (MMA_SPLIT_PIXELS + 2) * 4).div_ceil(128);

/// Pixels a row of a [`Method::Mma`] workgroup covers (conv3x3_mma.wgsl's MT = 4 tiles of 16).
pub const MMA_PIXELS: u32 = 64;

/// Pixels a row of a [`Method::MmaSplit`] workgroup covers (MT = 2): half of [`MMA_PIXELS`], so
/// that the window's remainders fit beside it in [`MMA_WORKGROUP_BYTES`].
pub const MMA_SPLIT_PIXELS: u32 = 32;

/// Whether a device runs [`Method::Mma`] in matrix units: it has wgpu's cooperative matrices
/// ([`crate::Gpu`] enables them only where [`crate::gpu::has_matrix_units`]: 16 x 16 x 16
/// f16 -> f32 and 32-lane subgroups; a device opened elsewhere with the feature must have the
/// same) and SHADER_F16. Elsewhere, with SHADER_F16, Mma tiles run `mma_emulated`.
pub fn matrix_units_supported(device: &wgpu::Device) -> bool {
    device.features().contains(wgpu::Features::EXPERIMENTAL_COOPERATIVE_MATRIX | wgpu::Features::SHADER_F16 | wgpu::Features::SUBGROUP)
}

/// Texture format of activations at f32 (weights-independent tests upload in it).
pub const ACTIVATION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// `src` (the text of `file`) with each pair's first string replaced by its second; each must
/// occur (a rewrite that finds nothing means the shader changed under it).
fn rewrite(mut src: String, file: &str, rewrites: &[(&str, &str)]) -> String {
    for (from, to) in rewrites {
        assert!(src.contains(from), "{file} has {from}");
        src = src.replace(from, to);
    }
    src
}

/// A WGSL module from source text.
fn shader_module(device: &wgpu::Device, label: &str, source: String) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor { label: Some(label), source: wgpu::ShaderSource::Wgsl(source.into()) })
}

/// Source text of a shader from [`SHADERS`].
pub fn shader_source(name: &str) -> &'static str {
    SHADERS.iter().find(|(n, _)| *n == name).map(|(_, s)| *s).expect("shader is in the table")
}

/// A shader's text as a module is made of it: the two conv kernels (`conv3x3`, `conv3x3_mma`)
/// with conv_common.wgsl appended (their shared parameters, bindings, reads and activation),
/// any other as written.
pub fn conv_module_source(name: &str) -> String {
    let src = shader_source(name);
    if ["conv3x3", "conv3x3_mma"].contains(&name) { format!("{src}\n{}", shader_source("conv_common")) } else { src.to_string() }
}

/// Channel blocks (texture layers) needed for `channels`.
pub fn blocks(channels: usize) -> u32 {
    channels.div_ceil(4) as u32
}

/// Uniform block of conv3x3.wgsl: one per (dispatch, reset).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct ConvParams {
    /// Output width.
    pub width: u32,
    /// Output height.
    pub height: u32,
    /// Blocks read from source a.
    pub cin4_a: u32,
    /// Blocks read from source b (0 when absent or when a reset hidden state is skipped).
    pub cin4_b: u32,
    /// Input blocks in the weight layout.
    pub cin4_total: u32,
    /// First output block of the dispatch's first group (workgroup z = 0).
    pub ob0: u32,
    /// Output blocks of the conv (groups past it store nothing).
    pub cout4: u32,
    /// LeakyReLU slope.
    pub slope: f32,
    /// vec4s between the weight chunks of consecutive groups in one binding (workgroup z).
    pub group_stride: u32,
    /// Winograd lanes tiles ([`Method::is_winograd_lanes`]): the weight-texture texel where the
    /// dispatch's first group's chunk starts (0 for the others, which bind their chunk by offset).
    pub weight_texel: u32,
    /// 1 where the conv writes its output max-pooled too (conv3x3.wgsl's `pools`, where its
    /// pipeline has the pooled store: [`ConvVariant::pool`]); 0 else.
    pub pool_out: u32,
    /// Padding to the uniform's 16-byte size.
    pub _pad: u32,
}

/// Uniform block of prep.wgsl: the sizes (the model's layout is [`PrepLayout`], overrides).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct PrepParams {
    /// Frame width.
    pub width: u32,
    /// Frame height.
    pub height: u32,
    /// Padded width.
    pub pwidth: u32,
    /// Padded height.
    pub pheight: u32,
}

/// How a model packs its input (prep.wgsl's override constants): fixed per model, so each
/// [`crate::Denoiser`] builds its own prep pipeline ([`Kernels::prep_pipeline`]) and the kernel
/// knows at compile time which buffer feeds each channel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PrepLayout {
    /// First channel of color, albedo, normal, depth, roughness in the packed input (`None`:
    /// not packed).
    pub offsets: [Option<u32>; 5],
    /// Channel blocks written.
    pub layers: u32,
    /// Color is divided by (albedo + `albedo_eps`).
    pub demodulate: bool,
    /// Color goes through log1p.
    pub log1p: bool,
    /// Demodulation epsilon.
    pub albedo_eps: f32,
}

impl PrepLayout {
    /// The pipeline constants that specialise prep.wgsl to this layout.
    fn constants(&self, store_max: f32) -> Vec<(&'static str, f64)> {
        let names = ["OFF_COLOR", "OFF_ALBEDO", "OFF_NORMAL", "OFF_DEPTH", "OFF_ROUGHNESS"];
        let mut c: Vec<(&'static str, f64)> = names.iter().zip(self.offsets).map(|(&n, o)| (n, o.unwrap_or(u32::MAX) as f64)).collect();
        c.extend([
            ("LAYERS", self.layers as f64),
            ("DEMODULATE", if self.demodulate { 1.0 } else { 0.0 }),
            ("TRANSFER", if self.log1p { 1.0 } else { 0.0 }),
            ("ALBEDO_EPS", self.albedo_eps as f64),
            ("STORE_MAX", store_max as f64),
        ]);
        c
    }
}

/// Uniform block of output.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct OutputParams {
    /// Frame width.
    pub width: u32,
    /// Frame height.
    pub height: u32,
    /// 1: remodulate.
    pub demodulate: u32,
    /// 0: none, 1: log1p.
    pub transfer: u32,
    /// Demodulation epsilon.
    pub albedo_eps: f32,
    /// Padding to 32 bytes.
    pub _pad: [u32; 3],
}

fn uniform_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Uniform, has_dynamic_offset: false, min_binding_size: None },
        count: None,
    }
}

fn dynamic_entry(binding: u32, ty: wgpu::BufferBindingType, size: u64) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: true, min_binding_size: wgpu::BufferSize::new(size) },
        count: None,
    }
}

fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn texture_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2Array,
            multisampled: false,
        },
        count: None,
    }
}

/// The layout entry of a plan's weight texture (rgba32float, 2D), read as the sources are.
fn weight_texture_entry(binding: u32, sources: SourceAccess) -> wgpu::BindGroupLayoutEntry {
    let ty = match sources {
        SourceAccess::Sampled => wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        SourceAccess::Storage => wgpu::BindingType::StorageTexture {
            access: wgpu::StorageTextureAccess::ReadOnly,
            format: wgpu::TextureFormat::Rgba32Float,
            view_dimension: wgpu::TextureViewDimension::D2,
        },
    };
    wgpu::BindGroupLayoutEntry { binding, visibility: wgpu::ShaderStages::COMPUTE, ty, count: None }
}

/// The layout entry of a conv source read as `sources` says.
fn source_entry(binding: u32, sources: SourceAccess, format: wgpu::TextureFormat) -> wgpu::BindGroupLayoutEntry {
    match sources {
        SourceAccess::Sampled => texture_entry(binding),
        SourceAccess::Storage => wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::StorageTexture {
                access: wgpu::StorageTextureAccess::ReadOnly,
                format,
                view_dimension: wgpu::TextureViewDimension::D2Array,
            },
            count: None,
        },
    }
}

fn storage_texture_entry(binding: u32, format: wgpu::TextureFormat) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::StorageTexture {
            access: wgpu::StorageTextureAccess::WriteOnly,
            format,
            view_dimension: wgpu::TextureViewDimension::D2Array,
        },
        count: None,
    }
}

/// Key of a specialised conv pipeline.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ConvVariant {
    /// Read mode of source a.
    pub read_a: Read,
    /// Read mode of source b (Direct when there is none).
    pub read_b: Read,
    /// The conv has a source b (a one-source kernel compiles without its fetches).
    pub source_b: bool,
    /// LeakyReLU or linear.
    pub leaky: bool,
    /// Output blocks per invocation ([`blocks_per_invocation`]).
    pub ob: u32,
    /// Output rows per invocation ([`rows_per_invocation`]).
    pub rows: u32,
    /// Output columns per invocation (1 or 2).
    pub cols: u32,
    /// Workgroup width (the height makes 64).
    pub group_x: u32,
    /// How the kernel computes the tile: its entry point.
    pub method: Method,
    /// Parts of the input blocks (split-K; 1: none).
    pub split: u32,
    /// The pipeline of split-K's second pass (entry point `reduce`) rather than the conv's.
    pub reduce: bool,
    /// How the conv reads its sources (the module and bind-group layout it is made with).
    pub sources: SourceAccess,
    /// The pipeline has the pooled store (conv3x3.wgsl's POOL_OUT): every conv whose tile can
    /// pool its output, whether it does is its parameters' `pool_out` ([`ConvPlan::pools`]).
    ///
    /// So a conv that pools and one that does not share a pipeline. Lavapipe compiles a
    /// pipeline with LLVM at its first dispatch, once per pipeline and static state of the
    /// textures bound (format, array or not, power-of-two sizes; a conv that does not pool binds
    /// its output at the pooled binding for that, [`ConvPlan::bind_group`]): 6 to 7 s for an
    /// F(4x4) one on this project's machine. The sample's first frame into an empty shader cache
    /// compiles 11 conv pipelines instead of 14 (docs/PERF.md, session 24); the pooled store
    /// costs a uniform branch per store where it is not taken.
    pub pool: bool,
    /// Where it reads its weights (the module and bind-group layout it is made with; Mma tiles
    /// read storage weights).
    pub memory: WeightMemory,
    /// It writes its output into the plan's buffer rather than its texture
    /// (conv3x3_wino4.wgsl's OUT_BUFFER), for the frame to copy ([`ConvPlan::staged`]).
    pub staged: bool,
}

impl ConvVariant {
    /// Whether the variant runs in the module with conv3x3_rows.wgsl and conv3x3_wino.wgsl:
    /// `accumulate_rows` (two-column lanes tiles) or `winograd_lanes`.
    fn runs_rows(&self) -> bool {
        (self.method == Method::Lanes && self.cols > 1 && !self.reduce) || self.method.is_winograd_lanes()
    }
}

/// How a conv tile is computed: the entry point of conv3x3.wgsl.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Method {
    /// `main`: the direct sum, each invocation fetching its inputs from the textures.
    #[default]
    Direct,
    /// `winograd`: Winograd F(2x2, 3x3), 16 multiplies per 2x2 outputs and channel pair for 36.
    Winograd,
    /// `lanes`: the direct sum with each weight vec4 loaded by one lane of the subgroup and
    /// broadcast to the others (one or two columns, the two-column step in conv3x3_rows.wgsl;
    /// subgroups of at least 8 lanes, [`lanes_supported`]). On lavapipe a weight load is
    /// otherwise a lane-by-lane gather.
    Lanes,
    /// `winograd_lanes` (conv3x3_wino.wgsl): [`Method::Winograd`] with each weight vec4 loaded
    /// by one lane of the subgroup, from the plan's weight texture, and broadcast to the others
    /// (subgroups of at least 8 lanes, [`winograd_lanes_supported`]), for CPU drivers.
    WinogradLanes,
    /// `winograd4_lanes` (conv3x3_wino4.wgsl): Winograd F(4x4, 3x3), 36 multiplies per 4x4
    /// outputs and channel pair for 144, with its weights loaded across the subgroup as
    /// [`Method::WinogradLanes`] loads them (subgroups of at least 8 lanes), for CPU drivers.
    Winograd4Lanes,
    /// conv3x3_mma.wgsl: an implicit matrix product in 16 x 16 x 16 tiles of f16 products
    /// summed in f32, in the device's matrix units (tensor cores, [`matrix_units_supported`])
    /// or emulated where it has none ([`Tile::mma`]).
    Mma,
    /// conv3x3_mma.wgsl's split entry points: [`Method::Mma`] with each operand carried as two
    /// f16 halves and three products per pair, f32-class results ([`Tile::mma_split`]).
    MmaSplit,
    /// [`Method::MmaSplit`] with the next chunk's input window read into registers while the
    /// current chunk's products run (conv3x3_mma.wgsl's PREFETCH, [`Tile::mma_split_prefetch`]).
    MmaSplitPrefetch,
}

impl Method {
    /// Weights per input-output channel pair: 9 taps, or 16 transformed ones for Winograd
    /// F(2x2, 3x3) and 36 for F(4x4, 3x3).
    pub fn taps(self) -> u32 {
        match self {
            Method::Direct | Method::Lanes | Method::Mma | Method::MmaSplit | Method::MmaSplitPrefetch => 9,
            Method::Winograd | Method::WinogradLanes => 16,
            Method::Winograd4Lanes => 36,
        }
    }

    /// The entry point in conv3x3.wgsl (conv3x3_mma.wgsl's `mma` and `mma_split` for the Mma
    /// methods, or `mma_emulated` and `mma_split_emulated` on devices without matrix units).
    pub fn entry_point(self) -> &'static str {
        match self {
            Method::Direct => "main",
            Method::Winograd => "winograd",
            Method::Lanes => "lanes",
            Method::WinogradLanes => "winograd_lanes",
            Method::Winograd4Lanes => "winograd4_lanes",
            Method::Mma => "mma",
            Method::MmaSplit | Method::MmaSplitPrefetch => "mma_split",
        }
    }

    /// Whether this is Winograd ([`Method::Winograd`], [`Method::WinogradLanes`],
    /// [`Method::Winograd4Lanes`]): transformed weights per channel pair ([`Method::taps`]),
    /// tiles of a fixed width (2 or 4 columns), no split.
    pub fn is_winograd(self) -> bool {
        matches!(self, Method::Winograd | Method::WinogradLanes | Method::Winograd4Lanes)
    }

    /// Whether this is Winograd with its weights across the subgroup ([`Method::WinogradLanes`],
    /// [`Method::Winograd4Lanes`]): subgroups of at least 8 lanes, weights from the plan's
    /// weight texture (binding 7, whatever the weight memory), the output pooled in the conv
    /// where the plan asks.
    pub fn is_winograd_lanes(self) -> bool {
        matches!(self, Method::WinogradLanes | Method::Winograd4Lanes)
    }

    /// Whether this is one of conv3x3_mma.wgsl's methods ([`Method::Mma`] and the split ones).
    pub fn is_mma(self) -> bool {
        matches!(self, Method::Mma | Method::MmaSplit | Method::MmaSplitPrefetch)
    }

    /// Whether this is one of conv3x3_mma.wgsl's split methods ([`Method::MmaSplit`],
    /// [`Method::MmaSplitPrefetch`]).
    pub fn is_mma_split(self) -> bool {
        matches!(self, Method::MmaSplit | Method::MmaSplitPrefetch)
    }
}

/// Conv `i`'s entry of a plan's choices: one entry for every conv, or one per conv.
pub(crate) fn per_conv<T: Copy>(choices: &[T], i: usize) -> T {
    choices[if choices.len() == 1 { 0 } else { i }]
}

/// Every pair of source access and weight memory a conv can have, in [`conv_slot`] order.
const CONV_SLOTS: [(SourceAccess, WeightMemory); 4] = [
    (SourceAccess::Sampled, WeightMemory::Uniform),
    (SourceAccess::Sampled, WeightMemory::Storage),
    (SourceAccess::Storage, WeightMemory::Uniform),
    (SourceAccess::Storage, WeightMemory::Storage),
];

/// Where a conv's layouts and modules are kept in [`Kernels`].
fn conv_slot(access: SourceAccess, memory: WeightMemory) -> usize {
    access as usize * 2 + memory as usize
}

/// The conv modules of one [`SourceAccess`] and [`WeightMemory`], each made when a pipeline
/// first needs it.
#[derive(Default)]
struct ConvModules {
    /// conv3x3.wgsl as rewritten for the precision, memory, device and access.
    main: Option<wgpu::ShaderModule>,
    /// The conv module with conv3x3_rows.wgsl (two-column lanes tiles, [`ROWS_STUB`]), for
    /// convs of one source.
    rows: Option<wgpu::ShaderModule>,
    /// The same for convs of two sources: its F(4x4) step in a loop per source
    /// ([`TWO_SOURCE_LOOPS`]).
    rows_b: Option<wgpu::ShaderModule>,
    /// conv3x3_mma.wgsl ([`mma_source`]) as rewritten for the precision and access.
    mma: Option<wgpu::ShaderModule>,
}

/// Shader modules, layouts and pipelines of one device; conv pipelines are cached by variant.
///
/// A conv reads its sources and its weights as its variant says ([`ConvVariant::sources`],
/// [`ConvVariant::memory`]), so one `Kernels` serves plans that mix sampled and storage-texture
/// sources (tuning picks per conv, [`crate::Denoiser`]) and uniform and storage weights (by
/// level on CPU drivers, [`WeightMemory::for_conv`]) conv by conv; each pair of the two has
/// its own bind-group layout, and its modules are made only when a pipeline of that pair is.
pub struct Kernels {
    /// Layout of prep.wgsl's group 0.
    pub prep_layout: wgpu::BindGroupLayout,
    /// Layout of output.wgsl's group 0.
    pub output_layout: wgpu::BindGroupLayout,
    /// Layout of pool.wgsl's group 0.
    pub pool_layout: wgpu::BindGroupLayout,
    /// The 2x2 max-pool pipeline (a pass per encoder block, [`crate::graph::Pool`], where the
    /// block's last conv does not pool its own output, [`ConvPlan::pools`]).
    pub pool: wgpu::ComputePipeline,
    /// prep.wgsl, specialised per model by [`Kernels::prep_pipeline`].
    prep_module: wgpu::ShaderModule,
    /// The pipeline layout over [`Kernels::prep_layout`].
    prep_pipeline_layout: wgpu::PipelineLayout,
    /// The output pipeline.
    pub output: wgpu::ComputePipeline,
    /// Layouts of the conv's group 0, at [`conv_slot`] of the source access and weight memory.
    conv_layouts: [wgpu::BindGroupLayout; 4],
    /// Pipeline layouts over [`Kernels::conv_layouts`], likewise.
    conv_pipeline_layouts: [wgpu::PipelineLayout; 4],
    /// The conv modules, likewise.
    modules: [ConvModules; 4],
    /// The device runs Mma tiles in matrix units ([`matrix_units_supported`]).
    matrix_units: bool,
    /// The device has subgroup operations (else [`WITHOUT_SUBGROUPS`] rewrites conv3x3.wgsl).
    subgroups: bool,
    conv: HashMap<ConvVariant, wgpu::ComputePipeline>,
    precision: Precision,
    memory: WeightMemory,
    /// The access of plans that do not choose per conv ([`ConvPlan::new`]).
    sources: SourceAccess,
    /// Plans made from here stage the outputs they can ([`Kernels::stage_outputs`]).
    staging: bool,
    /// The device reads zero outside a texture ([`out_of_bounds_reads_zero`]).
    reads_zero: bool,
    /// The conv pipelines read their zero padding from outside the textures
    /// ([`Kernels::pad_from_bounds`]).
    oob_zero: bool,
    /// The lanes module stores staged outputs in 64-bit words ([`wide_staged_stores`], unless
    /// [`Kernels::stage_in_32_bit_words`]).
    wide_stores: bool,
    /// The Winograd lanes kernels gather for 8-lane subgroups ([`narrow_gathers`], or
    /// [`Kernels::gather_in_8_lanes`]).
    gathers8: bool,
    /// The two-column lanes tiles read their weights from the plan's weight texture
    /// ([`TEXEL_WEIGHTS`], unless [`Kernels::lanes_weights_in_buffers`]).
    lanes_texels: bool,
}

impl Kernels {
    /// Compile the modules and the fixed pipelines for activations stored in `precision`, conv
    /// weights read from `memory` and conv sources read as suits the device
    /// ([`SourceAccess::for_device_type`]).
    ///
    /// The storage texel format, a binding's address space and a texture's type are the things
    /// WGSL cannot take as override constants, so for f16 the kernels' `rgba32float` storage
    /// declarations are rewritten to `rgba16float`, for storage weights the conv's one uniform
    /// weight declaration ([`UNIFORM_WEIGHTS`]) to [`STORAGE_WEIGHTS`], and for storage-texture
    /// sources the conv's `Source` alias and `load` ([`STORAGE_SOURCES`]); everything else (the
    /// clamp to the f16 range) is an override.
    pub fn new(device: &wgpu::Device, precision: Precision, memory: WeightMemory) -> Self {
        Self::with_sources(device, precision, memory, SourceAccess::for_device_type(device.adapter_info().device_type))
    }

    /// [`Kernels::new`] with the conv's sources read as `sources` says (rewritten by
    /// [`STORAGE_SOURCES`] for storage textures, before the f16 rewrite).
    pub fn with_sources(device: &wgpu::Device, precision: Precision, memory: WeightMemory, sources: SourceAccess) -> Self {
        let layout = |label, entries: &[wgpu::BindGroupLayoutEntry]| {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries })
        };
        let conv_layout = |access: SourceAccess, memory: WeightMemory| {
            layout(
                "conv3x3",
                &[
                    dynamic_entry(0, wgpu::BufferBindingType::Uniform, std::mem::size_of::<ConvParams>() as u64),
                    source_entry(1, access, precision.format()),
                    source_entry(2, access, precision.format()),
                    match memory {
                        WeightMemory::Uniform => dynamic_entry(3, wgpu::BufferBindingType::Uniform, WEIGHT_CHUNK_BYTES),
                        WeightMemory::Storage => dynamic_entry(3, wgpu::BufferBindingType::Storage { read_only: true }, 16),
                    },
                    storage_texture_entry(4, precision.format()),
                    storage_entry(5, false),
                    storage_texture_entry(6, precision.format()),
                    weight_texture_entry(7, access),
                ],
            )
        };
        let prep_layout = layout(
            "prep",
            &[
                uniform_entry(0),
                storage_entry(1, true),
                storage_entry(2, true),
                storage_entry(3, true),
                storage_entry(4, true),
                storage_entry(5, true),
                storage_texture_entry(6, precision.format()),
                storage_entry(7, false),
            ],
        );
        let output_layout = layout(
            "output",
            &[uniform_entry(0), texture_entry(1), storage_entry(2, true), storage_entry(3, false), storage_entry(4, true)],
        );
        let pipeline_layout = |bgl: &wgpu::BindGroupLayout| {
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: None,
                bind_group_layouts: &[Some(bgl)],
                immediate_size: 0,
            })
        };
        // prep, output and pool: f16 storage is their only rewrite (and prep's without subgroups).
        let subgroups = device.features().contains(wgpu::Features::SUBGROUP);
        let module = |name: &str| {
            let mut src = conv_module_source(name);
            if name == "prep" && !subgroups {
                src = rewrite(src, "prep.wgsl", &PREP_WITHOUT_SUBGROUPS);
            }
            shader_module(device, name, if precision == Precision::F16 { src.replace("rgba32float", "rgba16float") } else { src })
        };
        let pipeline = |label, layout: &wgpu::PipelineLayout, module: &wgpu::ShaderModule, constants: &[(&str, f64)]| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(label),
                layout: Some(layout),
                module,
                entry_point: Some("main"),
                compilation_options: wgpu::PipelineCompilationOptions { constants, zero_initialize_workgroup_memory: false },
                cache: None,
            })
        };
        let output = pipeline("output", &pipeline_layout(&output_layout), &module("output"), &[]);
        let pool_layout = layout("pool", &[texture_entry(0), storage_texture_entry(1, precision.format())]);
        let pool = pipeline("pool", &pipeline_layout(&pool_layout), &module("pool"), &[]);
        let conv_layouts = CONV_SLOTS.map(|(access, memory)| conv_layout(access, memory));
        Self {
            conv_pipeline_layouts: std::array::from_fn(|i| pipeline_layout(&conv_layouts[i])),
            conv_layouts,
            modules: Default::default(),
            matrix_units: matrix_units_supported(device),
            subgroups,
            prep_pipeline_layout: pipeline_layout(&prep_layout),
            prep_module: module("prep"),
            prep_layout,
            output_layout,
            pool_layout,
            pool,
            output,
            conv: HashMap::new(),
            precision,
            memory,
            sources,
            staging: false,
            reads_zero: out_of_bounds_reads_zero(device),
            oob_zero: false,
            wide_stores: wide_staged_stores(device),
            gathers8: narrow_gathers(device),
            lanes_texels: true,
        }
    }

    /// Gather the Winograd lanes kernels' weights in loads of 8 lanes (conv3x3_gather8.wgsl) even
    /// where the subgroups have 16 or more: for holding the two to each other on one device
    /// (tests/engine/kernels.rs). Call it before any conv pipeline is made.
    pub fn gather_in_8_lanes(&mut self) {
        assert!(self.conv.is_empty(), "gather_in_8_lanes after conv pipelines were made");
        self.gathers8 = true;
    }

    /// Have the two-column lanes tiles read their weights from the weight buffer (uniform chunks
    /// or storage, as the plan's weight memory says) rather than the weight texture: for
    /// comparing the two (`cargo run --release -p rae-core --example lanes_weights_cost`). Call
    /// it before any conv pipeline is made.
    pub fn lanes_weights_in_buffers(&mut self) {
        assert!(self.conv.is_empty(), "lanes_weights_in_buffers after conv pipelines were made");
        self.lanes_texels = false;
    }

    /// Whether the two-column lanes tiles of plans made from here read their weights from the
    /// weight texture ([`TEXEL_WEIGHTS`]).
    pub fn lanes_weights_in_texels(&self) -> bool {
        self.lanes_texels
    }

    /// Store staged outputs in 32-bit words even where [`wide_staged_stores`] holds: for
    /// comparing the two (`cargo run --release -p rae-core --example staged_cost`). Call it
    /// before any conv pipeline is made.
    pub fn stage_in_32_bit_words(&mut self) {
        assert!(self.conv.is_empty(), "stage_in_32_bit_words after conv pipelines were made");
        self.wide_stores = false;
    }

    /// Have the conv pipelines read their zero padding from outside the source textures,
    /// without testing each pixel, where the device reads zero there
    /// ([`out_of_bounds_reads_zero`], conv_common.wgsl's OOB_ZERO): one load per fetch instead
    /// of a branch around it (lavapipe: the L0 convs in 0.93-0.98x the time, about 3% of the
    /// 256x256 frame, and the direct16x4 pipeline compiles in 0.4x; docs/PERF.md, session 28).
    ///
    /// Only for plans whose sources have exactly the sizes their read modes imply: a pooled
    /// source twice the level's, an upsampled one half, a pooled-and-upsampled one the level's,
    /// each level even where a mode halves or doubles it, as the [`crate::Denoiser`]'s padded
    /// levels are. Then every pixel outside the level reads texels outside its source; at odd
    /// sizes an upsampled read at the right edge would land inside. Call it before any conv
    /// pipeline is made (they are made once per variant).
    pub fn pad_from_bounds(&mut self) {
        assert!(self.conv.is_empty(), "pad_from_bounds after conv pipelines were made");
        self.oob_zero = self.reads_zero;
    }

    /// Have the plans made from here on stage the outputs of their F(4x4) convs where a copy
    /// can take them: the conv writes its output into the plan's buffer and the frame copies it
    /// into the texture (on a CPU driver, with f32 activations, at levels a multiple of 16
    /// wide, up to [`STAGING_BYTES`]; [`ConvPlan::staged`]).
    ///
    /// Lavapipe stores an rgba32float texel with four loops over the subgroup's lanes, one per
    /// 32-bit word, each spilling the vectors it picks a lane from; a vec4 store into a buffer is
    /// one such loop, and `copy_buffer_to_texture` is a memcpy on the queue thread (0.04-0.10x
    /// the texel stores it replaces; docs/PERF.md, sessions 25 and 28). Only a caller that
    /// records the copies may ask for it ([`crate::Denoiser`]): [`ConvPlan::record`] alone leaves
    /// a staged conv's texture unwritten.
    pub fn stage_outputs(&mut self) {
        self.staging = self.precision == Precision::F32;
    }

    /// A conv kernel's text (`src`, from `file`) with the rewrites both conv modules take: the
    /// source access ([`STORAGE_SOURCES`]) and f16 storage.
    fn conv_kernel_text(&self, file: &str, src: String, access: SourceAccess) -> String {
        let src = if access == SourceAccess::Storage { rewrite(src, file, &STORAGE_SOURCES) } else { src };
        if self.precision == Precision::F16 { src.replace("rgba32float", "rgba16float") } else { src }
    }

    /// conv3x3.wgsl as this device, precision, weight memory and source access run it (the
    /// rewrites of [`Kernels::new`]).
    fn conv_text(&self, access: SourceAccess, memory: WeightMemory) -> String {
        let mut src = self.conv_kernel_text("conv3x3.wgsl", conv_module_source("conv3x3"), access);
        if !self.subgroups {
            src = rewrite(src, "conv3x3.wgsl", &WITHOUT_SUBGROUPS);
        }
        if memory == WeightMemory::Storage {
            src = rewrite(src, "conv3x3.wgsl", &[(UNIFORM_WEIGHTS, STORAGE_WEIGHTS)]);
        }
        src
    }

    /// conv3x3_mma.wgsl as this device, precision and source access run it.
    fn mma_text(&self, access: SourceAccess) -> String {
        self.conv_kernel_text("conv3x3_mma.wgsl", mma_source(self.matrix_units), access)
    }

    /// The input-preparation pipeline for a model whose input is packed as `layout` says
    /// (prep.wgsl specialised by override constants; one per [`crate::Denoiser`]).
    pub fn prep_pipeline(&self, device: &wgpu::Device, layout: &PrepLayout) -> wgpu::ComputePipeline {
        let constants = layout.constants(self.precision.store_max());
        device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("prep"),
            layout: Some(&self.prep_pipeline_layout),
            module: &self.prep_module,
            entry_point: Some("main"),
            compilation_options: wgpu::PipelineCompilationOptions { constants: &constants, zero_initialize_workgroup_memory: false },
            cache: None,
        })
    }

    /// Layout of the conv's group 0 for sources read as `access` says and weights in `memory`.
    pub fn conv_layout(&self, access: SourceAccess, memory: WeightMemory) -> &wgpu::BindGroupLayout {
        &self.conv_layouts[conv_slot(access, memory)]
    }

    /// How many conv pipelines are made (one per variant; [`Kernels::prepare`]).
    pub fn conv_pipelines(&self) -> usize {
        self.conv.len()
    }

    /// Where the convs of a plan that does not choose per conv read their weights.
    pub fn weight_memory(&self) -> WeightMemory {
        self.memory
    }

    /// How the convs of a plan that does not choose per conv read their sources.
    pub fn source_access(&self) -> SourceAccess {
        self.sources
    }

    /// Whether Mma tiles run in the device's matrix units (else emulated).
    pub fn matrix_units(&self) -> bool {
        self.matrix_units
    }

    /// The conv pipeline for a variant, created on first use.
    pub fn conv(&mut self, device: &wgpu::Device, v: ConvVariant) -> wgpu::ComputePipeline {
        self.prepare(device, &[v]);
        self.conv[&v].clone()
    }

    /// Create the pipelines of `variants` that are not cached yet, on one thread per core.
    ///
    /// A pipeline's creation is mostly the driver's front end (lavapipe translates and
    /// optimises the SPIR-V before its shader cache is consulted; that is most of a denoiser's
    /// build, docs/PERF.md session 10), and Vulkan lets pipelines of one device be created
    /// concurrently, so a plan's variants are made side by side rather than in turn.
    pub fn prepare(&mut self, device: &wgpu::Device, variants: &[ConvVariant]) {
        let mut missing: Vec<ConvVariant> = Vec::new();
        for v in variants {
            if !self.conv.contains_key(v) && !missing.contains(v) {
                missing.push(*v);
            }
        }
        if missing.is_empty() {
            return;
        }
        // The modules the missing variants run, per source access and weight memory:
        // conv3x3.wgsl, the module with conv3x3_rows.wgsl for two-column lanes tiles
        // ([`ROWS_STUB`]), conv3x3_mma.wgsl (storage weights only).
        for (access, memory) in CONV_SLOTS {
            let of_slot = || missing.iter().filter(|v| v.sources == access && v.memory == memory);
            let m = &self.modules[conv_slot(access, memory)];
            let (need_main, need_rows, need_rows_b, need_mma) = (
                m.main.is_none() && of_slot().any(|v| !v.method.is_mma() && !v.runs_rows()),
                m.rows.is_none() && of_slot().any(|v| v.runs_rows() && !v.source_b),
                m.rows_b.is_none() && of_slot().any(|v| v.runs_rows() && v.source_b),
                m.mma.is_none() && of_slot().any(|v| v.method.is_mma()),
            );
            let text = if need_main || need_rows || need_rows_b { self.conv_text(access, memory) } else { String::new() };
            let mma = need_mma.then(|| shader_module(device, "conv3x3_mma", self.mma_text(access)));
            let lanes = |two_sources: bool| {
                let label = if two_sources { "conv3x3 (lanes tiles, two sources)" } else { "conv3x3 (lanes tiles)" };
                shader_module(
                    device,
                    label,
                    lanes_module_source(
                        &text,
                        access,
                        LanesModule {
                            wide_stores: self.wide_stores,
                            two_sources,
                            gathers8: self.gathers8,
                            texel_weights: self.lanes_texels,
                        },
                    ),
                )
            };
            let rows = need_rows.then(|| lanes(false));
            let rows_b = need_rows_b.then(|| lanes(true));
            let main = need_main.then(|| shader_module(device, "conv3x3", text));
            let m = &mut self.modules[conv_slot(access, memory)];
            m.main = m.main.take().or(main);
            m.rows = m.rows.take().or(rows);
            m.rows_b = m.rows_b.take().or(rows_b);
            m.mma = m.mma.take().or(mma);
        }
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get()).min(missing.len());
        let this = &*self;
        let made: Vec<(ConvVariant, wgpu::ComputePipeline)> = if threads <= 1 {
            missing.iter().map(|&v| (v, this.create_conv(device, v))).collect()
        } else {
            // Thread t makes variants t, t + threads, ...; the results are gathered in order.
            std::thread::scope(|scope| {
                let workers: Vec<_> = (0..threads)
                    .map(|t| {
                        let missing = &missing;
                        scope.spawn(move || {
                            missing.iter().skip(t).step_by(threads).map(|&v| (v, this.create_conv(device, v))).collect::<Vec<_>>()
                        })
                    })
                    .collect();
                workers.into_iter().flat_map(|w| w.join().expect("a pipeline-creating thread panicked")).collect()
            })
        };
        self.conv.extend(made);
    }

    /// Create one conv pipeline (its module made by [`Kernels::prepare`]).
    fn create_conv(&self, device: &wgpu::Device, v: ConvVariant) -> wgpu::ComputePipeline {
        let modules = &self.modules[conv_slot(v.sources, v.memory)];
        // conv_common.wgsl's overrides, then the kernel's own.
        let mut constants = vec![
            ("MODE_A", v.read_a as u32 as f64),
            ("MODE_B", v.read_b as u32 as f64),
            ("SOURCE_B", if v.source_b { 1.0 } else { 0.0 }),
            ("LEAKY", if v.leaky { 1.0 } else { 0.0 }),
            ("STORE_MAX", self.precision.store_max() as f64),
            // The Mma tiles (GPUs; emulated elsewhere) keep their tests.
            ("OOB_ZERO", (self.oob_zero && !v.method.is_mma()) as u32 as f64),
        ];
        let (label, module, entry) = if v.method.is_mma() {
            // Split tiles split the activations too where they are f32 (f16 ones are exact).
            let split = v.method.is_mma_split();
            let pixels = if split { MMA_SPLIT_PIXELS } else { MMA_PIXELS };
            let prefetch = v.method == Method::MmaSplitPrefetch;
            constants.extend([
                ("NT", v.ob as f64),
                ("MT", (pixels / 16) as f64),
                ("SPLIT", split as u32 as f64),
                ("SPLIT_A", (split && self.precision == Precision::F32) as u32 as f64),
                ("PREFETCH", prefetch as u32 as f64),
            ]);
            let entry = match (self.matrix_units, split) {
                (true, _) => v.method.entry_point(),
                (false, false) => "mma_emulated",
                (false, true) => "mma_split_emulated",
            };
            ("conv3x3_mma", modules.mma.as_ref().expect("made by prepare"), entry)
        } else {
            constants.extend([
                ("OB", v.ob as f64),
                ("ROWS", v.rows as f64),
                ("TW", v.cols as f64),
                ("WG_X", v.group_x as f64),
                ("WG_Y", (64 / v.group_x) as f64),
                ("SPLIT", v.split as f64),
                ("LANES", if v.method == Method::Lanes { 1.0 } else { 0.0 }),
                ("POOL_OUT", v.pool as u32 as f64),
            ]);
            if v.runs_rows() {
                constants.push(("WEIGHT_TEXELS_WIDTH", WEIGHT_TEXELS_WIDTH as f64));
                constants.push(("OUT_BUFFER", v.staged as u32 as f64));
            }
            let module = match (v.runs_rows(), v.source_b) {
                (true, false) => modules.rows.as_ref(),
                (true, true) => modules.rows_b.as_ref(),
                _ => modules.main.as_ref(),
            }
            .expect("made by prepare");
            ("conv3x3", module, if v.reduce { "reduce" } else { v.method.entry_point() })
        };
        device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(label),
            layout: Some(&self.conv_pipeline_layouts[conv_slot(v.sources, v.memory)]),
            module,
            entry_point: Some(entry),
            compilation_options: wgpu::PipelineCompilationOptions { constants: &constants, zero_initialize_workgroup_memory: false },
            cache: None,
        })
    }
}

/// The most rows of a two-column lanes tile: conv3x3_rows.wgsl has no more (16 rows in two
/// columns ran 1.36-1.41x the time of 8 on lavapipe, and every row it has costs build time).
pub const LANES_W2_MAX_ROWS: u32 = 8;

/// The conv kernel's register tile: at most `rows` output rows x `blocks` output blocks (4
/// channels each) x `cols` adjacent columns per invocation, computed directly or by Winograd's
/// F(2x2, 3x3). Levels lower than `rows` and convs with fewer output blocks (or too many input
/// blocks for `blocks` in one weight chunk) get a smaller tile.
///
/// Taller tiles share each weight load among more outputs; wider ones share each input fetch
/// (a 2-column tile fetches 4 input columns for 2 outputs, a 1-column tile 3 for 1). A Winograd
/// tile (2 columns, 2 or 4 rows) multiplies 16 times per 2x2 outputs and input channel where the
/// direct one multiplies 36 times, for 16 weights per channel pair instead of 9 and a few
/// additions. CPU drivers run [`Tile::cpu`] (8 x 2 in two columns, weights loaded across the
/// subgroup), where every input fetch is a call into the driver and the two columns share it
/// (docs/PERF.md); GPUs tune per conv ([`crate::TileChoice`]) and fall back to the default
/// (16 x 2) where they cannot time candidates; `rae-cli bench --tile` sweeps any of them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Tile {
    /// Output rows per invocation: 1, 2, 4, 8 or 16 ([`CONV_ROWS`]).
    pub rows: u32,
    /// Output blocks per invocation: 1, 2, or 4 with one column.
    pub blocks: u32,
    /// Output columns per invocation: 1 or 2.
    pub cols: u32,
    /// Workgroup width in invocations (8, 16, 32 or 64; the height makes 64 invocations).
    pub group_x: u32,
    /// How the tile is computed ([`Tile::winograd`]).
    pub method: Method,
    /// Parts the input blocks are split into (split-K, direct tiles only; 1: none): each part
    /// sums its share into a partial buffer and a second pass adds them ([`Tile::with_split`]).
    pub split: u32,
}

impl Default for Tile {
    fn default() -> Self {
        Tile { rows: CONV_ROWS, blocks: 2, cols: 1, group_x: WORKGROUP, method: Method::Direct, split: 1 }
    }
}

impl Tile {
    /// The tile of CPU drivers without subgroups: 16 rows x 4 blocks (2 or 1 where a conv's
    /// weights or outputs are fewer), 0.83-0.93x the time of 16 x 2 on lavapipe (docs/PERF.md,
    /// session 6); [`Tile::cpu`] picks [`Tile::CPU_LANES`] instead where the device has subgroups.
    pub const CPU: Tile = Tile { rows: CONV_ROWS, blocks: 4, cols: 1, group_x: WORKGROUP, method: Method::Direct, split: 1 };

    /// The tile of CPU drivers with subgroups: 8 rows x 2 blocks x 2 columns, weights loaded
    /// across the subgroup. On lavapipe at 512-bit vectors it took 0.78x the frame time of
    /// `lanes16x4` (the default before it; 0.84-0.86x at 256 bits) and 0.93x that of `lanes4x2w2`,
    /// with the same warm build time; compiling into an empty shader cache takes longer (the
    /// first 64x64 frame in 38 s, against 27 for `lanes16x4` and 14 for `lanes4x2w2`), once
    /// per machine and driver (docs/PERF.md, session 11).
    pub const CPU_LANES: Tile = Tile { rows: 8, blocks: 2, cols: 2, group_x: WORKGROUP, method: Method::Lanes, split: 1 };

    /// The CPU drivers' Winograd tile: F(2x2, 3x3) in two stacked 2x2 output tiles (4 rows x
    /// 2 columns) x 4 blocks, weights loaded across the subgroup ([`Method::WinogradLanes`]).
    /// It takes 256 multiply-adds per 4 outputs and input block where [`Tile::CPU_LANES`] takes
    /// 576. On lavapipe (Zen 5, 512-bit vectors) the 256x256 frame's big convs of 32 input
    /// channels and more took about 0.8x the time of `lanes8x2w2` in four stacked tiles
    /// (docs/PERF.md, session 22). Two stacked tiles were faster still on the 16 x 16 and 8 x 8
    /// levels: on the Zen 3 of session 31 (8 lanes) its bottleneck took half the time of
    /// `lanes4x2w2`'s and its 16 x 16 convs less than `winolanes8x4`'s; on the Zen 4 of session
    /// 32 (16 lanes) tuning kept it or `lanes4x2w2` on every 16 x 16 conv, never `winolanes8x4`,
    /// and it compiles in 0.4x the time. Its weights are texels of the plan's weight texture
    /// (since session 23: a 64 KiB uniform chunk held four blocks of 16 weights per channel pair
    /// only up to 15 input blocks). The rounding is Winograd's: within the golden tolerance.
    pub const CPU_WINOGRAD: Tile = Tile { rows: 4, blocks: 4, cols: 2, group_x: WORKGROUP, method: Method::WinogradLanes, split: 1 };

    /// [`Tile::CPU_WINOGRAD`] in four stacked 2x2 output tiles (8 rows): the CPU drivers' tile
    /// on 16 x 16 levels from session 22 to 31, a [`TileChoice::Tuned`] candidate since.
    ///
    /// [`TileChoice::Tuned`]: crate::TileChoice::Tuned
    pub const CPU_WINOGRAD_TALL: Tile = Tile { rows: 8, ..Tile::CPU_WINOGRAD };

    /// The CPU drivers' F(4x4, 3x3) tile: one 4x4 output tile (4 rows x 4 columns) x 4 blocks,
    /// weights loaded across the subgroup from the plan's weight texture
    /// ([`Method::Winograd4Lanes`]). It takes 144 multiply-adds per 16 outputs and input block
    /// where [`Tile::CPU_WINOGRAD`] takes 256. On lavapipe (Zen 5, 512-bit vectors) the 256x256
    /// frame's convs on levels of 32 x 32 and more took 0.6-0.9x the time of the F(2x2) tile's
    /// and `lanes8x2w2`'s; on 16 x 16 levels, where a subgroup covers half its pixels, 1.3-1.7x
    /// (docs/PERF.md, session 23). Against two stacked 4x4 tiles ([`Tile::CPU_WINOGRAD4_TALL`],
    /// the tile until session 31), one tile on every conv and frames alternating in one
    /// process, it took 0.91x the 128x128 frame time, 0.965-0.999x the 256x256 one, 0.93x the
    /// 512x512 one and 0.98-1.02x the 1280x720 one on the Zen 4 of session 32 at 16 lanes; at
    /// 8 lanes (the Zen 3 of session 31) tuning never kept the tall one. It compiles in about
    /// half the time: 5.7 s a pipeline into an empty shader cache against 11.8 at 16 lanes,
    /// 13 s against 30 at 8 (`compile_cost`). Its rounding is within the golden tolerance.
    pub const CPU_WINOGRAD4: Tile = Tile { rows: 4, blocks: 4, cols: 4, group_x: WORKGROUP, method: Method::Winograd4Lanes, split: 1 };

    /// [`Tile::CPU_WINOGRAD4`] in two stacked 4x4 output tiles (8 rows): the CPU drivers' tile on
    /// levels of 32 x 32 and more from session 23 to 31, a [`TileChoice::Tuned`] candidate since.
    ///
    /// [`TileChoice::Tuned`]: crate::TileChoice::Tuned
    pub const CPU_WINOGRAD4_TALL: Tile = Tile { rows: 8, ..Tile::CPU_WINOGRAD4 };

    /// The tile of CPU drivers on `device`: [`Tile::CPU_LANES`] where the device has subgroups
    /// of 8 or more lanes ([`lanes_supported`]), else [`Tile::CPU`].
    pub fn cpu(device: &wgpu::Device) -> Tile {
        if lanes_supported(device) { Tile::CPU_LANES } else { Tile::CPU }
    }

    /// The tile of CPU drivers for a conv reading `in_blocks` input blocks on a `width` x
    /// `height` level: [`Tile::cpu`]; where that is [`Tile::CPU_LANES`] and the device runs the
    /// Winograd lanes tiles ([`winograd_lanes_supported`]), [`Tile::CPU_WINOGRAD4`] on levels of
    /// at least [`CPU_WINOGRAD4_MIN_PIXELS`] and [`Tile::CPU_WINOGRAD`] below them for convs of
    /// at least [`CPU_WINOGRAD_MIN_BLOCKS`]: down to 1 x 1 where subgroups have 8 lanes
    /// ([`narrow_gathers`]), above [`CPU_SHORT_TILE_MAX_PIXELS`] where they have 16. The rest
    /// take [`Tile::CPU_LANES`], in 4 rows instead of 8 on levels of at most
    /// [`CPU_SHORT_TILE_MAX_PIXELS`].
    ///
    /// An 8 x 8 level is 4 invocations of 8 rows x 2 columns per output group, so 4 of a
    /// subgroup's 16 lanes have pixels, and the others still load weights for them. At 4 rows
    /// twice as many lanes work: the 256x256 frame's bottleneck convs (8 x 8, storage weights)
    /// took 0.72x the time (docs/PERF.md, session 21). At 16 lanes tuning kept `lanes4x2w2`
    /// there over [`Tile::CPU_WINOGRAD`] (by 4-18%, session 32); at 8 lanes the Winograd tile
    /// took half its time (session 31).
    pub fn cpu_for(device: &wgpu::Device, width: u32, height: u32, in_blocks: u32) -> Tile {
        let tile = Tile::cpu(device);
        let (winograd, narrow) = (winograd_lanes_supported(device), narrow_gathers(device));
        let pixels = width * height;
        if tile != Tile::CPU_LANES {
            tile
        } else if winograd && pixels >= CPU_WINOGRAD4_MIN_PIXELS {
            Tile::CPU_WINOGRAD4
        } else if winograd && in_blocks >= CPU_WINOGRAD_MIN_BLOCKS && (narrow || pixels > CPU_SHORT_TILE_MAX_PIXELS) {
            Tile::CPU_WINOGRAD
        } else if pixels <= CPU_SHORT_TILE_MAX_PIXELS {
            Tile { rows: 4, ..tile }
        } else {
            tile
        }
    }

    /// A one-column tile, if the kernel has one of this shape.
    pub fn new(rows: u32, blocks: u32) -> Option<Self> {
        Self::with_cols(rows, blocks, 1)
    }

    /// A tile, if the kernel has one of this shape.
    pub fn with_cols(rows: u32, blocks: u32, cols: u32) -> Option<Self> {
        // Four blocks take the accumulators a second column would use.
        ([1, 2, 4, 8, 16].contains(&rows) && ((1..=2).contains(&blocks) || (blocks == 4 && cols == 1)) && (1..=2).contains(&cols))
            .then_some(Tile { rows, blocks, cols, group_x: WORKGROUP, method: Method::Direct, split: 1 })
    }

    /// A Winograd F(2x2, 3x3) tile of `rows` (2: one 2x2 output tile, 4: two stacked) x
    /// `blocks` (1 or 2), if the kernel has it.
    pub fn winograd(rows: u32, blocks: u32) -> Option<Self> {
        ([2, 4].contains(&rows) && (1..=2).contains(&blocks)).then_some(Tile {
            rows,
            blocks,
            cols: 2,
            group_x: WORKGROUP,
            method: Method::Winograd,
            split: 1,
        })
    }

    /// A Winograd F(2x2, 3x3) tile with its weights loaded across the subgroup
    /// ([`Method::WinogradLanes`]): `rows` (4: two stacked 2x2 output tiles, 8: four) x `blocks`
    /// (1, 2 or 4), if the kernel has it.
    pub fn winograd_lanes(rows: u32, blocks: u32) -> Option<Self> {
        ([4, 8].contains(&rows) && [1, 2, 4].contains(&blocks)).then_some(Tile {
            rows,
            blocks,
            cols: 2,
            group_x: WORKGROUP,
            method: Method::WinogradLanes,
            split: 1,
        })
    }

    /// A Winograd F(4x4, 3x3) tile with its weights loaded across the subgroup
    /// ([`Method::Winograd4Lanes`]): `rows` (4: one 4x4 output tile, 8: two stacked) x 4 columns
    /// x `blocks` (1, 2 or 4), if the kernel has it.
    pub fn winograd4_lanes(rows: u32, blocks: u32) -> Option<Self> {
        ([4, 8].contains(&rows) && [1, 2, 4].contains(&blocks)).then_some(Tile {
            rows,
            blocks,
            cols: 4,
            group_x: WORKGROUP,
            method: Method::Winograd4Lanes,
            split: 1,
        })
    }

    /// This direct tile with its weights loaded across the subgroup ([`Method::Lanes`]), if it
    /// is direct.
    pub fn with_lanes(self) -> Option<Self> {
        Tile::lanes(self.rows, self.blocks, self.cols).filter(|_| self.method == Method::Direct).map(|t| Tile {
            group_x: self.group_x,
            split: self.split,
            ..t
        })
    }

    /// A tile with its weights loaded across the subgroup ([`Method::Lanes`]): `rows` x `blocks`
    /// x `cols`, where lanes tiles also take 4 blocks in 2 columns (and two columns at most
    /// [`LANES_W2_MAX_ROWS`] rows), if the kernel has it.
    pub fn lanes(rows: u32, blocks: u32, cols: u32) -> Option<Self> {
        let rows_ok = [1, 2, 4, 8, 16].contains(&rows) && (cols == 1 || rows <= LANES_W2_MAX_ROWS);
        (rows_ok && [1, 2, 4].contains(&blocks) && (1..=2).contains(&cols)).then_some(Tile {
            rows,
            blocks,
            cols,
            group_x: WORKGROUP,
            method: Method::Lanes,
            split: 1,
        })
    }

    /// A matrix-unit tile ([`Method::Mma`]): workgroups of 4 rows x 64 pixels x `channels`
    /// output channels (16, 32, 48 or 64), if the kernel has it. Inputs and weights are rounded
    /// to f16 for the products (inputs clamped to +-65504), which are summed in f32: with f16
    /// activations that adds the weights' rounding to the storage's; with f32 activations it is
    /// a TF32-like mode (10-bit mantissas in), not f32 arithmetic. Needs storage weights
    /// ([`WeightMemory::Storage`]) and SHADER_F16; runs in matrix units where the device has
    /// them ([`matrix_units_supported`]), else emulated (correct, slow: for tests).
    pub fn mma(channels: u32) -> Option<Self> {
        [16, 32, 48, 64].contains(&channels).then_some(Tile {
            rows: 4,
            blocks: channels / 4,
            cols: 1,
            group_x: WORKGROUP,
            method: Method::Mma,
            split: 1,
        })
    }

    /// A split matrix-unit tile ([`Method::MmaSplit`]): workgroups of 4 rows x 32 pixels
    /// ([`MMA_SPLIT_PIXELS`]) x `channels` output channels (16, 32, 48 or 64), if the kernel has
    /// it. Each operand x goes in as hi and its remainder scaled by 2^11, lo = f16(2^11 (x -
    /// hi)) (hi = f16(x) for the weights, x cut to f16's 10 mantissa bits for the activations),
    /// and a product as hi(a) hi(b) + (hi(a) lo(b) + lo(a) hi(b)) / 2^11: 21- to 22-bit
    /// operands, so f32 activations get f32-class results (held to the golden tolerance) for
    /// three times the matrix products, and f16 activations (exact in f16) two. Inputs are
    /// clamped to +-65504 as for [`Tile::mma`] (the default model's activations stay under 26,
    /// docs/STABILITY.md). Needs what [`Tile::mma`] needs.
    pub fn mma_split(channels: u32) -> Option<Self> {
        Some(Tile { method: Method::MmaSplit, ..Tile::mma(channels)? })
    }

    /// [`Tile::mma_split`] with each chunk's input window read into registers during the
    /// previous chunk's products ([`Method::MmaSplitPrefetch`]): the same results, bit for bit,
    /// for 7 more vec4 registers an invocation ([`MMA_PREFETCH_TEXELS`]). Written in session 18
    /// without a GPU to time it, so it is not among [`crate::denoiser::MMA_SPLIT_TILES`] until
    /// a GPU session has held it to the goldens and timed it (docs/PERF.md).
    pub fn mma_split_prefetch(channels: u32) -> Option<Self> {
        Some(Tile { method: Method::MmaSplitPrefetch, ..Tile::mma(channels)? })
    }

    /// Weights per input-output channel pair ([`Method::taps`]).
    pub fn taps(&self) -> u32 {
        self.method.taps()
    }

    /// This tile in workgroups `group_x` invocations wide (8, 16, 32 or 64), if the kernel has it.
    pub fn with_group(self, group_x: u32) -> Option<Self> {
        [8, 16, 32, 64].contains(&group_x).then_some(Tile { group_x, ..self })
    }

    /// This direct tile with its input blocks split `split` ways (1 to 16; 1: no split), if it
    /// is direct.
    pub fn with_split(self, split: u32) -> Option<Self> {
        (!self.method.is_winograd() && (1..=16).contains(&split)).then_some(Tile { split, ..self })
    }

    /// Workgroup height in invocations.
    pub fn group_y(&self) -> u32 {
        64 / self.group_x
    }
}

impl std::fmt::Display for Tile {
    /// `ROWSxBLOCKS`, with `wCOLS` appended for a 2-column tile (`8x1w2`) and `gGROUPX` for a
    /// workgroup other than 8 x 8 and `kSPLIT` for a split tile (`8x1g32k4`); Winograd tiles are
    /// `wino` and `ROWSxBLOCKS` (`wino4x1g32`); Mma tiles are `mma` and their output channels
    /// (`mma32`), with `x3` for the split ones' three products (`mma32x3`) and `x3p` for those
    /// that prefetch their windows (`mma32x3p`).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.method {
            Method::Mma => return write!(f, "mma{}", 4 * self.blocks),
            Method::MmaSplit => return write!(f, "mma{}x3", 4 * self.blocks),
            Method::MmaSplitPrefetch => return write!(f, "mma{}x3p", 4 * self.blocks),
            Method::Direct => {}
            Method::Winograd => write!(f, "wino")?,
            Method::Lanes => write!(f, "lanes")?,
            Method::WinogradLanes => write!(f, "winolanes")?,
            Method::Winograd4Lanes => write!(f, "wino4lanes")?,
        }
        write!(f, "{}x{}", self.rows, self.blocks)?;
        if self.cols > 1 && !self.method.is_winograd() {
            write!(f, "w{}", self.cols)?;
        }
        if self.group_x != WORKGROUP {
            write!(f, "g{}", self.group_x)?;
        }
        if self.split > 1 {
            write!(f, "k{}", self.split)?;
        }
        Ok(())
    }
}

/// Output rows per invocation for a conv `height` pixels high with at most `max_rows`
/// (a power of two up to [`CONV_ROWS`]): the smallest of 2, 4, 8 that covers a lower level
/// whole, so levels a few pixels high (the deepest ones of small frames) do not compute 16 rows
/// to keep 2, else `max_rows`.
pub fn rows_per_invocation(height: u32, max_rows: u32) -> u32 {
    [2, 4, 8].into_iter().find(|&r| height <= r).unwrap_or(CONV_ROWS).min(max_rows)
}

/// Output blocks per invocation for a conv reading `cin4` input blocks with `taps` weights
/// per channel pair (9, or 16 for Winograd): the most of 4, 2, 1 whose weights and biases fit
/// one weight chunk (more outputs per input fetch; direct tiles get 4 up to 28 input blocks);
/// `None` when not even one block fits (direct: more than 113 input blocks, 452 channels;
/// Winograd: more than 63, 252 channels).
pub fn blocks_per_invocation(cin4: u32, taps: u32) -> Option<u32> {
    [4, 2, 1].into_iter().find(|&ob| (cin4 * taps * 4 + 1) * ob <= WEIGHT_CHUNK)
}

/// Winograd F(2x2, 3x3)'s weight transform G g G^T of one 3x3 kernel (row-major, `[ky][kx]`),
/// in f64 and rounded once: the 16 weights conv3x3.wgsl's `winograd` multiplies with.
pub fn winograd_taps(g: &[f32]) -> [f32; 16] {
    const G: [[f64; 3]; 4] = [[1.0, 0.0, 0.0], [0.5, 0.5, 0.5], [0.5, -0.5, 0.5], [0.0, 0.0, 1.0]];
    weight_transform(&G, g)
}

/// G g G^T of one 3x3 kernel `g` for the N x 3 matrix `m` = G, in f64 and rounded once,
/// row-major (position p = N i + j).
fn weight_transform<const N: usize, const NN: usize>(m: &[[f64; 3]; N], g: &[f32]) -> [f32; NN] {
    debug_assert_eq!(N * N, NN);
    std::array::from_fn(|p| {
        let (i, j) = (p / N, p % N);
        let mut u = 0.0;
        for a in 0..3 {
            for b in 0..3 {
                u += m[i][a] * g[a * 3 + b] as f64 * m[j][b];
            }
        }
        u as f32
    })
}

/// Winograd F(4x4, 3x3)'s weight transform G g G^T of one 3x3 kernel (row-major, `[ky][kx]`),
/// in f64 and rounded once: the 36 weights conv3x3_wino4.wgsl's `winograd4_lanes` multiplies
/// with, for its B and A (points 0, 1, -1, 2, -2 and infinity).
pub fn winograd4_taps(g: &[f32]) -> [f32; 36] {
    const G: [[f64; 3]; 6] = [
        [1.0 / 4.0, 0.0, 0.0],
        [-1.0 / 6.0, -1.0 / 6.0, -1.0 / 6.0],
        [-1.0 / 6.0, 1.0 / 6.0, -1.0 / 6.0],
        [1.0 / 24.0, 1.0 / 12.0, 1.0 / 6.0],
        [1.0 / 24.0, -1.0 / 12.0, 1.0 / 6.0],
        [0.0, 0.0, 1.0],
    ];
    weight_transform(&G, g)
}

/// The weight chunk of output blocks `ob0 .. ob0 + ob` of a conv over `cat(a, b)`, laid out as
/// conv3x3.wgsl reads it: taps `[in block][ky*3+kx][in lane][j]` -> vec4 over block `ob0 + j`'s
/// 4 output channels, then `ob` bias vec4s. With [`Method::Winograd`] the 9 taps of each pair
/// are the 16 of [`winograd_taps`] (`[in block][position][in lane][j]`), with
/// [`Method::Winograd4Lanes`] the 36 of [`winograd4_taps`].
///
/// Input blocks follow the sources: source a's channels padded to a multiple of 4, then source
/// b's, so the kernel reads each source's texture layers without a concat. Padding weights are
/// zero, so padding channels (always written as zero) and padding outputs contribute nothing.
pub fn pack_group(spec: &ConvSpec, ob0: usize, ob: usize, method: Method) -> Vec<[f32; 4]> {
    let (weight, bias, cout, ca, cb) = (spec.weight, spec.bias, spec.cout, spec.ca, spec.cb);
    let cin = ca + cb;
    debug_assert_eq!(weight.len(), cout * cin * 9);
    let (ba, bb) = (blocks(ca) as usize, blocks(cb) as usize);
    let channel = |ib: usize, lane: usize| input_channel(spec, ib, lane);
    let taps = method.taps() as usize;
    // The weights of one channel pair as the kernel multiplies them.
    let pair = |o: usize, i: usize| -> [f32; 36] {
        let g = &weight[(o * cin + i) * 9..][..9];
        match method {
            Method::Winograd4Lanes => winograd4_taps(g),
            Method::Winograd | Method::WinogradLanes => {
                let u = winograd_taps(g);
                std::array::from_fn(|t| u.get(t).copied().unwrap_or(0.0))
            }
            _ => std::array::from_fn(|t| g.get(t).copied().unwrap_or(0.0)),
        }
    };
    let mut out = Vec::with_capacity((ba + bb) * taps * 4 * ob + ob);
    for ib in 0..ba + bb {
        // [lane][j][l] -> the pair's weights, zero for padding.
        let pairs: Vec<[[f32; 36]; 4]> = (0..4 * ob)
            .map(|k| {
                let (lane, j) = (k / ob, k % ob);
                std::array::from_fn(|l| {
                    let o = 4 * (ob0 + j) + l;
                    match channel(ib, lane) {
                        Some(i) if o < cout => pair(o, i),
                        _ => [0.0; 36],
                    }
                })
            })
            .collect();
        for tap in 0..taps {
            out.extend(pairs.iter().map(|p| std::array::from_fn(|l| p[l][tap])));
        }
    }
    for j in 0..ob {
        out.push(std::array::from_fn(|l| bias.get(4 * (ob0 + j) + l).copied().unwrap_or(0.0)));
    }
    out
}

/// The input channel of `cat(a, b)` at lane `lane` of input block `ib` (source a's channels
/// padded to a multiple of 4, then source b's), or `None` for a padding lane.
fn input_channel(spec: &ConvSpec, ib: usize, lane: usize) -> Option<usize> {
    let ba = blocks(spec.ca) as usize;
    if ib < ba {
        let c = 4 * ib + lane;
        (c < spec.ca).then_some(c)
    } else {
        let c = 4 * (ib - ba) + lane;
        (c < spec.cb).then_some(spec.ca + c)
    }
}

/// f16 values of one Mma group's weights ([`Method::Mma`]): output channels `n0 .. n0 + 16 *
/// nt` of a conv over `cat(a, b)`, laid out as conv3x3_mma.wgsl reads them. For chunk c (input
/// blocks 4c .. 4c + 3, in [`pack_group`]'s block order) and tap t = ky * 3 + kx, `nt` tiles of
/// 16 x 16 `[k][n]` (input channel of block 4c + k / 4, lane k % 4; output channel
/// n0 + 16 tile + n); with `split` ([`Method::MmaSplit`]) all those tiles again as the
/// weights' scaled remainders f16((w - f16(w)) * 2^11); then the bias as hi = f16(b) for the
/// 16 * nt channels and lo = f16(b - hi) for them. Padding is zero.
pub fn pack_mma(spec: &ConvSpec, n0: usize, nt: usize, split: bool) -> Vec<half::f16> {
    let (weight, cout, cin) = (spec.weight, spec.cout, spec.ca + spec.cb);
    debug_assert_eq!(weight.len(), cout * cin * 9);
    let chunks = (blocks(spec.ca) + blocks(spec.cb)).div_ceil(4) as usize;
    // The tiles' weights in f32, in the kernel's order.
    let mut tiles: Vec<f32> = Vec::with_capacity(chunks * 9 * nt * 256);
    for c in 0..chunks {
        // The input channel of each row k of this chunk's tiles.
        let rows: Vec<Option<usize>> = (0..16).map(|k| input_channel(spec, 4 * c + k / 4, k % 4)).collect();
        for t in 0..9 {
            for tile in 0..nt {
                for i in &rows {
                    for n in 0..16 {
                        let o = n0 + 16 * tile + n;
                        tiles.push(match *i {
                            Some(i) if o < cout => weight[(o * cin + i) * 9 + t],
                            _ => 0.0,
                        });
                    }
                }
            }
        }
    }
    let mut out: Vec<half::f16> = Vec::with_capacity(tiles.len() * (1 + split as usize) + 32 * nt);
    out.extend(tiles.iter().map(|&w| half::f16::from_f32(w)));
    if split {
        // Each weight's remainder below its f16, scaled by 2^11 (conv3x3_mma.wgsl's LO_SCALE)
        // so that it stays a normal f16 where an unscaled one would be subnormal.
        out.extend(tiles.iter().map(|&w| half::f16::from_f32((w - half::f16::from_f32(w).to_f32()) * MMA_LO_SCALE)));
    }
    let bias: Vec<f32> = (0..16 * nt).map(|n| spec.bias.get(n0 + n).copied().unwrap_or(0.0)).collect();
    let hi: Vec<half::f16> = bias.iter().map(|&b| half::f16::from_f32(b)).collect();
    out.extend(&hi);
    out.extend(bias.iter().zip(&hi).map(|(&b, h)| half::f16::from_f32(b - h.to_f32())));
    out
}

/// Scale of a split operand's remainder ([`Method::MmaSplit`], conv3x3_mma.wgsl's LO_SCALE):
/// 2^11, one f16 mantissa.
pub const MMA_LO_SCALE: f32 = 2048.0;

/// Full-resolution f32 texture layers split-K's partial sums may take ([`ConvPlan::new`]).
pub const PARTIAL_LAYERS: u64 = 4;

/// The most bytes one staged conv output may take ([`Kernels::stage_outputs`]): 32 channels
/// of 512 x 512 in f32, so that a 1080p frame stages its small levels only rather than hold
/// a 267 MB buffer for its first.
pub const STAGING_BYTES: u64 = 32 << 20;

/// One convolution to plan: its size, sources, weights and kernel variant.
#[derive(Debug, Clone, Copy)]
pub struct ConvSpec<'a> {
    /// Module name, for errors and labels.
    pub name: &'a str,
    /// Output width (the convolution's resolution).
    pub width: u32,
    /// Output height.
    pub height: u32,
    /// Channels of source a (and how it is read).
    pub ca: usize,
    /// Channels of source b (0: none).
    pub cb: usize,
    /// Output channels.
    pub cout: usize,
    /// PyTorch layout `[cout][ca + cb][3][3]`.
    pub weight: &'a [f32],
    /// `[cout]`.
    pub bias: &'a [f32],
    /// Read modes of a and b.
    pub read_a: Read,
    /// Read mode of b (Direct when absent).
    pub read_b: Read,
    /// LeakyReLU after the conv.
    pub leaky: bool,
    /// LeakyReLU slope.
    pub slope: f32,
    /// Source b is a recurrent hidden state: a reset frame reads none of its channels.
    pub b_is_hidden: bool,
    /// The output is read max-pooled 2x2 (an encoder block's last conv, [`crate::graph::Pool`]):
    /// the conv writes the pooled value itself where its tile allows ([`ConvPlan::pools`]).
    pub pooled: bool,
}

/// One dispatch: `count` consecutive output-block groups (workgroup z), their parameter and
/// weight offsets.
#[derive(Debug, Clone, Copy)]
struct Group {
    /// Offsets into the parameter buffer: normal frame, reset frame.
    params: [u32; 2],
    /// Offset into the weight buffer.
    weights: u32,
    /// Groups in this dispatch (their chunks follow each other, `group_stride` apart).
    count: u32,
}

/// Append a dispatch's two parameter blocks (normal frame, then reset frame, whose recurrent
/// conv reads no hidden-state blocks), each at an `align`-byte offset; returns the offsets.
fn push_params(params: &mut Vec<u8>, align: usize, s: &ConvSpec, ob0: u32, group_stride: u32, weight_texel: u32, pool: bool) -> [u32; 2] {
    let (cin4_a, cin4_b) = (blocks(s.ca), blocks(s.cb));
    std::array::from_fn(|reset| {
        let p = ConvParams {
            width: s.width,
            height: s.height,
            cin4_a,
            cin4_b: if reset == 1 && s.b_is_hidden { 0 } else { cin4_b },
            cin4_total: cin4_a + cin4_b,
            ob0,
            cout4: blocks(s.cout),
            slope: s.slope,
            group_stride,
            weight_texel,
            pool_out: pool as u32,
            _pad: 0,
        };
        params.resize(params.len().next_multiple_of(align), 0);
        let at = params.len() as u32;
        params.extend_from_slice(bytemuck::bytes_of(&p));
        at
    })
}

/// A planned convolution: its pipeline, workgroups and groups, and split-K's second pass.
struct Planned {
    pipeline: wgpu::ComputePipeline,
    /// How the conv reads its sources (its bind groups' layout).
    sources: SourceAccess,
    /// Where it reads its weights (its bind groups' layout and binding size).
    memory: WeightMemory,
    /// It writes its output max-pooled too ([`ConvPlan::pools`]).
    pool: bool,
    /// Its output's size (width, height, layers) where it writes it into the buffer to copy.
    staged: Option<[u32; 3]>,
    workgroups: (u32, u32),
    /// Parts per group (workgroup z runs over groups x parts).
    split: u32,
    groups: Vec<Group>,
    /// The reduce pipeline and its workgroups, when split.
    reduce: Option<(wgpu::ComputePipeline, [u32; 3])>,
}

/// Every convolution of a network, ready to dispatch: one uniform buffer of parameter blocks
/// and one buffer of weights (each dispatch's groups at an aligned offset, bound by dynamic
/// offset), and the pipeline and dispatches of each conv. Built once per [`crate::Denoiser`].
pub struct ConvPlan {
    params: wgpu::Buffer,
    weights: wgpu::Buffer,
    /// Split-K's partial sums, or the staged outputs ([`Kernels::stage_outputs`]; 16 bytes
    /// when no conv needs it). Each split or staged conv overwrites it in turn.
    partial: wgpu::Buffer,
    /// Binding 7: the weights of Winograd lanes convs ([`Method::is_winograd_lanes`]),
    /// [`WEIGHT_TEXELS_WIDTH`] texels a row (1 x 1 where the plan has none).
    weight_texels: wgpu::TextureView,
    /// Bytes of the weight texture.
    weight_texels_bytes: u64,
    /// Bytes of a weight binding, `[WeightMemory as usize]`: one chunk for uniform weights, the
    /// largest storage-weight conv for storage ones.
    weight_binding: [u64; 2],
    convs: Vec<Planned>,
    tiles: Vec<Tile>,
    sources: Vec<SourceAccess>,
    memories: Vec<WeightMemory>,
}

impl ConvPlan {
    /// Pack and upload every conv's weights and parameters, conv `i` with at most `tiles[i]`
    /// (one tile for all when `tiles` has one entry; a split is capped so that the partial sums
    /// fit [`PARTIAL_LAYERS`] layers at the largest conv's resolution); fails when a conv is too
    /// wide for one uniform weight chunk. Every conv reads its sources as `kernels` does by
    /// default ([`Kernels::source_access`]).
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        kernels: &mut Kernels,
        specs: &[ConvSpec],
        tiles: &[Tile],
    ) -> crate::Result<Self> {
        let sources = kernels.sources;
        Self::with_sources(device, queue, kernels, specs, tiles, &[sources])
    }

    /// [`ConvPlan::new`] with conv `i` reading its sources as `sources[i]` says (one entry: all
    /// alike), as tuning picks them where both kinds run ([`crate::Denoiser`]).
    pub fn with_sources(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        kernels: &mut Kernels,
        specs: &[ConvSpec],
        tiles: &[Tile],
        sources: &[SourceAccess],
    ) -> crate::Result<Self> {
        let memory = kernels.memory;
        Self::with_choices(device, queue, kernels, specs, tiles, sources, &[memory])
    }

    /// [`ConvPlan::with_sources`] with conv `i` reading its weights from `memories[i]` (one
    /// entry: all alike), as [`WeightMemory::for_conv`] picks them by level on CPU drivers.
    pub fn with_choices(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        kernels: &mut Kernels,
        specs: &[ConvSpec],
        tiles: &[Tile],
        sources: &[SourceAccess],
        memories: &[WeightMemory],
    ) -> crate::Result<Self> {
        use wgpu::util::DeviceExt;
        assert!(tiles.len() == 1 || tiles.len() == specs.len(), "one tile, or one per conv");
        assert!(sources.len() == 1 || sources.len() == specs.len(), "one source access, or one per conv");
        assert!(memories.len() == 1 || memories.len() == specs.len(), "one weight memory, or one per conv");
        // Tiles with weights across the lanes, on a device whose subgroups are too narrow.
        let narrow = |t: &&Tile| match t.method {
            Method::Lanes => (!lanes_supported(device)).then_some(("weights across lanes", 8)),
            Method::WinogradLanes | Method::Winograd4Lanes => {
                (!winograd_lanes_supported(device)).then_some(("Winograd weights across lanes", 8))
            }
            _ => None,
        };
        if let Some((t, (what, lanes))) = tiles.iter().find_map(|t| narrow(&t).map(|n| (t, n))) {
            let info = device.adapter_info();
            let has = if device.features().contains(wgpu::Features::SUBGROUP) {
                format!("{} to {}", info.subgroup_min_size, info.subgroup_max_size)
            } else {
                "none".to_string()
            };
            return Err(crate::Error::UnsupportedTile {
                tile: t.to_string(),
                reason: format!("{what} need subgroups of at least {lanes} lanes; {} has {has}", info.name),
            });
        }
        let limits = device.limits();
        // Parameter blocks are uniform, and weights may be either: every offset suits both.
        let align = limits.min_uniform_buffer_offset_alignment.max(limits.min_storage_buffer_offset_alignment) as usize;
        let mut params: Vec<u8> = Vec::new();
        let mut weights: Vec<u8> = Vec::new();
        // Winograd lanes convs' weights, texel by texel (the weight texture).
        let mut weight_texels: Vec<[f32; 4]> = Vec::new();
        // Each conv's variant, workgroups, split, groups and reduce pass, before its pipelines.
        let mut pending = Vec::with_capacity(specs.len());
        let mut used = Vec::with_capacity(specs.len());
        // The largest storage-weight conv's bytes (its binding's size).
        let mut binding = 0u64;
        let mut partial = 0u64;
        // Split-K's partial sums may take as much memory as 16 channels at full resolution in f32
        // (4 texture layers): enough to split the deep levels, where splitting pays, while a
        // split full-resolution conv (gigabytes at 1080p) is split less or not at all.
        let partial_budget = specs.iter().map(|s| s.width as u64 * s.height as u64).max().unwrap_or(0) * 16 * PARTIAL_LAYERS;
        for (i, s) in specs.iter().enumerate() {
            let (tile, access, memory) = (per_conv(tiles, i), per_conv(sources, i), per_conv(memories, i));
            let (cin4_a, cin4_b) = (blocks(s.ca), blocks(s.cb));
            let cin4 = cin4_a + cin4_b;
            if tile.method.is_mma() {
                let unsupported = |reason: String| crate::Error::UnsupportedTile { tile: tile.to_string(), reason };
                if memory != WeightMemory::Storage {
                    return Err(unsupported("Mma tiles read their weights from a storage buffer (weights memory `storage`)".into()));
                }
                if !device.features().contains(wgpu::Features::SHADER_F16) {
                    return Err(unsupported(format!("Mma tiles need SHADER_F16, which {} lacks", device.adapter_info().name)));
                }
                let split = tile.method.is_mma_split();
                let shared = device.limits().max_compute_workgroup_storage_size;
                if shared < MMA_WORKGROUP_BYTES {
                    return Err(unsupported(format!(
                        "{tile} uses {MMA_WORKGROUP_BYTES} bytes of workgroup memory; the device allows {shared}"
                    )));
                }
                // Tiles of 16 output channels, at most as many per group as the conv has.
                let tiles16 = s.cout.div_ceil(16) as u32;
                let nt = (tile.blocks / 4).clamp(1, tiles16);
                // The hi tiles, with `split` their remainders, then the bias's two halves.
                let stride = cin4.div_ceil(4) * 9 * nt * 256 * (1 + split as u32) + 32 * nt;
                let group_count = tiles16.div_ceil(nt);
                binding = binding.max(group_count as u64 * stride as u64 * 2);
                let mut group = Group { params: [0; 2], weights: 0, count: group_count };
                group.params = push_params(&mut params, align, s, 0, stride, 0, false);
                weights.resize(weights.len().next_multiple_of(align), 0);
                group.weights = weights.len() as u32;
                for g in 0..group_count {
                    let packed = pack_mma(s, (16 * nt * g) as usize, nt as usize, split);
                    debug_assert_eq!(packed.len() as u32, stride);
                    weights.extend_from_slice(bytemuck::cast_slice(&packed));
                }
                let variant = ConvVariant {
                    read_a: s.read_a,
                    read_b: s.read_b,
                    source_b: s.cb > 0,
                    leaky: s.leaky,
                    ob: nt,
                    rows: 1,
                    cols: 1,
                    group_x: WORKGROUP,
                    method: tile.method,
                    split: 1,
                    reduce: false,
                    sources: access,
                    pool: false,
                    memory,
                    staged: false,
                };
                // Workgroups of 4 rows (conv3x3_mma.wgsl's ROWS) x 64 or 32 pixels (16 MT).
                let pixels = if split { MMA_SPLIT_PIXELS } else { MMA_PIXELS };
                pending.push((variant, false, (s.width.div_ceil(pixels), s.height.div_ceil(4)), 1, vec![group], None, None));
                used.push(Tile { blocks: 4 * nt, ..tile });
                continue;
            }
            let taps = tile.taps();
            // Two columns only where the level is wider than one (Winograd tiles are 2 wide).
            let cols = if s.width > 1 || tile.method.is_winograd() { tile.cols } else { 1 };
            // The tiles of the lanes module read their weights from the weight texture
            // (TEXEL_WEIGHTS), which takes no chunk.
            let texels = tile.method.is_winograd_lanes() || (tile.method == Method::Lanes && cols > 1 && kernels.lanes_texels);
            // Their pipelines then all take one weight memory, which they do not read: a conv
            // on a level of uniform weights shares the pipeline of its kind on a level of
            // storage ones (each an LLVM compile of seconds on lavapipe).
            let memory = if texels { WeightMemory::Storage } else { memory };
            let ob = match memory {
                _ if texels => 4,
                WeightMemory::Uniform => blocks_per_invocation(cin4, taps).ok_or_else(|| crate::Error::Arch {
                    origin: s.name.to_string(),
                    reason: format!(
                        "{} input channels ({cin4} blocks of 4, padded per source) exceed one 64 KiB weight chunk (at most {} blocks with {} tiles)",
                        s.ca + s.cb,
                        (WEIGHT_CHUNK - 1) / (taps * 4),
                        if tile.method.is_winograd() { "Winograd" } else { "direct" }
                    ),
                })?,
                WeightMemory::Storage => 4,
            };
            let cout4 = blocks(s.cout);
            // No more blocks than the conv has output blocks to fill: the 3-channel output convs
            // would compute a second, discarded tile with OB = 2 (OB stays 1, 2 or 4).
            let mut ob = ob.min(tile.blocks);
            while ob > 1 && ob / 2 >= cout4 {
                ob /= 2;
            }
            // F(4x4, 3x3) computes whole 4x4 output tiles.
            let rows = rows_per_invocation(s.height, tile.rows).max(if tile.method == Method::Winograd4Lanes { 4 } else { 1 });
            // Split (direct tiles only) no further than one input block per part, nor beyond the
            // partial-sum budget.
            let part_bytes = cout4 as u64 * s.width as u64 * s.height as u64 * 16;
            let split = if !tile.method.is_winograd() { tile.split.min(cin4).min((partial_budget / part_bytes) as u32).max(1) } else { 1 };
            let used_tile = Tile { rows, blocks: ob, cols, group_x: tile.group_x, method: tile.method, split };
            // The conv pools its own output where each invocation holds whole 2x2 windows (its
            // pipeline has the pooled store wherever it can, ConvVariant::pool).
            let can_pool =
                (tile.method == Method::Lanes && cols == 2 && rows.is_multiple_of(2) && split == 1) || tile.method.is_winograd_lanes();
            let pool = s.pooled && can_pool;
            // Staged where asked, the row pitch a copy's (256 bytes), the buffer within bounds.
            let staged = (kernels.staging
                && tile.method == Method::Winograd4Lanes
                && (s.width * 16).is_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
                && part_bytes <= STAGING_BYTES)
                .then_some([s.width, s.height, cout4]);
            if staged.is_some() {
                partial = partial.max(part_bytes);
            }
            let variant = ConvVariant {
                read_a: s.read_a,
                read_b: s.read_b,
                source_b: s.cb > 0,
                leaky: s.leaky,
                ob,
                rows,
                cols,
                group_x: tile.group_x,
                method: tile.method,
                split,
                reduce: false,
                sources: access,
                pool: can_pool,
                memory,
                staged: staged.is_some(),
            };
            // Split-K's partial sums: one buffer for the largest split conv, which every split
            // conv overwrites in turn (the reduce of one runs before the next conv starts).
            if split > 1 {
                partial = partial.max(split as u64 * cout4 as u64 * s.width as u64 * s.height as u64 * 16);
            }
            // Groups of `ob` output blocks, as many per dispatch as fit one chunk (workgroup z).
            let stride = (cin4 * taps * 4 + 1) * ob;
            let group_count = cout4.div_ceil(ob);
            let per_dispatch = match memory {
                _ if texels => group_count,
                WeightMemory::Uniform => (WEIGHT_CHUNK / stride).min(group_count),
                WeightMemory::Storage => group_count,
            };
            if memory == WeightMemory::Storage && !texels {
                binding = binding.max(per_dispatch as u64 * stride as u64 * 16);
            }
            let mut groups = Vec::new();
            for first in (0..group_count).step_by(per_dispatch as usize) {
                let count = per_dispatch.min(group_count - first);
                let mut group = Group { params: [0; 2], weights: 0, count };
                group.params = push_params(&mut params, align, s, first * ob, stride, weight_texels.len() as u32, pool);
                if !texels {
                    weights.resize(weights.len().next_multiple_of(align), 0);
                    group.weights = weights.len() as u32;
                }
                for g in first..first + count {
                    let chunk = pack_group(s, (g * ob) as usize, ob as usize, tile.method);
                    debug_assert_eq!(chunk.len() as u32, stride);
                    if texels {
                        weight_texels.extend_from_slice(&chunk);
                    } else {
                        weights.extend_from_slice(bytemuck::cast_slice(&chunk));
                    }
                }
                groups.push(group);
            }
            // The reduce pipeline depends on the activation and the part count only.
            let reduce_variant = ConvVariant {
                read_a: Read::Direct,
                read_b: Read::Direct,
                source_b: true,
                ob: 1,
                rows: 1,
                cols: 1,
                group_x: WORKGROUP,
                method: Method::Direct,
                reduce: true,
                pool: false,
                staged: false,
                ..variant
            };
            let reduce = (split > 1).then_some((reduce_variant, [s.width.div_ceil(8), s.height.div_ceil(8), cout4]));
            pending.push((
                variant,
                pool,
                (s.width.div_ceil(cols).div_ceil(tile.group_x), s.height.div_ceil(rows).div_ceil(tile.group_y())),
                split,
                groups,
                reduce,
                staged,
            ));
            used.push(used_tile);
        }
        // Every pipeline the plan needs, made side by side, then the convs' dispatches.
        let variants: Vec<ConvVariant> = pending.iter().flat_map(|p| std::iter::once(p.0).chain(p.5.map(|r| r.0))).collect();
        kernels.prepare(device, &variants);
        let convs: Vec<Planned> = pending
            .into_iter()
            .map(|(variant, pool, workgroups, split, groups, reduce, staged)| Planned {
                pipeline: kernels.conv(device, variant),
                sources: variant.sources,
                memory: variant.memory,
                pool,
                staged,
                workgroups,
                split,
                groups,
                reduce: reduce.map(|(v, n)| (kernels.conv(device, v), n)),
            })
            .collect();
        // Every binding spans a whole chunk (or the largest storage conv) past its offset.
        let weight_binding = [WEIGHT_CHUNK_BYTES, binding.next_multiple_of(16).max(16)];
        let end = convs.iter().flat_map(|c| c.groups.iter().map(|g| g.weights as u64 + weight_binding[c.memory as usize])).max();
        weights.resize(end.unwrap_or(0) as usize, 0);
        params.resize(params.len().next_multiple_of(16), 0);
        let init = |label, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
        };
        let weight_usage = convs
            .iter()
            .map(|c| match c.memory {
                WeightMemory::Uniform => wgpu::BufferUsages::UNIFORM,
                WeightMemory::Storage => wgpu::BufferUsages::STORAGE,
            })
            .fold(wgpu::BufferUsages::empty(), |a, b| a | b);
        // The weight texture: rows of WEIGHT_TEXELS_WIDTH texels (1 x 1 when no conv reads it).
        let (tex_w, tex_h) = if weight_texels.is_empty() {
            (1, 1)
        } else {
            (WEIGHT_TEXELS_WIDTH, (weight_texels.len() as u32).div_ceil(WEIGHT_TEXELS_WIDTH))
        };
        if tex_h > device.limits().max_texture_dimension_2d {
            return Err(crate::Error::UnsupportedTile {
                tile: Method::Winograd4Lanes.entry_point().to_string(),
                reason: format!(
                    "its weights need a {tex_w} x {tex_h} texture; the device allows {}",
                    device.limits().max_texture_dimension_2d
                ),
            });
        }
        weight_texels.resize((tex_w * tex_h) as usize, [0.0; 4]);
        let weight_texture = device.create_texture_with_data(
            queue,
            &wgpu::TextureDescriptor {
                label: Some("conv weight texels"),
                size: wgpu::Extent3d { width: tex_w, height: tex_h, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba32Float,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::STORAGE_BINDING,
                view_formats: &[],
            },
            wgpu::util::TextureDataOrder::LayerMajor,
            bytemuck::cast_slice(&weight_texels),
        );
        Ok(Self {
            weight_texels: weight_texture.create_view(&Default::default()),
            weight_texels_bytes: weight_texture.size().width as u64 * weight_texture.size().height as u64 * 16,
            params: init("conv params", &params, wgpu::BufferUsages::UNIFORM),
            weights: init("conv weights", &weights, weight_usage),
            partial: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("conv partial sums"),
                // Never empty: every conv binds it, the 64-bit staged stores as one 32-byte word
                // at least (conv3x3_stage64.wgsl), where the conv does not use it.
                size: partial.max(32),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            weight_binding,
            sources: convs.iter().map(|c| c.sources).collect(),
            memories: convs.iter().map(|c| c.memory).collect(),
            convs,
            tiles: used,
        })
    }

    /// The tile each conv runs with (after the level-height and weight-chunk limits).
    pub fn tiles(&self) -> &[Tile] {
        &self.tiles
    }

    /// How each conv reads its sources.
    pub fn sources(&self) -> &[SourceAccess] {
        &self.sources
    }

    /// Where each conv reads its weights.
    pub fn memories(&self) -> &[WeightMemory] {
        &self.memories
    }

    /// Bytes of the weight, parameter and partial-sum buffers.
    pub fn bytes(&self) -> u64 {
        self.params.size() + self.weights.size() + self.partial.size() + self.weight_texels_bytes
    }

    /// Whether conv `i` writes its output max-pooled 2x2 too (conv3x3.wgsl's `pools`), so that
    /// the pool pass after it is not run: a conv whose [`ConvSpec::pooled`] is set, with a tile
    /// that can pool ([`ConvVariant::pool`]: two-column lanes tiles of an even number of rows,
    /// unsplit, and the Winograd lanes tiles). Its bind group takes the pooled value
    /// ([`ConvPlan::bind_group`]).
    pub fn pools(&self, i: usize) -> bool {
        self.convs[i].pool
    }

    /// Whether conv `i` writes its output into the plan's buffer ([`Kernels::stage_outputs`]):
    /// after [`ConvPlan::record`] the caller ends the pass and records this copy into the texture
    /// bound as the conv's output.
    pub fn staged(&self, i: usize) -> bool {
        self.convs[i].staged.is_some()
    }

    /// Copy conv `i`'s staged output into `dst`, its output texture (nothing where it is not
    /// staged).
    pub fn copy_staged(&self, encoder: &mut wgpu::CommandEncoder, i: usize, dst: &wgpu::Texture) {
        let Some([width, height, layers]) = self.convs[i].staged else { return };
        encoder.copy_buffer_to_texture(
            wgpu::TexelCopyBufferInfo {
                buffer: &self.partial,
                layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(width * 16), rows_per_image: Some(height) },
            },
            dst.as_image_copy(),
            wgpu::Extent3d { width, height, depth_or_array_layers: layers },
        );
    }

    /// Dispatches per frame.
    pub fn dispatches(&self) -> usize {
        self.convs.iter().map(|c| c.groups.len()).sum()
    }

    /// A bind group of conv `i` over the given textures (offsets are supplied per dispatch), in
    /// the layout of its source access and weight memory. `pooled` is the value its output
    /// max-pools into, where it has one; a conv that [pools](ConvPlan::pools) needs it, and one
    /// that does not binds `dst` there instead.
    #[allow(clippy::too_many_arguments)]
    pub fn bind_group(
        &self,
        device: &wgpu::Device,
        kernels: &Kernels,
        i: usize,
        a: &wgpu::TextureView,
        b: &wgpu::TextureView,
        dst: &wgpu::TextureView,
        pooled: Option<&wgpu::TextureView>,
    ) -> wgpu::BindGroup {
        // A conv that does not pool binds its output at binding 6 too (never written there: its
        // `pools` is false), so its pipeline's textures have the static state of a pooling
        // conv's and lavapipe compiles the pipeline once for both ([`ConvVariant::pool`]).
        let pooled = if self.pools(i) {
            pooled.unwrap_or_else(|| panic!("conv {i} pools its output: its bind group needs the pooled value"))
        } else {
            dst
        };
        let buffer =
            |buffer, size| wgpu::BindingResource::Buffer(wgpu::BufferBinding { buffer, offset: 0, size: wgpu::BufferSize::new(size) });
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("conv3x3"),
            layout: kernels.conv_layout(self.convs[i].sources, self.convs[i].memory),
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: buffer(&self.params, std::mem::size_of::<ConvParams>() as u64) },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(a) },
                wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::TextureView(b) },
                wgpu::BindGroupEntry { binding: 3, resource: buffer(&self.weights, self.weight_binding[self.convs[i].memory as usize]) },
                wgpu::BindGroupEntry { binding: 4, resource: wgpu::BindingResource::TextureView(dst) },
                wgpu::BindGroupEntry { binding: 5, resource: self.partial.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 6, resource: wgpu::BindingResource::TextureView(pooled) },
                wgpu::BindGroupEntry { binding: 7, resource: wgpu::BindingResource::TextureView(&self.weight_texels) },
            ],
        })
    }

    /// Record conv `i` (every output-block group) into a pass.
    pub fn record(&self, pass: &mut wgpu::ComputePass, i: usize, reset: bool, group: &wgpu::BindGroup) {
        let c = &self.convs[i];
        pass.set_pipeline(&c.pipeline);
        for g in &c.groups {
            pass.set_bind_group(0, group, &[g.params[reset as usize], g.weights]);
            pass.dispatch_workgroups(c.workgroups.0, c.workgroups.1, g.count * c.split);
        }
        // Split-K: add the parts (the parameters of any group carry the conv's size).
        if let Some((pipeline, [x, y, z])) = &c.reduce {
            pass.set_pipeline(pipeline);
            pass.dispatch_workgroups(*x, *y, *z);
        }
    }

    /// Dispatch conv `i`'s pipelines (and its split-K reduce) with one workgroup each, on a
    /// reset frame's parameters: what makes a driver that compiles at first dispatch compile
    /// them, at no cost in arithmetic ([`crate::Denoiser::compile_backwards`]).
    pub fn record_compile(&self, pass: &mut wgpu::ComputePass, i: usize, group: &wgpu::BindGroup) {
        let c = &self.convs[i];
        pass.set_pipeline(&c.pipeline);
        if let Some(g) = c.groups.first() {
            pass.set_bind_group(0, group, &[g.params[1], g.weights]);
            pass.dispatch_workgroups(1, 1, 1);
        }
        if let Some((pipeline, _)) = &c.reduce {
            pass.set_pipeline(pipeline);
            pass.dispatch_workgroups(1, 1, 1);
        }
    }
}

//! Every WGSL source of rae (one table, [`SHADERS`]) and the text rewrites a module is made
//! with where WGSL has no override for the difference: storage formats, address spaces, texture
//! types, subgroup operations, and the lanes module's appended kernels.

use super::*;

/// Every shader of rae, by name; the only place WGSL enters the crate.
pub const SHADERS: &[(&str, &str)] = &[
    ("conv3x3", include_str!("../../../../shaders/conv3x3.wgsl")),
    ("conv3x3_rows", include_str!("../../../../shaders/conv3x3_rows.wgsl")),
    ("conv3x3_wino", include_str!("../../../../shaders/conv3x3_wino.wgsl")),
    ("conv3x3_wino4", include_str!("../../../../shaders/conv3x3_wino4.wgsl")),
    ("conv3x3_gather16", include_str!("../../../../shaders/conv3x3_gather16.wgsl")),
    ("conv3x3_gather8", include_str!("../../../../shaders/conv3x3_gather8.wgsl")),
    ("conv3x3_stage64", include_str!("../../../../shaders/conv3x3_stage64.wgsl")),
    ("conv3x3_mma", include_str!("../../../../shaders/conv3x3_mma.wgsl")),
    ("conv3x3_mma_coop", include_str!("../../../../shaders/conv3x3_mma_coop.wgsl")),
    ("conv_common", include_str!("../../../../shaders/conv_common.wgsl")),
    ("input_policy", include_str!("../../../../shaders/input_policy.wgsl")),
    ("prep", include_str!("../../../../shaders/prep.wgsl")),
    ("output", include_str!("../../../../shaders/output.wgsl")),
    ("pool", include_str!("../../../../shaders/pool.wgsl")),
    ("motion", include_str!("../../../../shaders/motion.wgsl")),
    ("carve", include_str!("../../../../shaders/carve.wgsl")),
    ("accumulate", include_str!("../../../../shaders/accumulate.wgsl")),
];

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

/// The rewrite of conv3x3_wino4.wgsl for convs of two sources: `wino4_step` takes whether
/// its block is source b's as an argument, a constant at each of its two calls, one loop per
/// source, where the kernel as written runs one loop over both sources' blocks and chooses the
/// window per block.
///
/// Lavapipe runs both sides of an `if` under a mask, so the one loop fetched both windows for
/// every block; two loops fetch one, and LLVM compiles the step's body twice (the 8x4 tile's
/// two-source pipeline in 9.2 s instead of 7.1). The two-source L0 convs took 0.90-0.96x the
/// time (`docs/perf/lavapipe-2026-12-02-s29.log`). Convs of one source keep the kernel as written: their
/// module is another ([`Kernels`] makes one of each).
pub const TWO_SOURCE_LOOPS: [(&str, &str); 3] = [
    (
        "m03: ptr<function, Wino6>, cb: u32, w: u32, x: i32, y0: i32) {",
        "m03: ptr<function, Wino6>, cb: u32, w: u32, x: i32, y0: i32, from_b: bool) {",
    ),
    ("    if !SOURCE_B || cb < params.cin4_a {\n        k = window6(src_a", "    if !from_b {\n        k = window6(src_a"),
    (
        "    for (var c = 0u; c < blocks; c++) {\n        wino4_step(&m00, &m01, &m02, &m03, c, w, xi, yi);\n    }",
        "    for (var c = 0u; c < params.cin4_a; c++) {\n        wino4_step(&m00, &m01, &m02, &m03, c, w, xi, yi, false);\n    }\n    for (var c = params.cin4_a; c < blocks; c++) {\n        wino4_step(&m00, &m01, &m02, &m03, c, w, xi, yi, true);\n    }",
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
    let conv = rewrite(conv.to_string(), "conv3x3.wgsl", &TEXEL_WEIGHTS);
    conv.replace(ROWS_STUB, &format!("{}\n{}\n{}\n{}", shader_source("conv3x3_rows"), shader_source("conv3x3_wino"), gathers, wino4))
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

/// Pixels a row of a [`Method::Mma`] workgroup covers (conv3x3_mma.wgsl's MT = 4 tiles of 16).
pub const MMA_PIXELS: u32 = 64;

/// Pixels a row of a [`Method::MmaSplit`] workgroup covers (MT = 2): half of [`MMA_PIXELS`], so
/// that the window's remainders fit beside it in [`MMA_WORKGROUP_BYTES`].
pub const MMA_SPLIT_PIXELS: u32 = 32;

/// `src` (the text of `file`) with each pair's first string replaced by its second; each must
/// occur (a rewrite that finds nothing means the shader changed under it).
pub(crate) fn rewrite(mut src: String, file: &str, rewrites: &[(&str, &str)]) -> String {
    for (from, to) in rewrites {
        assert!(src.contains(from), "{file} has {from}");
        src = src.replace(from, to);
    }
    src
}

/// Source text of a shader from [`SHADERS`].
pub fn shader_source(name: &str) -> &'static str {
    SHADERS.iter().find(|(n, _)| *n == name).map(|(_, s)| *s).expect("shader is in the table")
}

/// A shader's text as a module is made of it: the two conv kernels (`conv3x3`, `conv3x3_mma`)
/// with conv_common.wgsl appended (their shared parameters, bindings, reads and activation)
/// and carve.wgsl (where a value carved into an arena's cells is), the pool kernel with
/// carve.wgsl, the input and output stages (`prep`, `output`) with input_policy.wgsl appended
/// (the input policy and the miss test they share), any other as written.
pub fn conv_module_source(name: &str) -> String {
    let src = shader_source(name);
    match name {
        "conv3x3" | "conv3x3_mma" => format!("{src}\n{}\n{}", shader_source("conv_common"), shader_source("carve")),
        "pool" => format!("{src}\n{}", shader_source("carve")),
        "prep" | "output" => format!("{src}\n{}", shader_source("input_policy")),
        _ => src.to_string(),
    }
}

/// motion.wgsl's warped-state declaration as f16 activations need it (its motion textures stay
/// rgba32float: a pixel's motion needs f32's precision).
pub const WARP_F16: [(&str, &str); 1] =
    [("var warped: texture_storage_2d_array<rgba32float, write>;", "var warped: texture_storage_2d_array<rgba16float, write>;")];

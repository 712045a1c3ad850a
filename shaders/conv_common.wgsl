// What both conv kernels (conv3x3.wgsl and conv3x3_mma.wgsl) share, appended to each by
// kernels::conv_module_source: the parameter block and the bindings other than the weights,
// the read modes and how a source is read, and the store's activation.

// How a source is read at output pixel (x, y).
const READ_DIRECT: u32 = 0u;        // src[x, y]
const READ_POOL: u32 = 1u;          // max of src[2x + i, 2y + j]          (src at 2x resolution)
const READ_UPSAMPLE: u32 = 2u;      // src[x / 2, y / 2]                   (src at 1/2 resolution)
const READ_POOL_UPSAMPLE: u32 = 3u; // upsample(pool(src)): max of the 2x2 block holding (x, y)
// MODE_A and MODE_B hold the read mode in bits 0-1 and two flags: CARVED, the source is a
// value carved into the cells of an arena below the arena's resolution (carve.wgsl), so its
// fetches test the level's bounds; and FROM_B, the mode is source b's (so `cell` takes
// params.carve_b).
const READ_MODE: u32 = 3u;
const CARVED: u32 = 4u;
const FROM_B: u32 = 8u;

override MODE_A: u32 = 0u;
override MODE_B: u32 = 8u;
override LEAKY: bool = true;
// The conv reads a source b (a concatenation). Half the convs read one source: without the
// second input-block loop their kernels carry half the multiply-add code, which lavapipe
// compiles with LLVM at the first dispatch (the sample's cold first frame 0.84x of the time
// with the loop everywhere; `docs/perf/lavapipe-2026-11-23-s8.log`). The lanes kernels run one loop over
// cat(a, b) and choose only the window's source per block; there SOURCE_B drops that choice
// (one-source convs sharing the two-source pipelines make frames 1.04x as long,
// `docs/perf/lavapipe-2026-11-25-s24.log`).
override SOURCE_B: bool = true;
// Largest magnitude stored: f32::MAX for f32 activations, 65504 for f16 (no infinities).
override STORE_MAX: f32 = 3.4028234e38;

// One per (dispatch, reset): kernels::ConvParams.
struct Params {
    width: u32,       // output (= convolution) resolution
    height: u32,
    cin4_a: u32,      // channel blocks read from a
    cin4_b: u32,      // channel blocks read from b (0: no b, or a zeroed hidden state)
    cin4_total: u32,  // input blocks in the weight layout (a + b)
    ob0: u32,         // first output block (texture layer) of the group at z = 0
    cout4: u32,       // output blocks of the conv
    slope: f32,       // LeakyReLU negative slope
    group_stride: u32,// vec4s from one group's weights to the next (group z at z * group_stride)
    weight_texel: u32,// winograd_lanes, winograd4_lanes: the weight texel of group z = 0 (conv3x3_wino4.wgsl)
    pool_out: u32,    // 1: the conv writes its output max-pooled too (conv3x3.wgsl's `pools`)
    _pad: u32,
    carve_a: vec4<u32>,   // where source a's cells are (carve.wgsl; level 0: as bound)
    carve_b: vec4<u32>,
    carve_dst: vec4<u32>,
    carve_pool: vec4<u32>,
}

// The conv's bindings but its weights (binding 3, declared by each kernel).
@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var src_a: Source;
@group(0) @binding(2) var src_b: Source;
@group(0) @binding(4) var dst: texture_storage_2d_array<rgba32float, write>;

// The sources' texture type: sampled textures read at level 0 (GPUs), or read-only storage
// textures on CPU drivers (kernels::SourceAccess; Kernels::new rewrites this alias and `load`,
// kernels::STORAGE_SOURCES), where lavapipe's storage-image load skips the sampler's per-lane
// mip-level set-up.
alias Source = texture_2d_array<f32>;

// One texel of a texture.
fn texel(t: Source, p: vec2<i32>, layer: u32) -> vec4<f32> {
    return textureLoad(t, p, layer, 0);
}

// Where channel block `layer` of the source read in `mode` (its FROM_B bit) is: its cell's
// top-left texel (x, y) and arena layer (z) (carve.wgsl). A value bound as it is has the carve
// of level 0 and first cell 0: (0, 0, layer). The kernels find it once per block, outside the
// windows of fetches that read the block: lavapipe compiles a pipeline whose every fetch found
// it in about 3x the time.
fn cell(mode: u32, layer: u32) -> vec3<u32> {
    return carved(select(params.carve_a, params.carve_b, (mode & FROM_B) != 0u), layer);
}

// One texel of a source at pixel p of its level, in the cell `at`.
fn load(t: Source, p: vec2<i32>, at: vec3<u32>) -> vec4<f32> {
    return texel(t, p + vec2<i32>(at.xy), at.z);
}

fn max4(t: Source, p: vec2<i32>, at: vec3<u32>) -> vec4<f32> {
    let a = load(t, p, at);
    let b = load(t, p + vec2<i32>(1, 0), at);
    let c = load(t, p + vec2<i32>(0, 1), at);
    let d = load(t, p + vec2<i32>(1, 1), at);
    return max(max(a, b), max(c, d));
}

// The device reads zero outside a texture (kernels::out_of_bounds_reads_zero: lavapipe, which
// has Vulkan's robustImageAccess2, and wgpu leaves its loads unchecked there) and the plan's
// sources have exactly the sizes their read modes imply (Kernels::pad_from_bounds), so every
// pixel outside the level reads texels outside its source and `fetch` need not test. Without
// the test a fetch is one load, where the test made it a branch: llvmpipe keeps the returned
// value in a variable whose every use LLVM's coroutine pass checks against every other, and
// runs the test's compares and masks on each fetch (`docs/perf/lavapipe-2026-12-02-s28.log`).
override OOB_ZERO: bool = false;

// One channel block of a source at output-resolution pixel (x, y), the block in the cell `at`
// (`cell`); zero outside (padding 1). Outside a carved source's cell lies another cell, never
// zero: its fetches always test.
fn fetch(t: Source, mode: u32, x: i32, y: i32, at: vec3<u32>) -> vec4<f32> {
    if (!OOB_ZERO || (mode & CARVED) != 0u) && (x < 0 || y < 0 || x >= i32(params.width) || y >= i32(params.height)) {
        return vec4<f32>(0.0);
    }
    return read_at(t, mode, x, y, at);
}

// `fetch` at a pixel (x, y) inside the level, without the test.
fn read_at(t: Source, mode: u32, x: i32, y: i32, at: vec3<u32>) -> vec4<f32> {
    switch mode & READ_MODE {
        case READ_POOL: { return max4(t, vec2<i32>(2 * x, 2 * y), at); }
        case READ_UPSAMPLE: { return load(t, vec2<i32>(x >> 1u, y >> 1u), at); }
        case READ_POOL_UPSAMPLE: { return max4(t, vec2<i32>(x & ~1, y & ~1), at); }
        default: { return load(t, vec2<i32>(x, y), at); }
    }
}

// Where output channel block `layer` is (as `cell` finds a source's), found once per block.
fn dst_cell(layer: u32) -> vec3<u32> {
    return carved(params.carve_dst, layer);
}

// Store output texel p of the block in the cell `at` (`dst_cell`).
fn store_dst(p: vec2<u32>, at: vec3<u32>, v: vec4<f32>) {
    textureStore(dst, p + at.xy, at.z, v);
}

// The condition of a loop that runs its body once, `loop { ... continuing { break if once(); } }`,
// to give a long unrolled body a basic block of its own on lavapipe (the Winograd lanes steps).
// LLVM's mem2reg (PromoteMemToReg's live-in scan) walks each block that both loads and stores a
// variable from the block's start to the variable's first use, so a body of thousands of
// operations in one block compiles in time quadratic in its length: 40% of the F(4x4) 8x4
// tile's compile was that scan. In three blocks per step that tile compiled in 7.6 s instead
// of 15.8, for frames 1.01-1.07x as long (`docs/perf/lavapipe-2026-12-01-s27.log`). The condition holds in every
// invocation that reaches such a loop (the kernels return first where ob0 >= cout4, so cout4
// is at least 1), but the compiler cannot know it, so the loop and its blocks stay.
fn once() -> bool {
    return params.cout4 != 0u;
}

fn activate(v: vec4<f32>) -> vec4<f32> {
    var a = v;
    if LEAKY {
        a = select(v * params.slope, v, v >= vec4<f32>(0.0));
    }
    return clamp(a, vec4<f32>(-STORE_MAX), vec4<f32>(STORE_MAX));
}

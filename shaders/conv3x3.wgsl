// 3x3 convolution (zero padding) with bias and optional LeakyReLU fused into the store, over the
// channel concatenation cat(a, b) of two sources read in place (no concat copy). Each source is
// read as-is, max-pooled 2x2, nearest-upsampled 2x, or max-pooled then upsampled, so pooling and
// upsampling never run as passes of their own.
//
// Activations are rgba32float texture arrays: layer l holds channels 4l..4l+3 (texture loads are
// vectorised on lavapipe, storage-buffer loads run lane by lane). Weights are vec4s of 4 output
// channels in a 2D texture; every invocation of a workgroup reads the same weight texel.
//
// Specialised per layer kind by override constants (read modes, activation); sizes come in the
// uniform, so one pipeline serves every resolution and width.

// How a source is read at output pixel (x, y).
const READ_DIRECT: u32 = 0u;        // src[x, y]
const READ_POOL: u32 = 1u;          // max of src[2x + i, 2y + j]          (src at 2x resolution)
const READ_UPSAMPLE: u32 = 2u;      // src[x / 2, y / 2]                   (src at 1/2 resolution)
const READ_POOL_UPSAMPLE: u32 = 3u; // upsample(pool(src)): max of the 2x2 block holding (x, y)

override MODE_A: u32 = 0u;
override MODE_B: u32 = 0u;
override LEAKY: bool = true;

// Register tile: each invocation computes 4 output rows x 4 output channels (one block) at one
// x, in four named accumulators: no indexable local arrays, which lavapipe would keep in
// per-lane scratch memory.
const ROWS: u32 = 4u;

struct Params {
    width: u32,       // output (= convolution) resolution
    height: u32,
    cin4_a: u32,      // channel blocks read from a
    cin4_b: u32,      // channel blocks read from b (0: no b, or a zeroed hidden state)
    cin4_total: u32,  // input blocks in the weight layout (a + b)
    cout4: u32,       // output blocks stored
    b_offset: u32,    // first vec4 of the bias in `weights`
    t_offset: u32,    // first vec4 of the taps: [out block][in block][tap][in lane] -> vec4 out
    slope: f32,       // LeakyReLU negative slope
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var src_a: texture_2d_array<f32>;
@group(0) @binding(2) var src_b: texture_2d_array<f32>;
@group(0) @binding(3) var weights: texture_2d<f32>;
@group(0) @binding(4) var dst: texture_storage_2d_array<rgba32float, write>;

// Weights are WEIGHT_ROW vec4s per texture row (kernels::WEIGHT_ROW on the host).
const WEIGHT_ROW: u32 = 4096u;

fn weight(i: u32) -> vec4<f32> {
    return textureLoad(weights, vec2<u32>(i % WEIGHT_ROW, i / WEIGHT_ROW), 0);
}

fn max4(t: texture_2d_array<f32>, p: vec2<i32>, layer: u32) -> vec4<f32> {
    let a = textureLoad(t, p, layer, 0);
    let b = textureLoad(t, p + vec2<i32>(1, 0), layer, 0);
    let c = textureLoad(t, p + vec2<i32>(0, 1), layer, 0);
    let d = textureLoad(t, p + vec2<i32>(1, 1), layer, 0);
    return max(max(a, b), max(c, d));
}

// One channel block of a source at output-resolution pixel (x, y); zero outside (padding 1).
fn fetch(t: texture_2d_array<f32>, mode: u32, x: i32, y: i32, layer: u32) -> vec4<f32> {
    if x < 0 || y < 0 || x >= i32(params.width) || y >= i32(params.height) {
        return vec4<f32>(0.0);
    }
    switch mode {
        case READ_POOL: { return max4(t, vec2<i32>(2 * x, 2 * y), layer); }
        case READ_UPSAMPLE: { return textureLoad(t, vec2<i32>(x >> 1u, y >> 1u), layer, 0); }
        case READ_POOL_UPSAMPLE: { return max4(t, vec2<i32>(x & ~1, y & ~1), layer); }
        default: { return textureLoad(t, vec2<i32>(x, y), layer, 0); }
    }
}

// The four accumulated rows of a tile.
struct Tile {
    r0: vec4<f32>,
    r1: vec4<f32>,
    r2: vec4<f32>,
    r3: vec4<f32>,
}

// The 4x4 block of weights of one tap: column l maps input lane l to the 4 output channels.
fn tap(i: u32) -> mat4x4<f32> {
    return mat4x4<f32>(weight(i), weight(i + 1u), weight(i + 2u), weight(i + 3u));
}

// Add input block `layer` of `t` (read with `mode`) at weight block `cb` to the tile whose
// top-left output is (x, y0).
fn accumulate(acc: ptr<function, Tile>, t: texture_2d_array<f32>, mode: u32, layer: u32, cb: u32, ob: u32, x: i32, y0: i32) {
    let base = params.t_offset + (ob * params.cin4_total + cb) * 36u;
    for (var kx = 0u; kx < 3u; kx++) {
        let sx = x + i32(kx) - 1;
        // Column kx of the 6-row input window.
        let v0 = fetch(t, mode, sx, y0 - 1, layer);
        let v1 = fetch(t, mode, sx, y0, layer);
        let v2 = fetch(t, mode, sx, y0 + 1, layer);
        let v3 = fetch(t, mode, sx, y0 + 2, layer);
        let v4 = fetch(t, mode, sx, y0 + 3, layer);
        let v5 = fetch(t, mode, sx, y0 + 4, layer);
        // Taps (ky, kx) for ky = 0, 1, 2; tap index ky * 3 + kx, 4 vec4s each.
        let m0 = tap(base + kx * 4u);
        let m1 = tap(base + 12u + kx * 4u);
        let m2 = tap(base + 24u + kx * 4u);
        (*acc).r0 += m0 * v0 + m1 * v1 + m2 * v2;
        (*acc).r1 += m0 * v1 + m1 * v2 + m2 * v3;
        (*acc).r2 += m0 * v2 + m1 * v3 + m2 * v4;
        (*acc).r3 += m0 * v3 + m1 * v4 + m2 * v5;
    }
}

fn activate(v: vec4<f32>) -> vec4<f32> {
    if LEAKY {
        return select(v * params.slope, v, v >= vec4<f32>(0.0));
    }
    return v;
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let x = gid.x;
    let y0 = gid.y * ROWS;
    let ob = gid.z;
    if x >= params.width || y0 >= params.height || ob >= params.cout4 {
        return;
    }
    let bias = weight(params.b_offset + ob);
    var acc = Tile(bias, bias, bias, bias);
    let xi = i32(x);
    let yi = i32(y0);
    // Source a: input blocks 0 .. cin4_a; then source b: blocks cin4_a .. cin4_a + cin4_b.
    for (var c = 0u; c < params.cin4_a; c++) {
        accumulate(&acc, src_a, MODE_A, c, c, ob, xi, yi);
    }
    for (var c = 0u; c < params.cin4_b; c++) {
        accumulate(&acc, src_b, MODE_B, c, params.cin4_a + c, ob, xi, yi);
    }
    // Store with the activation fused (rows past the bottom edge are dropped).
    let h = params.height;
    textureStore(dst, vec2<u32>(x, y0), ob, activate(acc.r0));
    if y0 + 1u < h { textureStore(dst, vec2<u32>(x, y0 + 1u), ob, activate(acc.r1)); }
    if y0 + 2u < h { textureStore(dst, vec2<u32>(x, y0 + 2u), ob, activate(acc.r2)); }
    if y0 + 3u < h { textureStore(dst, vec2<u32>(x, y0 + 3u), ob, activate(acc.r3)); }
}

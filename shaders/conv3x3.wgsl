// 3x3 convolution (zero padding) with bias and optional LeakyReLU fused into the store, over the
// channel concatenation cat(a, b) of two sources read in place (no concat copy). Each source is
// read as-is, max-pooled 2x2, nearest-upsampled 2x, or max-pooled then upsampled, so pooling and
// upsampling never run as passes of their own.
//
// Activations are rgba32float texture arrays: layer l holds channels 4l..4l+3 (texture loads are
// vectorised on lavapipe, storage-buffer loads are not). Weights are vec4s of 4 output channels;
// every invocation of a workgroup reads the same weight address, so the load is a broadcast.
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

// Register tile: each invocation computes ROWS output rows x BLOCKS*4 output channels at one x.
const ROWS: u32 = 4u;
const BLOCKS: u32 = 4u;

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
@group(0) @binding(3) var<storage, read> weights: array<vec4<f32>>;
@group(0) @binding(4) var dst: texture_storage_2d_array<rgba32float, write>;

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
        case 1u: { return max4(t, vec2<i32>(2 * x, 2 * y), layer); }
        case 2u: { return textureLoad(t, vec2<i32>(x >> 1u, y >> 1u), layer, 0); }
        case 3u: { return max4(t, vec2<i32>(x & ~1, y & ~1), layer); }
        default: { return textureLoad(t, vec2<i32>(x, y), layer, 0); }
    }
}

// acc[r][k] += sum over the 3x3 taps and 4 input lanes of block `cb`, for the window of inputs.
fn accumulate(
    acc: ptr<function, array<vec4<f32>, ROWS * BLOCKS>>,
    window: ptr<function, array<vec4<f32>, (ROWS + 2u) * 3u>>,
    ob0: u32,
    cb: u32,
) {
    for (var k = 0u; k < BLOCKS; k++) {
        let base = params.t_offset + ((ob0 + k) * params.cin4_total + cb) * 36u;
        for (var tap = 0u; tap < 9u; tap++) {
            let w0 = weights[base + tap * 4u];
            let w1 = weights[base + tap * 4u + 1u];
            let w2 = weights[base + tap * 4u + 2u];
            let w3 = weights[base + tap * 4u + 3u];
            let ky = tap / 3u;
            let kx = tap % 3u;
            for (var r = 0u; r < ROWS; r++) {
                let v = (*window)[(r + ky) * 3u + kx];
                (*acc)[r * BLOCKS + k] += v.x * w0 + v.y * w1 + v.z * w2 + v.w * w3;
            }
        }
    }
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let x = gid.x;
    let y0 = gid.y * ROWS;
    let ob0 = gid.z * BLOCKS;
    if x >= params.width || y0 >= params.height {
        return;
    }
    // Start from the bias (padded to whole tiles with zeros on the host).
    var acc: array<vec4<f32>, ROWS * BLOCKS>;
    for (var k = 0u; k < BLOCKS; k++) {
        let bias = weights[params.b_offset + ob0 + k];
        for (var r = 0u; r < ROWS; r++) {
            acc[r * BLOCKS + k] = bias;
        }
    }
    var window: array<vec4<f32>, (ROWS + 2u) * 3u>;
    let xi = i32(x) - 1;
    let yi = i32(y0) - 1;
    // Source a: input blocks 0 .. cin4_a.
    for (var c = 0u; c < params.cin4_a; c++) {
        for (var i = 0u; i < ROWS + 2u; i++) {
            for (var j = 0u; j < 3u; j++) {
                window[i * 3u + j] = fetch(src_a, MODE_A, xi + i32(j), yi + i32(i), c);
            }
        }
        accumulate(&acc, &window, ob0, c);
    }
    // Source b: input blocks cin4_a .. cin4_a + cin4_b.
    for (var c = 0u; c < params.cin4_b; c++) {
        for (var i = 0u; i < ROWS + 2u; i++) {
            for (var j = 0u; j < 3u; j++) {
                window[i * 3u + j] = fetch(src_b, MODE_B, xi + i32(j), yi + i32(i), c);
            }
        }
        accumulate(&acc, &window, ob0, params.cin4_a + c);
    }
    // Store with the activation fused.
    for (var r = 0u; r < ROWS; r++) {
        let y = y0 + r;
        if y >= params.height {
            break;
        }
        for (var k = 0u; k < BLOCKS; k++) {
            if ob0 + k < params.cout4 {
                var v = acc[r * BLOCKS + k];
                if LEAKY {
                    v = select(v * params.slope, v, v >= vec4<f32>(0.0));
                }
                textureStore(dst, vec2<u32>(x, y), ob0 + k, v);
            }
        }
    }
}

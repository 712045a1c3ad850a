// Temporal accumulation of the denoised output along the motion: rae-core's accumulate.rs (the
// CPU reference) and weights-tool's rae_weights/accumulate.py are the same computation, and the
// tests hold the three to each other.
//
// After the output pass (which writes the network's radiance into `current`), per pixel, on
// tonemapped values T(x) = x / (1 + x):
// 1. The history is the previous accumulated output at x + motion, tonemapped, bilinear between
//    pixel centres; used only where the motion is valid (finite, at most `params.limit`) and
//    the point lies inside the frame, and on frames with history (`params.history`); elsewhere
//    the output is `current`.
// 2. The history is clipped, per channel, to mean +- GAMMA standard deviations of T over the
//    current output's 3x3 neighbourhood inside the frame (no ghosting at disocclusions), and
//    to the neighbourhood's minimum and maximum (the output stays within its range).
// 3. The output is T^-1(ALPHA T(current) + (1 - ALPHA) T(history)), at most RADIANCE_MAX.
// It writes the result into the caller's output and into `next`, the next frame's history.

const ALPHA: f32 = 0.5;
const GAMMA: f32 = 0.5;
const RADIANCE_MAX: f32 = 1e8;

struct Params {
    width: u32,
    height: u32,
    limit: f32,     // the largest valid |motion| component (4 x the frame's larger side)
    history: u32,   // 0: no history this frame (first frame, reset, no motion): pass through
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> current: array<f32>;
@group(0) @binding(2) var<storage, read> previous: array<f32>;
@group(0) @binding(3) var<storage, read> motion: array<f32>;
@group(0) @binding(4) var<storage, read_write> radiance: array<f32>;
@group(0) @binding(5) var<storage, read_write> next: array<f32>;

fn tonemapped(buffer_is_current: bool, x: u32, y: u32) -> vec3<f32> {
    let i = 3u * (y * params.width + x);
    var v: vec3<f32>;
    if buffer_is_current {
        v = vec3<f32>(current[i], current[i + 1u], current[i + 2u]);
    } else {
        v = vec3<f32>(previous[i], previous[i + 1u], previous[i + 2u]);
    }
    return v / (vec3<f32>(1.0) + v);
}

fn store(i: u32, v: vec3<f32>) {
    radiance[3u * i] = v.x;
    radiance[3u * i + 1u] = v.y;
    radiance[3u * i + 2u] = v.z;
    next[3u * i] = v.x;
    next[3u * i + 1u] = v.y;
    next[3u * i + 2u] = v.z;
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= params.width || gid.y >= params.height {
        return;
    }
    let i = gid.y * params.width + gid.x;
    let here = vec3<f32>(current[3u * i], current[3u * i + 1u], current[3u * i + 2u]);
    if params.history == 0u {
        store(i, here);
        return;
    }
    let m = vec2<f32>(motion[2u * i], motion[2u * i + 1u]);
    let s = vec2<f32>(gid.xy) + m;
    let last = vec2<f32>(f32(params.width - 1u), f32(params.height - 1u));
    // NaN fails every comparison, and an infinity exceeds the limit.
    if !(all(abs(m) <= vec2<f32>(params.limit)) && all(s >= vec2<f32>(0.0)) && all(s <= last)) {
        store(i, here);
        return;
    }
    // The 3x3 neighbourhood, loaded once (a tap outside the frame loads its nearest pixel and
    // counts for nothing): its count, sum, range, then the deviation from the mean.
    var taps: array<vec3<f32>, 9>;
    var inside: array<f32, 9>;
    var count = 0.0;
    var sum = vec3<f32>(0.0);
    var lowest = vec3<f32>(1.0);
    var highest = vec3<f32>(0.0);
    let size = vec2<i32>(i32(params.width), i32(params.height));
    for (var k = 0; k < 9; k++) {
        let q = vec2<i32>(gid.xy) + vec2<i32>(k % 3 - 1, k / 3 - 1);
        let c = clamp(q, vec2<i32>(0), size - vec2<i32>(1));
        let v = tonemapped(true, u32(c.x), u32(c.y));
        let w = select(0.0, 1.0, all(q == c));
        taps[k] = v;
        inside[k] = w;
        count += w;
        sum += v * w;
        if w > 0.0 {
            lowest = min(lowest, v);
            highest = max(highest, v);
        }
    }
    let mean = sum / count;
    var dev = vec3<f32>(0.0);
    for (var k = 0; k < 9; k++) {
        let d = taps[k] - mean;
        dev += d * d * inside[k];
    }
    let deviation = sqrt(dev / count);
    let s0 = floor(s);
    let f = s - s0;
    let p = vec2<u32>(s0);
    let q = min(p + vec2<u32>(1u), vec2<u32>(params.width - 1u, params.height - 1u));
    let top = tonemapped(false, p.x, p.y) * (1.0 - f.x) + tonemapped(false, q.x, p.y) * f.x;
    let bottom = tonemapped(false, p.x, q.y) * (1.0 - f.x) + tonemapped(false, q.x, q.y) * f.x;
    let history = min(max(top * (1.0 - f.y) + bottom * f.y, max(mean - GAMMA * deviation, lowest)), min(mean + GAMMA * deviation, highest));
    let b = ALPHA * (here / (vec3<f32>(1.0) + here)) + (1.0 - ALPHA) * history;
    store(i, min(b / max(vec3<f32>(1.0) - b, vec3<f32>(1e-30)), vec3<f32>(RADIANCE_MAX)));
}

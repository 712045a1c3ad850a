// Output: network result (channel block 0 of a texture array, padded size) -> radiance, tightly
// packed RGB f32: the rectangle at (x0, y0) of size width x height (the frame, cropping the
// padding; or a frame tile's interior, cropping its overlap). Inverts the transfer function,
// clamping first so the result is finite, non-negative and bounded, and remodulates by
// (albedo + eps).
//
// The bound: demodulated output radiance <= OUT_GAIN x the frame's largest demodulated input
// radiance (prep.wgsl records its transfer-space value in `stats[0]`), and <= exp(80) - 1. A
// denoiser moves energy between pixels; it does not make any, so a frame cannot come out
// brighter than twice its brightest input, and an all-black frame comes out black
// (rae-core `cpu::output_limit` is the same rule).

const ALBEDO_MAX: f32 = 1e3;
const RADIANCE_MAX: f32 = 1e8;
// exp(80) - 1 ~ 5.5e34: finite in f32 with room for the albedo factor.
const OUT_LOG_MAX: f32 = 80.0;
const OUT_GAIN: f32 = 2.0;

struct Params {
    x0: u32,          // the rectangle read from the network output
    y0: u32,
    width: u32,       // its size: the output buffer is width x height
    height: u32,
    in_stride: u32,   // row length of the albedo buffer (the network's pixel (x, y) is its)
    demodulate: u32,
    transfer: u32,    // 0: none, 1: log1p
    albedo_eps: f32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var src: texture_2d_array<f32>;
@group(0) @binding(2) var<storage, read> albedo: array<f32>;
@group(0) @binding(3) var<storage, read_write> radiance: array<f32>;
@group(0) @binding(4) var<storage, read> stats: array<u32, 4>;

fn albedo_channel(v: f32) -> f32 {
    let b = bitcast<u32>(v);
    if (b & 0x7f800000u) == 0x7f800000u {
        return 0.0;
    }
    return clamp(v, 0.0, ALBEDO_MAX);
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= params.width || gid.y >= params.height {
        return;
    }
    let at = vec2<u32>(params.x0 + gid.x, params.y0 + gid.y);
    let y = textureLoad(src, at, 0u, 0).xyz;
    let in_max = bitcast<f32>(stats[0]);
    var r: vec3<f32>;
    if params.transfer == 1u {
        let limit = min(log(1.0 + OUT_GAIN * (exp(in_max) - 1.0)), OUT_LOG_MAX);
        r = exp(clamp(y, vec3<f32>(0.0), vec3<f32>(limit))) - vec3<f32>(1.0);
    } else {
        r = clamp(y, vec3<f32>(0.0), vec3<f32>(min(OUT_GAIN * in_max, RADIANCE_MAX)));
    }
    let i = gid.y * params.width + gid.x;
    if params.demodulate != 0u {
        let j = at.y * params.in_stride + at.x;
        let a = vec3<f32>(albedo_channel(albedo[3u * j]), albedo_channel(albedo[3u * j + 1u]),
                          albedo_channel(albedo[3u * j + 2u]));
        r = r * (a + vec3<f32>(params.albedo_eps));
    }
    radiance[3u * i] = r.x;
    radiance[3u * i + 1u] = r.y;
    radiance[3u * i + 2u] = r.z;
}

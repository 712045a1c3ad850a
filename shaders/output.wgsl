// Output: network result (channel block 0 of a texture array, padded size) -> radiance, tightly
// packed RGB f32: the rectangle at (x0, y0) of size width x height (the frame, cropping the
// padding; or a frame tile's interior, cropping its overlap). Inverts the transfer function,
// clamping first so the result is finite, non-negative and bounded, and remodulates by
// (albedo + eps). At a miss (input_policy.wgsl's `is_miss`, appended) the result is the input
// color: where the ray hits nothing the renderer looks the background up, it does not estimate it.
//
// The bound: demodulated output radiance <= OUT_GAIN x the frame's largest demodulated input
// radiance (prep.wgsl records its transfer-space value in `stats[0]`), and <= exp(80) - 1. A
// denoiser moves energy between pixels; it does not make any, so a frame cannot come out
// brighter than twice its brightest input, and an all-black frame comes out black
// (rae-core `cpu::output_limit` is the same rule).

// exp(80) - 1 ~ 5.5e34: finite in f32 with room for the albedo factor.
const OUT_LOG_MAX: f32 = 80.0;
const OUT_GAIN: f32 = 2.0;

struct Params {
    x0: u32,          // the rectangle read from the network output
    y0: u32,
    width: u32,       // its size: the output buffer is width x height
    height: u32,
    in_stride: u32,   // row length of the input buffers (the network's pixel (x, y) is theirs)
    demodulate: u32,
    transfer: u32,    // 0: none, 1: log1p
    albedo_eps: f32,
    miss_by: u32,     // bit 0: depth tells a miss, bit 1: normal does (what the model reads)
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var src: texture_2d_array<f32>;
@group(0) @binding(2) var<storage, read> albedo: array<f32>;
@group(0) @binding(3) var<storage, read_write> radiance: array<f32>;
@group(0) @binding(4) var<storage, read> stats: array<u32, 4>;
@group(0) @binding(5) var<storage, read> color: array<f32>;
@group(0) @binding(6) var<storage, read> normal: array<f32>;
@group(0) @binding(7) var<storage, read> depth: array<f32>;

// Whether input pixel j is a miss, from the buffers the model reads (params.miss_by).
fn miss_at(j: u32) -> bool {
    let by_depth = (params.miss_by & 1u) != 0u;
    let by_normal = (params.miss_by & 2u) != 0u;
    var d = DEPTH_MAX;
    var n = vec3<f32>(0.0);
    if by_depth {
        d = sanitize_depth(depth[j]);
    }
    if by_normal {
        n = sanitize_normal(vec3<f32>(normal[3u * j], normal[3u * j + 1u], normal[3u * j + 2u]));
    }
    return is_miss(d, n, by_depth, by_normal);
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
    let j = at.y * params.in_stride + at.x;
    let miss = params.miss_by != 0u && miss_at(j);
    if miss {
        r = sanitize_color(vec3<f32>(color[3u * j], color[3u * j + 1u], color[3u * j + 2u]));
    } else if params.demodulate != 0u {
        let a = sanitize_albedo(vec3<f32>(albedo[3u * j], albedo[3u * j + 1u], albedo[3u * j + 2u]));
        r = r * (a + vec3<f32>(params.albedo_eps));
    }
    radiance[3u * i] = r.x;
    radiance[3u * i + 1u] = r.y;
    radiance[3u * i + 2u] = r.z;
}

// Input preparation: the renderer's buffers (tightly packed f32: RGB, or one value per pixel)
// -> the network input, a texture array of channel blocks at the padded size.
//
// Every value is made finite and bounded first (the input policy, see rae-core `frame`); color is
// divided by (albedo + eps) when the model demodulates and passed through log1p when it declares
// that transfer; depth goes through log1p. Only the buffers the model declares are packed, at the
// channel offsets the host computed from the model. Pixels past the frame (padding to a multiple
// of 2^levels) replicate the nearest edge pixel.
//
// It also records the frame's largest prepared color value in `stats` (cleared by the host
// before the pass), which output.wgsl uses to bound the result. Prepared color is >= 0, so its
// bits order like u32s and an atomicMax on the bits is a max on the values.

const NONE: u32 = 0xffffffffu;
const RADIANCE_MAX: f32 = 1e8;
const ALBEDO_MAX: f32 = 1e3;
const DEPTH_MAX: f32 = 1e6;
// Largest magnitude stored: f32::MAX for f32 activations, 65504 for f16.
override STORE_MAX: f32 = 3.4028234e38;

struct Params {
    width: u32,        // frame size
    height: u32,
    pwidth: u32,       // padded size (the network's)
    pheight: u32,
    off_color: u32,    // first channel of each buffer in the packed input, or NONE
    off_albedo: u32,
    off_normal: u32,
    off_depth: u32,
    off_roughness: u32,
    layers: u32,       // channel blocks written
    demodulate: u32,   // 1: color / (albedo + albedo_eps)
    transfer: u32,     // 0: none, 1: log1p
    albedo_eps: f32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> color: array<f32>;
@group(0) @binding(2) var<storage, read> albedo: array<f32>;
@group(0) @binding(3) var<storage, read> normal: array<f32>;
@group(0) @binding(4) var<storage, read> depth: array<f32>;
@group(0) @binding(5) var<storage, read> roughness: array<f32>;
@group(0) @binding(6) var dst: texture_storage_2d_array<rgba32float, write>;
// [0]: bits of the largest prepared color value of the frame.
@group(0) @binding(7) var<storage, read_write> stats: array<atomic<u32>, 4>;

var<workgroup> group_max: atomic<u32>;

// NaN -> 0, +Inf -> posinf, -Inf -> lo, then clamp to [lo, hi]. Decided on the bits, so no
// compiler assumption about NaN can remove the test.
fn sanitize(v: f32, lo: f32, hi: f32, posinf: f32) -> f32 {
    let b = bitcast<u32>(v);
    if (b & 0x7f800000u) == 0x7f800000u {
        if (b & 0x007fffffu) != 0u {
            return clamp(0.0, lo, hi);
        }
        if (b & 0x80000000u) != 0u {
            return lo;
        }
        return clamp(posinf, lo, hi);
    }
    return clamp(v, lo, hi);
}


fn albedo_at(i: u32) -> vec3<f32> {
    let a = vec3<f32>(albedo[3u * i], albedo[3u * i + 1u], albedo[3u * i + 2u]);
    return vec3<f32>(
        sanitize(a.x, 0.0, ALBEDO_MAX, 0.0),
        sanitize(a.y, 0.0, ALBEDO_MAX, 0.0),
        sanitize(a.z, 0.0, ALBEDO_MAX, 0.0),
    );
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    if li == 0u {
        atomicStore(&group_max, 0u);
    }
    workgroupBarrier();
    let inside = gid.x < params.pwidth && gid.y < params.pheight;
    if inside {
        atomicMax(&group_max, prepare(gid.xy));
    }
    workgroupBarrier();
    if li == 0u {
        atomicMax(&stats[0], atomicLoad(&group_max));
    }
}

// Prepare and store one pixel of the padded input; returns the bits of its largest color value.
fn prepare(gid: vec2<u32>) -> u32 {
    let i = min(gid.y, params.height - 1u) * params.width + min(gid.x, params.width - 1u);
    var ch: array<f32, 16>;
    var color_max = 0.0;

    if params.off_color != NONE {
        let c = vec3<f32>(color[3u * i], color[3u * i + 1u], color[3u * i + 2u]);
        var s = vec3<f32>(
            sanitize(c.x, 0.0, RADIANCE_MAX, RADIANCE_MAX),
            sanitize(c.y, 0.0, RADIANCE_MAX, RADIANCE_MAX),
            sanitize(c.z, 0.0, RADIANCE_MAX, RADIANCE_MAX),
        );
        if params.demodulate != 0u {
            s = s / (albedo_at(i) + vec3<f32>(params.albedo_eps));
        }
        if params.transfer == 1u {
            s = log(vec3<f32>(1.0) + s);
        }
        color_max = max(s.x, max(s.y, s.z));
        ch[params.off_color] = s.x;
        ch[params.off_color + 1u] = s.y;
        ch[params.off_color + 2u] = s.z;
    }
    if params.off_albedo != NONE {
        let a = albedo_at(i);
        ch[params.off_albedo] = a.x;
        ch[params.off_albedo + 1u] = a.y;
        ch[params.off_albedo + 2u] = a.z;
    }
    if params.off_normal != NONE {
        let n = vec3<f32>(normal[3u * i], normal[3u * i + 1u], normal[3u * i + 2u]);
        ch[params.off_normal] = sanitize(n.x, -1.0, 1.0, 0.0);
        ch[params.off_normal + 1u] = sanitize(n.y, -1.0, 1.0, 0.0);
        ch[params.off_normal + 2u] = sanitize(n.z, -1.0, 1.0, 0.0);
    }
    if params.off_depth != NONE {
        ch[params.off_depth] = log(1.0 + sanitize(depth[i], 0.0, DEPTH_MAX, DEPTH_MAX));
    }
    if params.off_roughness != NONE {
        ch[params.off_roughness] = sanitize(roughness[i], 0.0, 1.0, 0.0);
    }
    for (var l = 0u; l < params.layers; l++) {
        let v = clamp(vec4<f32>(ch[4u * l], ch[4u * l + 1u], ch[4u * l + 2u], ch[4u * l + 3u]), vec4<f32>(-STORE_MAX), vec4<f32>(STORE_MAX));
        textureStore(dst, vec2<u32>(gid.x, gid.y), l, v);
    }
    return bitcast<u32>(color_max);
}

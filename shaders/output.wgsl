// Output: network result (channel block 0 of a texture array, padded size) -> radiance, tightly
// packed RGB f32 at the frame size (the padding is cropped here). Inverts the transfer function,
// clamping first so the result is finite and non-negative, and remodulates by (albedo + eps).

const ALBEDO_MAX: f32 = 1e3;
const RADIANCE_MAX: f32 = 1e8;
// exp(80) - 1 ~ 5.5e34: finite in f32 with room for the albedo factor.
const OUT_LOG_MAX: f32 = 80.0;

struct Params {
    width: u32,
    height: u32,
    demodulate: u32,
    transfer: u32,    // 0: none, 1: log1p
    albedo_eps: f32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var src: texture_2d_array<f32>;
@group(0) @binding(2) var<storage, read> albedo: array<f32>;
@group(0) @binding(3) var<storage, read_write> radiance: array<f32>;

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
    let y = textureLoad(src, vec2<u32>(gid.x, gid.y), 0u, 0).xyz;
    var r: vec3<f32>;
    if params.transfer == 1u {
        r = exp(clamp(y, vec3<f32>(0.0), vec3<f32>(OUT_LOG_MAX))) - vec3<f32>(1.0);
    } else {
        r = clamp(y, vec3<f32>(0.0), vec3<f32>(RADIANCE_MAX));
    }
    let i = gid.y * params.width + gid.x;
    if params.demodulate != 0u {
        let a = vec3<f32>(albedo_channel(albedo[3u * i]), albedo_channel(albedo[3u * i + 1u]),
                          albedo_channel(albedo[3u * i + 2u]));
        r = r * (a + vec3<f32>(params.albedo_eps));
    }
    radiance[3u * i] = r.x;
    radiance[3u * i + 1u] = r.y;
    radiance[3u * i + 2u] = r.z;
}

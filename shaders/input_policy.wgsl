// The input policy, shared by prep.wgsl and output.wgsl (appended to both by rae-core
// `kernels::conv_module_source`): every buffer value made finite and bounded, and which pixels
// are misses (rae-core `frame` documents the policy; `cpu` and weights-tool's model.py apply the
// same rules).

const RADIANCE_MAX: f32 = 1e8;
const ALBEDO_MAX: f32 = 1e3;
const DEPTH_MAX: f32 = 1e6;

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

fn sanitize3(v: vec3<f32>, lo: f32, hi: f32, posinf: f32) -> vec3<f32> {
    return vec3<f32>(sanitize(v.x, lo, hi, posinf), sanitize(v.y, lo, hi, posinf), sanitize(v.z, lo, hi, posinf));
}

fn sanitize_color(c: vec3<f32>) -> vec3<f32> {
    return sanitize3(c, 0.0, RADIANCE_MAX, RADIANCE_MAX);
}

fn sanitize_albedo(a: vec3<f32>) -> vec3<f32> {
    return sanitize3(a, 0.0, ALBEDO_MAX, 0.0);
}

fn sanitize_normal(n: vec3<f32>) -> vec3<f32> {
    return sanitize3(n, -1.0, 1.0, 0.0);
}

// A miss is a miss whatever the renderer writes for its depth: +inf (rae-trace), 0 (Blender's
// Denoising Depth), NaN, a negative value or one past DEPTH_MAX all become DEPTH_MAX.
fn sanitize_depth(v: f32) -> f32 {
    let d = sanitize(v, 0.0, DEPTH_MAX, DEPTH_MAX);
    return select(DEPTH_MAX, d, d > 0.0);
}

// Whether a pixel's camera ray hit nothing, from the sanitised buffers the model reads: depth
// at DEPTH_MAX (`by_depth`) or a zero normal (`by_normal`; rae-trace and Cycles write 0 where
// the ray misses). There albedo counts as 1 and the output is the input color.
fn is_miss(depth: f32, normal: vec3<f32>, by_depth: bool, by_normal: bool) -> bool {
    return (by_depth && depth >= DEPTH_MAX) || (by_normal && all(normal == vec3<f32>(0.0)));
}

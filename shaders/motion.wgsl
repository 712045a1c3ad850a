// Reprojection of the hidden state with motion vectors: weights-tool's rae_weights/warp.py is
// the same computation in PyTorch, and the golden tests hold the two to each other.
//
// Motion is rae's convention: per pixel, where its surface point was in the previous frame minus
// where it is now, in pixels, x right, y down (two f32 per pixel, the frame's rows top first).
// Three entry points, each a pass of its own, before any conv of a frame that has history:
// - `motion_in`: the frame's motion into level 0 at the padded size as (mx, my, valid, 0): a
//   pixel's motion is valid when both components are finite and at most `params.limit`
//   (4 x the frame's larger side); invalid motion is zeroed. Padding pixels replicate the
//   nearest edge pixel, as prep does with the inputs.
// - `motion_down`: level k + 1 from level k, the mean of each 2x2 block, motion halved (into
//   level-k+1 pixels): each level holds its blocks' mean motion and the fraction of valid pixels.
// - `warp`: a recurrent block's previous hidden state fetched at x + motion of its level,
//   bilinear between pixel centres, zero outside the level, scaled by the validity (where no
//   pixel is valid the block starts from zero, as on a first frame). It writes into the texture
//   the block writes its new state into later in the frame, which is free until then
//   (kernels::ConvPlan reads it there as the recurrent conv's source b).
// Binding numbers are disjoint per entry point: each pipeline's layout has only its own.

struct MotionParams {
    width: u32,   // frame size
    height: u32,
    limit: f32,   // the largest valid |motion| component
    _pad: u32,
}

@group(0) @binding(0) var<uniform> params: MotionParams;
@group(0) @binding(1) var<storage, read> motion: array<f32>;
@group(0) @binding(2) var level0: texture_storage_2d<rgba32float, write>;

@compute @workgroup_size(8, 8, 1)
fn motion_in(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(level0);
    if gid.x >= size.x || gid.y >= size.y {
        return;
    }
    let x = min(gid.x, params.width - 1u);
    let y = min(gid.y, params.height - 1u);
    let i = 2u * (y * params.width + x);
    let m = vec2<f32>(motion[i], motion[i + 1u]);
    // NaN fails every comparison, and an infinity exceeds the limit: both are invalid.
    let ok = all(abs(m) <= vec2<f32>(params.limit));
    textureStore(level0, gid.xy, select(vec4<f32>(0.0), vec4<f32>(m, 1.0, 0.0), ok));
}

@group(0) @binding(3) var finer: texture_2d<f32>;
@group(0) @binding(4) var coarser: texture_storage_2d<rgba32float, write>;

@compute @workgroup_size(8, 8, 1)
fn motion_down(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(coarser);
    if gid.x >= size.x || gid.y >= size.y {
        return;
    }
    let p = vec2<i32>(gid.xy) * 2;
    let sum = textureLoad(finer, p, 0) + textureLoad(finer, p + vec2<i32>(1, 0), 0) + textureLoad(finer, p + vec2<i32>(0, 1), 0)
        + textureLoad(finer, p + vec2<i32>(1, 1), 0);
    let mean = sum * 0.25;
    textureStore(coarser, gid.xy, vec4<f32>(mean.xy * 0.5, mean.z, 0.0));
}

@group(0) @binding(5) var level: texture_2d<f32>;
@group(0) @binding(6) var previous: texture_2d_array<f32>;
// The activations' format (kernels::WARP_F16 rewrites it for f16 storage).
@group(0) @binding(7) var warped: texture_storage_2d_array<rgba32float, write>;

// One texel per invocation, workgroup z = the state's channel block. A tap outside the level has
// weight zero and loads the nearest texel inside: no test in front of a load, which a CPU
// driver would run masked.
@compute @workgroup_size(8, 8, 1)
fn warp(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = vec2<i32>(textureDimensions(warped));
    let here = vec2<i32>(gid.xy);
    if here.x >= size.x || here.y >= size.y {
        return;
    }
    let m = textureLoad(level, here, 0);
    let s = vec2<f32>(here) + m.xy;
    let s0 = floor(s);
    let f = s - s0;
    let p = vec2<i32>(s0);
    let q = p + vec2<i32>(1);
    let last = size - vec2<i32>(1);
    // Per axis: the lower and upper tap's weight (zero outside the level) and where they load.
    let lo_in = select(vec2<f32>(0.0), vec2<f32>(1.0), p >= vec2<i32>(0) & p <= last);
    let hi_in = select(vec2<f32>(0.0), vec2<f32>(1.0), q >= vec2<i32>(0) & q <= last);
    let lo = clamp(p, vec2<i32>(0), last);
    let hi = clamp(q, vec2<i32>(0), last);
    let wx = vec2<f32>((1.0 - f.x) * lo_in.x, f.x * hi_in.x);
    let wy = vec2<f32>((1.0 - f.y) * lo_in.y, f.y * hi_in.y) * m.z;
    let a = textureLoad(previous, lo, gid.z, 0);
    let b = textureLoad(previous, vec2<i32>(hi.x, lo.y), gid.z, 0);
    let c = textureLoad(previous, vec2<i32>(lo.x, hi.y), gid.z, 0);
    let d = textureLoad(previous, hi, gid.z, 0);
    textureStore(warped, here, gid.z, a * (wx.x * wy.x) + b * (wx.y * wy.x) + c * (wx.x * wy.y) + d * (wx.y * wy.y));
}

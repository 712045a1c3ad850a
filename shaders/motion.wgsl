// Reprojection of the hidden state with motion vectors: weights-tool's rae_weights/warp.py is
// the same computation in PyTorch, and the golden tests hold the two to each other.
//
// Motion is rae's convention: per pixel, where its surface point was in the previous frame minus
// where it is now, in pixels, x right, y down (two f32 per pixel, the frame's rows top first).
// Four entry points, each a pass of its own. The first three run before any conv of a frame
// that has history:
// - `motion_in`: the frame's motion into level 0 at the padded size as (mx, my, valid, 0): a
//   pixel's motion is valid when both components are finite and at most `params.limit`
//   (4 x the frame's larger side); invalid motion is zeroed. Padding pixels replicate the
//   nearest edge pixel, as prep does with the inputs. `valid` is then scaled by the pixel's
//   history test (disocclusion): where the previous frame saw another surface at x + motion,
//   its state there is not this pixel's history.
// - `motion_down`: level k + 1 from level k, the mean of each 2x2 block, motion halved (into
//   level-k+1 pixels): each level holds its blocks' mean motion and the fraction of valid pixels.
// - `warp`: a recurrent block's previous hidden state fetched at x + motion of its level,
//   bilinear between pixel centres, zero outside the level, scaled by the validity (where no
//   pixel is valid the block starts from zero, as on a first frame). It writes into the texture
//   the block writes its new state into later in the frame, which is free until then
//   (kernels::ConvPlan reads it there as the recurrent conv's source b).
// - `guide_store`: after the others, on every frame: this frame's guide (normal and prepared
//   depth, from the packed input) into `guide_out`, for the next frame's history test.
// Binding numbers are disjoint per entry point: each pipeline's layout has only its own.
//
// The history test compares the pixel's guide with the previous frame's guide fetched at
// x + motion (bilinear, edge taps clamped): a linear ramp from 1 at `DEPTH_TOLERANCE` to 0 at
// twice that on the difference of prepared depth (log1p, so a relative difference for depths
// above 1), times one from 1 at `NORMAL_TOLERANCE` to 0 at twice that on the distance between
// the normals. Ramps rather than thresholds: the validity is continuous in the inputs, so the
// engine and PyTorch agree to rounding. A model that reads neither normal nor depth has no
// guide and every history passes; one that reads one of them tests that one.

const NONE: u32 = 0xffffffffu;
const DEPTH_TOLERANCE: f32 = 0.05;
const NORMAL_TOLERANCE: f32 = 0.5;
// The first channel of normal and of depth in the packed input (kernels::PrepLayout; NONE: the
// model does not read it).
override OFF_NORMAL: u32 = 0xffffffffu;
override OFF_DEPTH: u32 = 0xffffffffu;

struct MotionParams {
    width: u32,   // frame size
    height: u32,
    limit: f32,   // the largest valid |motion| component
    _pad: u32,
}

@group(0) @binding(0) var<uniform> params: MotionParams;
@group(0) @binding(1) var<storage, read> motion: array<f32>;
@group(0) @binding(2) var level0: texture_storage_2d<rgba32float, write>;
// The frame's packed input (prep's output) and the previous frame's guide (`guide_store`'s;
// 1 x 1 and unread for a model without a guide).
@group(0) @binding(8) var input: texture_2d_array<f32>;
@group(0) @binding(9) var guide: texture_2d<f32>;

// Channel c of the packed input at p (c is an override expression: the index folds away).
fn input_channel(p: vec2<i32>, c: u32) -> f32 {
    return textureLoad(input, p, i32(c / 4u), 0)[c % 4u];
}

// The guide of pixel p: (normal, prepared depth), zero where the model reads none.
fn guide_at(p: vec2<i32>) -> vec4<f32> {
    var g = vec4<f32>(0.0);
    if OFF_NORMAL != NONE {
        g = vec4<f32>(input_channel(p, OFF_NORMAL), input_channel(p, OFF_NORMAL + 1u), input_channel(p, OFF_NORMAL + 2u), 0.0);
    }
    if OFF_DEPTH != NONE {
        g.w = input_channel(p, OFF_DEPTH);
    }
    return g;
}

// 1 up to 1, 0 from 2, linear between.
fn ramp(s: f32) -> f32 {
    return clamp(2.0 - s, 0.0, 1.0);
}

// The history test of pixel `here` with motion `m` (see the top of the file).
fn history(here: vec2<i32>, m: vec2<f32>) -> f32 {
    if OFF_NORMAL == NONE && OFF_DEPTH == NONE {
        return 1.0;
    }
    let last = vec2<i32>(textureDimensions(guide)) - vec2<i32>(1);
    let s = vec2<f32>(here) + m;
    let s0 = floor(s);
    let f = s - s0;
    let lo = clamp(vec2<i32>(s0), vec2<i32>(0), last);
    let hi = clamp(vec2<i32>(s0) + vec2<i32>(1), vec2<i32>(0), last);
    let top = textureLoad(guide, lo, 0) * (1.0 - f.x) + textureLoad(guide, vec2<i32>(hi.x, lo.y), 0) * f.x;
    let bottom = textureLoad(guide, vec2<i32>(lo.x, hi.y), 0) * (1.0 - f.x) + textureLoad(guide, hi, 0) * f.x;
    let previous = top * (1.0 - f.y) + bottom * f.y;
    let now = guide_at(here);
    return ramp(abs(previous.w - now.w) / DEPTH_TOLERANCE) * ramp(length(previous.xyz - now.xyz) / NORMAL_TOLERANCE);
}

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
    let sane = select(vec2<f32>(0.0), m, ok);
    let v = select(0.0, history(vec2<i32>(gid.xy), sane), ok);
    textureStore(level0, gid.xy, vec4<f32>(sane, v, 0.0));
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
    let lo_in = select(vec2<f32>(0.0), vec2<f32>(1.0), (p >= vec2<i32>(0)) & (p <= last));
    let hi_in = select(vec2<f32>(0.0), vec2<f32>(1.0), (q >= vec2<i32>(0)) & (q <= last));
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

@group(0) @binding(10) var guide_out: texture_storage_2d<rgba32float, write>;

@compute @workgroup_size(8, 8, 1)
fn guide_store(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(guide_out);
    if gid.x >= size.x || gid.y >= size.y {
        return;
    }
    textureStore(guide_out, gid.xy, guide_at(vec2<i32>(gid.xy)));
}

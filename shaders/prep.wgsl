// Input preparation: the renderer's buffers (tightly packed f32: RGB, or one value per pixel)
// -> the network input, a texture array of channel blocks at the padded size.
//
// Every value is made finite and bounded first (the input policy, input_policy.wgsl, appended);
// at a miss (`is_miss`) albedo is 1; color is divided by (albedo + eps) when the model
// demodulates and passed through log1p when it declares that transfer; depth goes through
// log1p. Only the buffers the model declares are packed, at the channel offsets the host computed from the model. Pixels past the frame (padding to a multiple
// of 2^levels) replicate the nearest edge pixel.
//
// It also records the frame's largest prepared color value in `stats` (cleared by the host
// before the pass), which output.wgsl uses to bound the result. Prepared color is >= 0, so its
// bits order like u32s and an atomicMax on the bits is a max on the values.
//
// Written for CPU drivers as much as GPUs (`docs/perf/lavapipe-2026-11-24-s17.log`). A pixel's channels are
// picked by comparisons with the override offsets, not gathered in an indexed local array
// (lavapipe keeps such an array in per-lane scratch memory and writes it lane by lane). The
// frame's maximum needs no workgroup memory or barrier (on lavapipe a barrier splits the
// shader into coroutines): each subgroup's largest value is read against the running maximum
// and added with atomicMax only when larger. The stored value only grows, so a stale read can
// cost an extra atomicMax but never lose a maximum; most subgroups stop at the read (at worst,
// a frame that brightens in dispatch order, every subgroup does both).

const NONE: u32 = 0xffffffffu;
// Largest magnitude stored: f32::MAX for f32 activations, 65504 for f16.
override STORE_MAX: f32 = 3.4028234e38;

// The model's input layout (kernels::PrepLayout), one pipeline per Denoiser: the first channel
// of each buffer in the packed input (NONE: not packed), the channel blocks written, whether
// color is divided by (albedo + ALBEDO_EPS), and its transfer (0: none, 1: log1p). As
// overrides, every test of them folds away and each output channel's source is known.
override OFF_COLOR: u32 = 0xffffffffu;
override OFF_ALBEDO: u32 = 0xffffffffu;
override OFF_NORMAL: u32 = 0xffffffffu;
override OFF_DEPTH: u32 = 0xffffffffu;
override OFF_ROUGHNESS: u32 = 0xffffffffu;
override LAYERS: u32 = 1u;
override DEMODULATE: bool = false;
override TRANSFER: u32 = 0u;
override ALBEDO_EPS: f32 = 1e-3;

struct Params {
    width: u32,        // frame size
    height: u32,
    pwidth: u32,       // padded size (the network's)
    pheight: u32,
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

// A pixel's prepared values, each buffer's (zero where the model does not read it).
struct Pixel {
    color: vec3<f32>,
    albedo: vec3<f32>,
    normal: vec3<f32>,
    depth: f32,
    roughness: f32,
}

// Component k (0, 1, 2) of v, by selects: no dynamic index into a vector.
fn component(v: vec3<f32>, k: u32) -> f32 {
    return select(select(v.z, v.y, k == 1u), v.x, k == 0u);
}

// Whether channel c is one of the `n` channels packed from `off` (NONE: never).
fn packed(c: u32, off: u32, n: u32) -> bool {
    return off != NONE && c >= off && c < off + n;
}

// Channel c of the network input: the buffer packed there, or zero (the padding channels of the
// last block).
fn channel(px: Pixel, c: u32) -> f32 {
    var v = 0.0;
    if packed(c, OFF_COLOR, 3u) {
        v = component(px.color, c - OFF_COLOR);
    }
    if packed(c, OFF_ALBEDO, 3u) {
        v = component(px.albedo, c - OFF_ALBEDO);
    }
    if packed(c, OFF_NORMAL, 3u) {
        v = component(px.normal, c - OFF_NORMAL);
    }
    if packed(c, OFF_DEPTH, 1u) {
        v = px.depth;
    }
    if packed(c, OFF_ROUGHNESS, 1u) {
        v = px.roughness;
    }
    return v;
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    // No early return: every invocation reaches subgroupMax (subgroup-uniform control flow).
    var m = 0u;
    if gid.x < params.pwidth && gid.y < params.pheight {
        m = prepare(gid.xy);
    }
    // The subgroup's maximum first, so that one lane per subgroup (those holding it) goes on to
    // the global maximum: a GPU's first wave would otherwise send every lane's atomicMax to one
    // address. Then test before writing: most values are below the running maximum, and a
    // load is cheaper than an atomic read-modify-write.
    let top = subgroupMax(m);
    if m == top && m > atomicLoad(&stats[0]) {
        atomicMax(&stats[0], m);
    }
}

// What subgroupMax becomes on a device without subgroups (kernels::PREP_WITHOUT_SUBGROUPS):
// every lane is its own subgroup, and each tests and writes its value.
fn no_subgroup_max(v: u32) -> u32 {
    return v;
}

// Prepare and store one pixel of the padded input; returns the bits of its largest color value.
fn prepare(gid: vec2<u32>) -> u32 {
    let i = min(gid.y, params.height - 1u) * params.width + min(gid.x, params.width - 1u);
    var px = Pixel(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), 0.0, 0.0);
    var color_max = 0.0;

    // Normal and depth first: they tell a miss, where albedo is 1.
    var d = DEPTH_MAX;
    if OFF_NORMAL != NONE {
        px.normal = sanitize_normal(vec3<f32>(normal[3u * i], normal[3u * i + 1u], normal[3u * i + 2u]));
    }
    if OFF_DEPTH != NONE {
        d = sanitize_depth(depth[i]);
        px.depth = log(1.0 + d);
    }
    // Albedo is read once, for demodulation and as an input channel alike.
    if OFF_ALBEDO != NONE || (OFF_COLOR != NONE && DEMODULATE) {
        let a = sanitize_albedo(vec3<f32>(albedo[3u * i], albedo[3u * i + 1u], albedo[3u * i + 2u]));
        px.albedo = select(a, vec3<f32>(1.0), is_miss(d, px.normal, OFF_DEPTH != NONE, OFF_NORMAL != NONE));
    }
    if OFF_COLOR != NONE {
        var s = sanitize_color(vec3<f32>(color[3u * i], color[3u * i + 1u], color[3u * i + 2u]));
        if DEMODULATE {
            s = s / (px.albedo + vec3<f32>(ALBEDO_EPS));
        }
        if TRANSFER == 1u {
            s = log(vec3<f32>(1.0) + s);
        }
        color_max = max(s.x, max(s.y, s.z));
        px.color = s;
    }
    if OFF_ROUGHNESS != NONE {
        px.roughness = sanitize(roughness[i], 0.0, 1.0, 0.0);
    }
    for (var l = 0u; l < LAYERS; l++) {
        let c = 4u * l;
        let v = vec4<f32>(channel(px, c), channel(px, c + 1u), channel(px, c + 2u), channel(px, c + 3u));
        textureStore(dst, vec2<u32>(gid.x, gid.y), l, clamp(v, vec4<f32>(-STORE_MAX), vec4<f32>(STORE_MAX)));
    }
    return bitcast<u32>(color_max);
}

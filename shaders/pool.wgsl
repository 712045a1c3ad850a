// 2x2 max-pool of every channel block of an encoder block's output into the next level, once per
// frame, so the convs that read it pooled (the next block's first conv, and the decoder's skip
// in the reference network, which upsamples it back) load one texel per value instead of four.
// A thread per output texel and layer (workgroup z = layer). The pooled value is carved into
// an arena's cells (carve.wgsl, appended), which give its size. Not run after a conv whose tile
// writes the pooled value itself (conv3x3.wgsl's POOL_OUT).

@group(0) @binding(0) var src: texture_2d_array<f32>;
@group(0) @binding(1) var dst: texture_storage_2d_array<rgba32float, write>;
// The pooled value's carve: first cell, level, the level's width and height.
@group(0) @binding(2) var<uniform> carve: vec4<u32>;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= carve.z || gid.y >= carve.w {
        return;
    }
    let p = vec2<i32>(gid.xy) * 2;
    let a = textureLoad(src, p, gid.z, 0);
    let b = textureLoad(src, p + vec2<i32>(1, 0), gid.z, 0);
    let c = textureLoad(src, p + vec2<i32>(0, 1), gid.z, 0);
    let d = textureLoad(src, p + vec2<i32>(1, 1), gid.z, 0);
    let at = carved(carve, gid.z);
    textureStore(dst, gid.xy + at.xy, at.z, max(max(a, b), max(c, d)));
}

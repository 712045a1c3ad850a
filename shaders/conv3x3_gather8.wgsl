// The gathers of the Winograd lanes kernels (conv3x3_wino.wgsl, conv3x3_wino4.wgsl) on
// subgroups of 8 lanes: conv3x3_gather16.wgsl's `Gather`, `gather` and ob<OB>_<k> broadcasts,
// which kernels::lanes_module_source puts in the lanes module in their place where the device's
// subgroups have fewer than 16 lanes (lavapipe on CPUs without AVX-512, where llvmpipe compiles
// for 256-bit vectors: subgroups of 8).
//
// A gather is still 16 consecutive vec4s of the weight texture, in two loads of 8: lane k holds
// texel at + k in `lo` and at + 8 + k in `hi`, and vec4 i of the 16 is broadcast from lane i % 8
// of `lo` (i < 8) or `hi`. Each broadcast reads the value conv3x3_gather16.wgsl's reads, so a
// tile's outputs are bit for bit the same on either (tests/engine/kernels.rs).

// 16 vec4s over 8 lanes: lane k holds the k-th in `lo` and the (8 + k)-th in `hi`.
struct Gather {
    lo: vec4<f32>,
    hi: vec4<f32>,
}

// The 16 vec4s from texel `at` of the weight texture on (conv3x3_wino4.wgsl's `weight_texel`).
fn gather(at: u32) -> Gather {
    return Gather(weight_texel(at + lane), weight_texel(at + 8u + lane));
}

// conv3x3_gather16.wgsl's broadcasts with vec4 i of the 16 taken from lo or hi (see there for
// which positions and blocks each holds).
fn ob1_0(a: Gather) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a.lo, 0u), subgroupBroadcast(a.lo, 1u), subgroupBroadcast(a.lo, 2u), subgroupBroadcast(a.lo, 3u));
}
fn ob1_1(a: Gather) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a.lo, 4u), subgroupBroadcast(a.lo, 5u), subgroupBroadcast(a.lo, 6u), subgroupBroadcast(a.lo, 7u));
}
fn ob1_2(a: Gather) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a.hi, 0u), subgroupBroadcast(a.hi, 1u), subgroupBroadcast(a.hi, 2u), subgroupBroadcast(a.hi, 3u));
}
fn ob1_3(a: Gather) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a.hi, 4u), subgroupBroadcast(a.hi, 5u), subgroupBroadcast(a.hi, 6u), subgroupBroadcast(a.hi, 7u));
}
fn ob2_00(a: Gather) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a.lo, 0u), subgroupBroadcast(a.lo, 2u), subgroupBroadcast(a.lo, 4u), subgroupBroadcast(a.lo, 6u));
}
fn ob2_01(a: Gather) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a.lo, 1u), subgroupBroadcast(a.lo, 3u), subgroupBroadcast(a.lo, 5u), subgroupBroadcast(a.lo, 7u));
}
fn ob2_10(a: Gather) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a.hi, 0u), subgroupBroadcast(a.hi, 2u), subgroupBroadcast(a.hi, 4u), subgroupBroadcast(a.hi, 6u));
}
fn ob2_11(a: Gather) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a.hi, 1u), subgroupBroadcast(a.hi, 3u), subgroupBroadcast(a.hi, 5u), subgroupBroadcast(a.hi, 7u));
}
fn ob4_0(a: Gather) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a.lo, 0u), subgroupBroadcast(a.lo, 4u), subgroupBroadcast(a.hi, 0u), subgroupBroadcast(a.hi, 4u));
}
fn ob4_1(a: Gather) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a.lo, 1u), subgroupBroadcast(a.lo, 5u), subgroupBroadcast(a.hi, 1u), subgroupBroadcast(a.hi, 5u));
}
fn ob4_2(a: Gather) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a.lo, 2u), subgroupBroadcast(a.lo, 6u), subgroupBroadcast(a.hi, 2u), subgroupBroadcast(a.hi, 6u));
}
fn ob4_3(a: Gather) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a.lo, 3u), subgroupBroadcast(a.lo, 7u), subgroupBroadcast(a.hi, 3u), subgroupBroadcast(a.hi, 7u));
}

// The gathers of the Winograd lanes kernels (conv3x3_wino.wgsl, conv3x3_wino4.wgsl) on
// subgroups of 16 lanes or more: `Gather`, `gather` and the ob<OB>_<k> broadcasts, which
// kernels::lanes_module_source puts in the lanes module where the device's subgroups have at
// least 16 lanes (conv3x3_gather8.wgsl's where they have 8).
//
// A gather is 16 consecutive vec4s of the weight texture, one per lane: lane k loads texel
// at + k (lanes past 15 load texels no broadcast reads).

// 16 vec4s spread over the lanes: lane k holds the k-th.
alias Gather = vec4<f32>;

// The 16 vec4s from texel `at` of the weight texture on (conv3x3_wino4.wgsl's `weight_texel`).
fn gather(at: u32) -> Gather {
    return weight_texel(at + lane);
}

// The 4x4 of position p from its gather: with OB = 1 the matrix of p sits in lanes 4 (p % 4) ..
// + 3 of g<p / 4>; with OB = 2 block j's in lanes 8 (p % 2) + j + 0, 2, 4, 6 of g<p / 2>; with
// OB = 4 block j's in lanes j + 0, 4, 8, 12 of g<p>.
fn ob1_0(a: Gather) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a, 0u), subgroupBroadcast(a, 1u), subgroupBroadcast(a, 2u), subgroupBroadcast(a, 3u));
}
fn ob1_1(a: Gather) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a, 4u), subgroupBroadcast(a, 5u), subgroupBroadcast(a, 6u), subgroupBroadcast(a, 7u));
}
fn ob1_2(a: Gather) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a, 8u), subgroupBroadcast(a, 9u), subgroupBroadcast(a, 10u), subgroupBroadcast(a, 11u));
}
fn ob1_3(a: Gather) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a, 12u), subgroupBroadcast(a, 13u), subgroupBroadcast(a, 14u), subgroupBroadcast(a, 15u));
}
fn ob2_00(a: Gather) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a, 0u), subgroupBroadcast(a, 2u), subgroupBroadcast(a, 4u), subgroupBroadcast(a, 6u));
}
fn ob2_01(a: Gather) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a, 1u), subgroupBroadcast(a, 3u), subgroupBroadcast(a, 5u), subgroupBroadcast(a, 7u));
}
fn ob2_10(a: Gather) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a, 8u), subgroupBroadcast(a, 10u), subgroupBroadcast(a, 12u), subgroupBroadcast(a, 14u));
}
fn ob2_11(a: Gather) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a, 9u), subgroupBroadcast(a, 11u), subgroupBroadcast(a, 13u), subgroupBroadcast(a, 15u));
}

fn ob4_0(a: Gather) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a, 0u), subgroupBroadcast(a, 4u), subgroupBroadcast(a, 8u), subgroupBroadcast(a, 12u));
}
fn ob4_1(a: Gather) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a, 1u), subgroupBroadcast(a, 5u), subgroupBroadcast(a, 9u), subgroupBroadcast(a, 13u));
}
fn ob4_2(a: Gather) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a, 2u), subgroupBroadcast(a, 6u), subgroupBroadcast(a, 10u), subgroupBroadcast(a, 14u));
}
fn ob4_3(a: Gather) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a, 3u), subgroupBroadcast(a, 7u), subgroupBroadcast(a, 11u), subgroupBroadcast(a, 15u));
}

// The staged stores of conv3x3_wino4.wgsl in 64-bit words: `stage_row64`, which
// kernels::lanes_module_source puts in place of `stage_row` on CPU drivers with 64-bit integers
// (kernels::wide_staged_stores). Only used inside that module, after conv3x3_wino4.wgsl.
//
// On lavapipe a buffer store is a loop over the subgroup's lanes, each iteration picking the
// lane's offset and each of the store's words out of spilled vectors, and a store takes at
// most four words. A row of four rgba32float pixels is four vec4<f32> stores of 16 bytes;
// packed two floats to a u64 it is two vec4<u64> stores of 32 bytes: half the loops for the
// same bytes, bit for bit the same memory (`docs/perf/lavapipe-2026-12-02-s29.log`).

// The staged output buffer (binding 5, `partial` elsewhere in the module) in 32-byte words:
// two pixels each.
@group(0) @binding(5) var<storage, read_write> staged64: array<vec4<u64>>;

// Two floats' bits in one word, `a` in the low half: in memory `a` then `b`, as two f32s.
fn pack64(a: f32, b: f32) -> u64 {
    return u64(bitcast<u32>(a)) | (u64(bitcast<u32>(b)) << 32u);
}

// The four pixels from pixel `i` of the staged buffer on (i even), as `stage_row` stores them.
fn stage_row64(i: u32, a: vec4<f32>, b: vec4<f32>, c: vec4<f32>, d: vec4<f32>) {
    let j = i / 2u;
    staged64[j] = vec4<u64>(pack64(a.x, a.y), pack64(a.z, a.w), pack64(b.x, b.y), pack64(b.z, b.w));
    staged64[j + 1u] = vec4<u64>(pack64(c.x, c.y), pack64(c.z, c.w), pack64(d.x, d.y), pack64(d.z, d.w));
}

// 3x3 convolution as a matrix product for matrix units (tensor cores): the same convolution
// as conv3x3.wgsl (zero padding, bias, optional LeakyReLU, sources cat(a, b) read direct,
// pooled, upsampled or both), computed as an implicit GEMM in 16 x 16 x 16 tiles with f16
// multiplicands and f32 sums.
//
// A workgroup of 128 invocations (4 subgroups of 32) computes 4 output rows x 16 * MT pixels
// x 16 * NT output channels. For each chunk of 16 input channels it stages the 6 x (16 MT + 2)
// input window of its tile into workgroup memory as f16 (`win`, pixel-major: a pixel's 16
// channels are adjacent), and then every subgroup adds, for each of the 9 taps, the products
// of its row's MT pixel tiles (A: 16 pixels x 16 channels, read from `win` at the tap's
// offset) with the tap's NT weight tiles (B: 16 input x 16 output channels, read from the
// weight buffer): MT * NT accumulators of 16 x 16 f32. At the end each accumulator goes through `stage` to the
// output texture with the bias, the activation and the clamp.
//
// Two entry points share the staging, the indexing and the store: `mma` (conv3x3_mma_coop.wgsl,
// appended by kernels::Kernels where the device has 16 x 16 x 16 f16 -> f32 cooperative
// matrices) and `mma_emulated` below, which computes the same products with each invocation
// holding 8 elements of each accumulator: it runs anywhere with SHADER_F16, so the tests check
// the staging, the weight layout and the store on CPU drivers, and only the matrix operations
// themselves are left to a device that has them.
//
// Rounding: inputs and weights are rounded to f16 (inputs clamped to +-65504 first), products
// are exact in f32 and summed in f32. In f32 storage this is a TF32-like mode (10-bit
// mantissas in, f32 sums), not f32 arithmetic; kernels::Tile::mma documents it.
//
// Split operands (entry points `mma_split` and `mma_split_emulated`, kernels::Tile::mma_split):
// each operand x is also carried as its scaled remainder lo(x) = f16((x - hi(x)) * LO_SCALE),
// hi(x) = f16(x) for the weights (rounded on the host) and x's mantissa cut to 10 bits for the
// activations (`stage_chunk_split` says why), and each pair is multiplied three times: a * b ~
// hi(a) hi(b) + (hi(a) lo(b) + lo(a) hi(b)) / LO_SCALE, the dropped lo(a) lo(b) being about
// 2^-21 of the product. That is 21- to 22-bit operands, f32-class results at three times the
// products. The remainder is scaled by 2^11 so
// that it stays a normal f16 (an unscaled remainder of a value under 0.125 would be subnormal,
// which devices may flush), and the scaled products sum in accumulators of their own, divided
// (exactly, a power of two) when the two meet at the store. With f16 activations (SPLIT_A
// false) the activations are exact in f16 and only the weights are split: two products.
//
// The parameter block, the sources and the output, the read modes, `fetch` and `activate` are
// conv_common.wgsl's, appended by kernels::conv_module_source.

enable f16;

// 16-channel output tiles per workgroup: 1 to 4.
override NT: u32 = 2u;
// 16-pixel tiles per subgroup row: 4 for `mma` and `mma_emulated`, 2 for the split entry
// points, whose window holds the remainders too (kernels::Tile::mma_split).
override MT: u32 = 4u;
// Split entry points: the weights carry their remainders (after all the hi tiles, before the
// bias), and with SPLIT_A the activations too (f32 storage; f16 activations have none).
override SPLIT: bool = false;
override SPLIT_A: bool = true;

// Rows per workgroup (one per subgroup) and the staged window's height (ROWS + 2).
const ROWS: u32 = 4u;
const WIN_H: u32 = 6u;
// Elements of one 16 x 16 tile.
const TILE: u32 = 256u;
// Scale of a split operand's remainder (2^11: one f16 mantissa).
const LO_SCALE: f32 = 2048.0;
// Weights of group z (16 * NT output channels from 4 * params.ob0 + z * 16 * NT), f16 from
// w = z * group_stride: for chunk c (input blocks 4c .. 4c + 3) and tap t = ky * 3 + kx, NT
// tiles of 16 x 16 at w + ((c * 9 + t) * NT + nt) * 256, row k (input channel 16c + k, in the
// order of kernels::pack_group's blocks) and column n (output channel); with SPLIT, the same
// tiles again as scaled remainders (`lo_tiles` further on); then the bias as two f16 halves,
// hi and lo (hi + lo is the f32 bias to 22 bits): 16 * NT hi, then 16 * NT lo.
@group(0) @binding(3) var<storage, read> weights: array<f16>;

// The input window of one chunk, [row][column][channel]; an A tile of pixels p .. p + 15 of a
// window row is 16 x 16 row-major at stride 16. The split entry points keep the remainders
// (scaled by LO_SCALE) after it, from lo_at(). Sized for the larger use: 6 x 66 x 16 = 6336
// (MT 4), 2 x 6 x 34 x 16 = 6528 (split, MT 2); kernels::MMA_WORKGROUP_BYTES.
var<workgroup> win: array<f16, 6528>;
// One 16 x 16 f32 accumulator per subgroup on its way to the output, row-major.
var<workgroup> stage: array<f32, 1024>;

// Pixels per subgroup row, and the staged window's width (2 more).
fn pixels() -> u32 {
    return 16u * MT;
}
fn win_w() -> u32 {
    return pixels() + 2u;
}

// Texels (4 channels) staged per chunk.
fn win_texels() -> u32 {
    return WIN_H * win_w() * 4u;
}

// Where the split entry points' remainders of the window start in `win`.
fn lo_at() -> u32 {
    return WIN_H * win_w() * 16u;
}

// Chunks of 16 input channels (4 blocks; the last one padded with zero weights).
fn chunks() -> u32 {
    return (params.cin4_total + 3u) / 4u;
}

// Texel i (< win_texels()) of chunk c's window whose top-left output pixel is (x0, y0), as the
// sources hold it: input block 4c + j (j = i % 4) at window pixel (r, q) is the source texel at
// (x0 + q - 1, y0 + r - 1). Blocks past cin4_a + cin4_b (padding, or a reset frame's hidden
// state) are zero. It goes to `win` at win_at(i), clamped by `to_f16_range`.
fn window_source(i: u32, c: u32, x0: u32, y0: u32) -> vec4<f32> {
    let j = i % 4u;
    let pixel = i / 4u;
    let x = i32(x0 + pixel % win_w()) - 1;
    let y = i32(y0 + pixel / win_w()) - 1;
    let ib = 4u * c + j;
    var v = vec4<f32>(0.0);
    if ib < params.cin4_a {
        v = fetch(src_a, MODE_A, x, y, cell(MODE_A, ib));
    } else if SOURCE_B && ib < params.cin4_a + params.cin4_b {
        v = fetch(src_b, MODE_B, x, y, cell(MODE_B, ib - params.cin4_a));
    }
    return v;
}

// f16 has no room past 65504: clamp rather than overflow to infinity.
fn to_f16_range(v: vec4<f32>) -> vec4<f32> {
    return clamp(v, vec4<f32>(-65504.0), vec4<f32>(65504.0));
}

// Texel i of chunk c's window, clamped to f16's range.
fn window_texel(i: u32, c: u32, x0: u32, y0: u32) -> vec4<f32> {
    return to_f16_range(window_source(i, c, x0, y0));
}

// Where texel i of the window goes in `win`: pixel i / 4, channels 4 (i % 4) .. + 3.
fn win_at(i: u32) -> u32 {
    return (i / 4u) * 16u + 4u * (i % 4u);
}

// Stage chunk c of the window whose top-left output pixel is (x0, y0) into `win`.
fn stage_chunk(li: u32, c: u32, x0: u32, y0: u32) {
    for (var i = li; i < win_texels(); i += 128u) {
        let h = vec4<f16>(window_texel(i, c, x0, y0));
        let o = win_at(i);
        win[o] = h.x;
        win[o + 1u] = h.y;
        win[o + 2u] = h.z;
        win[o + 3u] = h.w;
    }
}

// Stage chunk c as `stage_chunk` does, and with SPLIT_A each value's scaled remainder into
// `win` from lo_at() (`put_texel_split`).
fn stage_chunk_split(li: u32, c: u32, x0: u32, y0: u32) {
    for (var i = li; i < win_texels(); i += 128u) {
        put_texel_split(i, window_source(i, c, x0, y0));
    }
}

// Window texel i, as read from the sources (`window_source`), into `win` at win_at(i): clamped
// to f16's range, hi, and with SPLIT_A its scaled remainder from lo_at().
//
// hi is v cut to what f16 holds exactly, in f32 arithmetic, not f16(v) widened back: the
// NVIDIA driver (580, H100) treats v - f32(f16(v)) as if the round trip were exact, so the
// remainder comes out zero and the split tiles gave f16-operand (TF32-like)
// error. In f16's normal range (from 2^-14) the cut is a mask to 10 mantissa bits; below it,
// where f16's spacing is 2^-24, a truncation to that multiple (exact: powers of two). Either
// converts to f16 exactly, and v - hi is exact in f32 with no conversion to fold.
fn put_texel_split(i: u32, source: vec4<f32>) {
    let v = to_f16_range(source);
    let cut = bitcast<vec4<f32>>(bitcast<vec4<u32>>(v) & vec4<u32>(0xffffe000u));
    let fine = trunc(v * 16777216.0) * (1.0 / 16777216.0);
    let hi = select(cut, fine, abs(v) < vec4<f32>(6.103515625e-5));
    let h = vec4<f16>(hi);
    let o = win_at(i);
    win[o] = h.x;
    win[o + 1u] = h.y;
    win[o + 2u] = h.z;
    win[o + 3u] = h.w;
    if SPLIT_A {
        let l = vec4<f16>((v - hi) * LO_SCALE);
        win[lo_at() + o] = l.x;
        win[lo_at() + o + 1u] = l.y;
        win[lo_at() + o + 2u] = l.z;
        win[lo_at() + o + 3u] = l.w;
    }
}

// Where subgroup sg's A tile mt (pixels 16 mt .. 16 mt + 15 of its row) starts in `win` for
// tap (ky, kx).
fn a_at(sg: u32, mt: u32, ky: u32, kx: u32) -> u32 {
    return ((sg + ky) * win_w() + mt * 16u + kx) * 16u;
}

// Where weight tile nt of chunk c and tap t starts, for the group at w.
fn b_at(w: u32, c: u32, t: u32, nt: u32) -> u32 {
    return w + ((c * 9u + t) * NT + nt) * TILE;
}

// Elements from a weight tile to its scaled remainder (SPLIT): one set of tiles.
fn lo_tiles() -> u32 {
    return chunks() * 9u * NT * TILE;
}

// Store the accumulator subgroup sg left in `stage` (tile mt, nt): 16 pixels x 4 blocks, two
// texels per lane, each with its bias, activated; pixels past the level's edge and blocks past
// the conv's outputs are dropped. z is the workgroup's group.
fn emit(sg: u32, lane: u32, mt: u32, nt: u32, x0: u32, y0: u32, z: u32) {
    let y = y0 + sg;
    let bias_at = z * params.group_stride + select(1u, 2u, SPLIT) * lo_tiles();
    for (var k = lane; k < 64u; k += 32u) {
        let p = k / 4u;
        let j = k % 4u;
        let x = x0 + mt * 16u + p;
        let n = nt * 16u + 4u * j;
        let block = params.ob0 + 4u * NT * z + n / 4u;
        if x < params.width && y < params.height && block < params.cout4 {
            let s = sg * TILE + p * 16u + 4u * j;
            let hi = vec4<f32>(f32(weights[bias_at + n]), f32(weights[bias_at + n + 1u]), f32(weights[bias_at + n + 2u]), f32(weights[bias_at + n + 3u]));
            let bias_lo = bias_at + 16u * NT + n;
            let lo = vec4<f32>(f32(weights[bias_lo]), f32(weights[bias_lo + 1u]), f32(weights[bias_lo + 2u]), f32(weights[bias_lo + 3u]));
            let v = vec4<f32>(stage[s], stage[s + 1u], stage[s + 2u], stage[s + 3u]) + (hi + lo);
            store_dst(vec2<u32>(x, y), dst_cell(block), activate(v));
        }
    }
}

// ---- Emulated matrix operations: entry point `mma_emulated` ----

// The 4 output channels n .. n + 3 of B's row k at b, widened.
fn b_row4(b: u32, k: u32, n: u32) -> vec4<f32> {
    let at = b + k * 16u + n;
    return vec4<f32>(f32(weights[at]), f32(weights[at + 1u]), f32(weights[at + 2u]), f32(weights[at + 3u]));
}

// Put lane `lane`'s part of an accumulator (`mma_emulated`'s layout below: columns n .. n + 3
// in v0 and n + 8 .. n + 11 in v8 of row p) into subgroup sg's part of `stage`.
fn put_lane(sg: u32, lane: u32, v0: vec4<f32>, v8: vec4<f32>) {
    let s = sg * TILE + (lane % 16u) * 16u + 4u * (lane / 16u);
    stage[s] = v0.x;
    stage[s + 1u] = v0.y;
    stage[s + 2u] = v0.z;
    stage[s + 3u] = v0.w;
    stage[s + 8u] = v8.x;
    stage[s + 9u] = v8.y;
    stage[s + 10u] = v8.z;
    stage[s + 11u] = v8.w;
}

// Lane `lane` of a subgroup holds row p = lane % 16 (a pixel) of each of its 4 * NT
// accumulators, at columns (output channels) 4q .. 4q + 3 and 8 + 4q .. 8 + 4q + 3 with
// q = lane / 16: accumulator (mt, nt) at acc[(mt * NT + nt) * 2] and [.. + 1].
@compute @workgroup_size(128, 1, 1)
fn mma_emulated(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let x0 = wg.x * pixels();
    let y0 = wg.y * ROWS;
    let w = wg.z * params.group_stride;
    let sg = li / 32u;
    let lane = li % 32u;
    let p = lane % 16u;
    let n = 4u * (lane / 16u);
    // Zero, as WGSL initialises a var without an initialiser.
    var acc: array<vec4<f32>, 32>;
    for (var c = 0u; c < chunks(); c++) {
        // The previous chunk's products are done before its window is overwritten.
        workgroupBarrier();
        stage_chunk(li, c, x0, y0);
        workgroupBarrier();
        for (var t = 0u; t < 9u; t++) {
            for (var mt = 0u; mt < MT; mt++) {
                let row = a_at(sg, mt, t / 3u, t % 3u) + p * 16u;
                for (var nt = 0u; nt < NT; nt++) {
                    let b = b_at(w, c, t, nt);
                    // Columns n .. n + 3 and n + 8 .. n + 11 of row p.
                    var m0 = acc[(mt * NT + nt) * 2u];
                    var m8 = acc[(mt * NT + nt) * 2u + 1u];
                    for (var k = 0u; k < 16u; k++) {
                        let a = vec4<f32>(f32(win[row + k]));
                        m0 = fma(a, b_row4(b, k, n), m0);
                        m8 = fma(a, b_row4(b, k, n + 8u), m8);
                    }
                    acc[(mt * NT + nt) * 2u] = m0;
                    acc[(mt * NT + nt) * 2u + 1u] = m8;
                }
            }
        }
    }
    for (var mt = 0u; mt < MT; mt++) {
        for (var nt = 0u; nt < NT; nt++) {
            workgroupBarrier();
            put_lane(sg, lane, acc[(mt * NT + nt) * 2u], acc[(mt * NT + nt) * 2u + 1u]);
            workgroupBarrier();
            emit(sg, lane, mt, nt, x0, y0, wg.z);
        }
    }
}

// ---- Emulated split products: entry point `mma_split_emulated` ----

// `mma_emulated` with split operands (MT 2): lane `lane` holds the same elements of the
// 2 * NT main accumulators at acc[(mt * NT + nt) * 2 ..] and of the remainders' products at
// acc[16 + (mt * NT + nt) * 2 ..]; the two meet before the store as `mma_split`'s do.
@compute @workgroup_size(128, 1, 1)
fn mma_split_emulated(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let x0 = wg.x * pixels();
    let y0 = wg.y * ROWS;
    let w = wg.z * params.group_stride;
    let sg = li / 32u;
    let lane = li % 32u;
    let p = lane % 16u;
    let n = 4u * (lane / 16u);
    // Zero, as WGSL initialises a var without an initialiser.
    var acc: array<vec4<f32>, 32>;
    for (var c = 0u; c < chunks(); c++) {
        // The previous chunk's products are done before its window is overwritten.
        workgroupBarrier();
        stage_chunk_split(li, c, x0, y0);
        workgroupBarrier();
        for (var t = 0u; t < 9u; t++) {
            for (var mt = 0u; mt < MT; mt++) {
                let row = a_at(sg, mt, t / 3u, t % 3u) + p * 16u;
                for (var nt = 0u; nt < NT; nt++) {
                    let b = b_at(w, c, t, nt);
                    let i = (mt * NT + nt) * 2u;
                    var m0 = acc[i];
                    var m8 = acc[i + 1u];
                    var r0 = acc[16u + i];
                    var r8 = acc[17u + i];
                    for (var k = 0u; k < 16u; k++) {
                        let a = vec4<f32>(f32(win[row + k]));
                        let b0 = b_row4(b, k, n);
                        let b8 = b_row4(b, k, n + 8u);
                        m0 = fma(a, b0, m0);
                        m8 = fma(a, b8, m8);
                        // The remainders' products: hi(a) lo(b), and lo(a) hi(b) with SPLIT_A.
                        r0 = fma(a, b_row4(b + lo_tiles(), k, n), r0);
                        r8 = fma(a, b_row4(b + lo_tiles(), k, n + 8u), r8);
                        if SPLIT_A {
                            let l = vec4<f32>(f32(win[lo_at() + row + k]));
                            r0 = fma(l, b0, r0);
                            r8 = fma(l, b8, r8);
                        }
                    }
                    acc[i] = m0;
                    acc[i + 1u] = m8;
                    acc[16u + i] = r0;
                    acc[17u + i] = r8;
                }
            }
        }
    }
    for (var mt = 0u; mt < MT; mt++) {
        for (var nt = 0u; nt < NT; nt++) {
            workgroupBarrier();
            let i = (mt * NT + nt) * 2u;
            put_lane(sg, lane, acc[i] + acc[16u + i] * (1.0 / LO_SCALE), acc[i + 1u] + acc[17u + i] * (1.0 / LO_SCALE));
            workgroupBarrier();
            emit(sg, lane, mt, nt, x0, y0, wg.z);
        }
    }
}

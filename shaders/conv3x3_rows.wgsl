// conv3x3.wgsl's `accumulate_rows` for two-column lanes tiles (kernels::Method::Lanes with
// 2 columns): appended in place of the empty one (kernels::ROWS_STUB) in the conv module that
// runs them, and in no other. It uses conv3x3.wgsl's declarations (Tile, fetch, weights, lane,
// lanes_*, mac3, the overrides).

// ROWS + 2 rows of one input column (the rows past them stay zero); two-column lanes tiles
// have at most 8 rows (kernels::LANES_W2_MAX_ROWS).
struct Column {
    v0: vec4<f32>,
    v1: vec4<f32>,
    v2: vec4<f32>,
    v3: vec4<f32>,
    v4: vec4<f32>,
    v5: vec4<f32>,
    v6: vec4<f32>,
    v7: vec4<f32>,
    v8: vec4<f32>,
    v9: vec4<f32>,
}

fn column(t: Source, mode: u32, x: i32, y0: i32, at: vec3<u32>) -> Column {
    var c: Column;
    c.v0 = fetch(t, mode, x, y0 + -1, at);
    c.v1 = fetch(t, mode, x, y0 + 0, at);
    c.v2 = fetch(t, mode, x, y0 + 1, at);
    if ROWS > 1u { c.v3 = fetch(t, mode, x, y0 + 2, at); }
    if ROWS > 2u { c.v4 = fetch(t, mode, x, y0 + 3, at); }
    if ROWS > 3u { c.v5 = fetch(t, mode, x, y0 + 4, at); }
    if ROWS > 4u { c.v6 = fetch(t, mode, x, y0 + 5, at); }
    if ROWS > 5u { c.v7 = fetch(t, mode, x, y0 + 6, at); }
    if ROWS > 6u { c.v8 = fetch(t, mode, x, y0 + 7, at); }
    if ROWS > 7u { c.v9 = fetch(t, mode, x, y0 + 8, at); }
    return c;
}

// The 4 columns of an input window, x - 1 .. x + 2.
struct Window4 {
    k0: Column,
    k1: Column,
    k2: Column,
    k3: Column,
}

// Input block `cb` of cat(a, b) in the window of columns x - 1 .. x + 2: source a's block cb, or
// source b's block cb - cin4_a. The branch is uniform; it is the only part of a lanes step that
// depends on the source, so the step's body is compiled once for both (conv_common.wgsl's
// SOURCE_B).
fn window4(cb: u32, x: i32, y0: i32) -> Window4 {
    var k: Window4;
    if !SOURCE_B || cb < params.cin4_a {
        let at = cell(MODE_A, cb);
        k = Window4(column(src_a, MODE_A, x - 1, y0, at), column(src_a, MODE_A, x, y0, at), column(src_a, MODE_A, x + 1, y0, at), column(src_a, MODE_A, x + 2, y0, at));
    } else {
        let at = cell(MODE_B, cb - params.cin4_a);
        k = Window4(column(src_b, MODE_B, x - 1, y0, at), column(src_b, MODE_B, x, y0, at), column(src_b, MODE_B, x + 1, y0, at), column(src_b, MODE_B, x + 2, y0, at));
    }
    return k;
}

// The nine taps of one output block, m<kx><ky>.
struct Taps {
    m00: mat4x4<f32>, m01: mat4x4<f32>, m02: mat4x4<f32>,
    m10: mat4x4<f32>, m11: mat4x4<f32>, m12: mat4x4<f32>,
    m20: mat4x4<f32>, m21: mat4x4<f32>, m22: mat4x4<f32>,
}

// The accumulators of two rows of one output block in both columns: a, b rows r, r + 1 of
// column 0; c, d the same rows of column 1.
struct Rows {
    a: vec4<f32>,
    b: vec4<f32>,
    c: vec4<f32>,
    d: vec4<f32>,
}

// Input lane k of one tap: the weights `w` (column k of the tap's 4x4: input lane k to the 4
// outputs) times the lane's value in each of the four input texels, added to the accumulators.
fn mac_lane(p: Rows, w: vec4<f32>, u: f32, v: f32, s: f32, t: f32) -> Rows {
    return Rows(fma(w, vec4<f32>(u), p.a), fma(w, vec4<f32>(v), p.b), fma(w, vec4<f32>(s), p.c), fma(w, vec4<f32>(t), p.d));
}

// One tap's 4x4 weights `m` on the four accumulators, from input texels u, v (column 0's
// rows) and s, t (column 1's), interleaved: each weight scalar feeds four accumulators while
// it is in a register, and each accumulator's products come in `mac`'s order (input lane x,
// y, z, w).
fn mac_rows(p: Rows, m: mat4x4<f32>, u: vec4<f32>, v: vec4<f32>, s: vec4<f32>, t: vec4<f32>) -> Rows {
    var q = mac_lane(p, m[0], u.x, v.x, s.x, t.x);
    q = mac_lane(q, m[1], u.y, v.y, s.y, t.y);
    q = mac_lane(q, m[2], u.z, v.z, s.z, t.z);
    return mac_lane(q, m[3], u.w, v.w, s.w, t.w);
}

// Rows r, r + 1 of one block in columns 0 (a, b) and 1 (c, d) over all nine taps, from input
// rows r .. r + 3 of the input columns l, k, r, q (column 0 reads l, k, r as kx = 0, 1, 2;
// column 1 reads k, r, q): 16 accumulators stay in registers for the 144 multiply-adds each.
// Each accumulator's products come in `add_column`'s order (kx, then ky, then input lane).
fn rows2(p0: Rows, ta: Taps, l0: vec4<f32>, l1: vec4<f32>, l2: vec4<f32>, l3: vec4<f32>, k0: vec4<f32>, k1: vec4<f32>, k2: vec4<f32>, k3: vec4<f32>, r0: vec4<f32>, r1: vec4<f32>, r2: vec4<f32>, r3: vec4<f32>, q0: vec4<f32>, q1: vec4<f32>, q2: vec4<f32>, q3: vec4<f32>) -> Rows {
    var p = mac_rows(p0, ta.m00, l0, l1, k0, k1);
    p = mac_rows(p, ta.m01, l1, l2, k1, k2);
    p = mac_rows(p, ta.m02, l2, l3, k2, k3);
    p = mac_rows(p, ta.m10, k0, k1, r0, r1);
    p = mac_rows(p, ta.m11, k1, k2, r1, r2);
    p = mac_rows(p, ta.m12, k2, k3, r2, r3);
    p = mac_rows(p, ta.m20, r0, r1, q0, q1);
    p = mac_rows(p, ta.m21, r1, r2, q1, q2);
    p = mac_rows(p, ta.m22, r2, r3, q2, q3);
    return p;
}

// Add one block's nine taps `t` to its tile in column 0 (acc, from the input columns l, c, r)
// and column 1 (acd, from c, r, q), two rows at a time.
fn add_block_rows(acc: ptr<function, Tile>, acd: ptr<function, Tile>, t: Taps, l: Column, c: Column, r: Column, q: Column) {
    { let p = rows2(Rows((*acc).r0, (*acc).r1, (*acd).r0, (*acd).r1), t, l.v0, l.v1, l.v2, l.v3, c.v0, c.v1, c.v2, c.v3, r.v0, r.v1, r.v2, r.v3, q.v0, q.v1, q.v2, q.v3); (*acc).r0 = p.a; (*acc).r1 = p.b; (*acd).r0 = p.c; (*acd).r1 = p.d; }
    if ROWS > 2u { let p = rows2(Rows((*acc).r2, (*acc).r3, (*acd).r2, (*acd).r3), t, l.v2, l.v3, l.v4, l.v5, c.v2, c.v3, c.v4, c.v5, r.v2, r.v3, r.v4, r.v5, q.v2, q.v3, q.v4, q.v5); (*acc).r2 = p.a; (*acc).r3 = p.b; (*acd).r2 = p.c; (*acd).r3 = p.d; }
    if ROWS > 4u { let p = rows2(Rows((*acc).r4, (*acc).r5, (*acd).r4, (*acd).r5), t, l.v4, l.v5, l.v6, l.v7, c.v4, c.v5, c.v6, c.v7, r.v4, r.v5, r.v6, r.v7, q.v4, q.v5, q.v6, q.v7); (*acc).r4 = p.a; (*acc).r5 = p.b; (*acd).r4 = p.c; (*acd).r5 = p.d; }
    if ROWS > 6u { let p = rows2(Rows((*acc).r6, (*acc).r7, (*acd).r6, (*acd).r7), t, l.v6, l.v7, l.v8, l.v9, c.v6, c.v7, c.v8, c.v9, r.v6, r.v7, r.v8, r.v9, q.v6, q.v7, q.v8, q.v9); (*acc).r6 = p.a; (*acc).r7 = p.b; (*acd).r6 = p.c; (*acd).r7 = p.d; }
}

// The taps of blocks j (0 to 3) from tap vec4s spread over the lanes as in `lanes_*`: a<kx><ky>
// holds lanes 0..7 of tap (ky, kx), b<kx><ky> lanes 8..15.
struct Spread {
    a00: vec4<f32>, a01: vec4<f32>, a02: vec4<f32>, a10: vec4<f32>, a11: vec4<f32>, a12: vec4<f32>, a20: vec4<f32>, a21: vec4<f32>, a22: vec4<f32>,
    b00: vec4<f32>, b01: vec4<f32>, b02: vec4<f32>, b10: vec4<f32>, b11: vec4<f32>, b12: vec4<f32>, b20: vec4<f32>, b21: vec4<f32>, b22: vec4<f32>,
}

// This lane's share of the weights of input block `cb`: tap (ky, kx)'s 4 x OB vec4s start at
// base + (ky * 3 + kx) * 4 * OB (lanes past them load unused vec4s).
fn spread(base: u32) -> Spread {
    var s: Spread;
    s.a00 = weight(base + 0u * OB + lane);
    s.a01 = weight(base + 12u * OB + lane);
    s.a02 = weight(base + 24u * OB + lane);
    s.a10 = weight(base + 4u * OB + lane);
    s.a11 = weight(base + 16u * OB + lane);
    s.a12 = weight(base + 28u * OB + lane);
    s.a20 = weight(base + 8u * OB + lane);
    s.a21 = weight(base + 20u * OB + lane);
    s.a22 = weight(base + 32u * OB + lane);
    if OB > 2u {
        s.b00 = weight(base + 0u * OB + 8u + lane);
        s.b01 = weight(base + 12u * OB + 8u + lane);
        s.b02 = weight(base + 24u * OB + 8u + lane);
        s.b10 = weight(base + 4u * OB + 8u + lane);
        s.b11 = weight(base + 16u * OB + 8u + lane);
        s.b12 = weight(base + 28u * OB + 8u + lane);
        s.b20 = weight(base + 8u * OB + 8u + lane);
        s.b21 = weight(base + 20u * OB + 8u + lane);
        s.b22 = weight(base + 32u * OB + 8u + lane);
    }
    return s;
}

// The nine taps of one block.
fn taps_1(s: Spread) -> Taps {
    return Taps(lanes_1(s.a00), lanes_1(s.a01), lanes_1(s.a02), lanes_1(s.a10), lanes_1(s.a11), lanes_1(s.a12), lanes_1(s.a20), lanes_1(s.a21), lanes_1(s.a22));
}

// The nine taps of block 0 of two.
fn taps_2_0(s: Spread) -> Taps {
    return Taps(lanes_2_0(s.a00), lanes_2_0(s.a01), lanes_2_0(s.a02), lanes_2_0(s.a10), lanes_2_0(s.a11), lanes_2_0(s.a12), lanes_2_0(s.a20), lanes_2_0(s.a21), lanes_2_0(s.a22));
}

// The nine taps of block 1 of two.
fn taps_2_1(s: Spread) -> Taps {
    return Taps(lanes_2_1(s.a00), lanes_2_1(s.a01), lanes_2_1(s.a02), lanes_2_1(s.a10), lanes_2_1(s.a11), lanes_2_1(s.a12), lanes_2_1(s.a20), lanes_2_1(s.a21), lanes_2_1(s.a22));
}

// The nine taps of block 0 of four.
fn taps_4_0(s: Spread) -> Taps {
    return Taps(lanes_4_0(s.a00, s.b00), lanes_4_0(s.a01, s.b01), lanes_4_0(s.a02, s.b02), lanes_4_0(s.a10, s.b10), lanes_4_0(s.a11, s.b11), lanes_4_0(s.a12, s.b12), lanes_4_0(s.a20, s.b20), lanes_4_0(s.a21, s.b21), lanes_4_0(s.a22, s.b22));
}

// The nine taps of block 1 of four.
fn taps_4_1(s: Spread) -> Taps {
    return Taps(lanes_4_1(s.a00, s.b00), lanes_4_1(s.a01, s.b01), lanes_4_1(s.a02, s.b02), lanes_4_1(s.a10, s.b10), lanes_4_1(s.a11, s.b11), lanes_4_1(s.a12, s.b12), lanes_4_1(s.a20, s.b20), lanes_4_1(s.a21, s.b21), lanes_4_1(s.a22, s.b22));
}

// The nine taps of block 2 of four.
fn taps_4_2(s: Spread) -> Taps {
    return Taps(lanes_4_2(s.a00, s.b00), lanes_4_2(s.a01, s.b01), lanes_4_2(s.a02, s.b02), lanes_4_2(s.a10, s.b10), lanes_4_2(s.a11, s.b11), lanes_4_2(s.a12, s.b12), lanes_4_2(s.a20, s.b20), lanes_4_2(s.a21, s.b21), lanes_4_2(s.a22, s.b22));
}

// The nine taps of block 3 of four.
fn taps_4_3(s: Spread) -> Taps {
    return Taps(lanes_4_3(s.a00, s.b00), lanes_4_3(s.a01, s.b01), lanes_4_3(s.a02, s.b02), lanes_4_3(s.a10, s.b10), lanes_4_3(s.a11, s.b11), lanes_4_3(s.a12, s.b12), lanes_4_3(s.a20, s.b20), lanes_4_3(s.a21, s.b21), lanes_4_3(s.a22, s.b22));
}

// Add input block `cb` of cat(a, b) (`window4`) to a two-column lanes tile (weights
// across the subgroup) whose top-left output is (x, y0), two rows at a time: the input columns
// x - 1 .. x + 2 are fetched first, then each pair of rows of each block takes all its
// products in both columns in one pass (`rows2`), its accumulators loaded and stored once per
// input block rather than once per column. Column 0's blocks are in acc0..acc3, column 1's in acc4..acc7;
// every sum runs in `accumulate`'s order, so the output is bit-identical to the direct tile's.
// A ROWS = 1 tile computes a second row it never stores.
//
// Why only two-column tiles, and at most 8 rows: this body is one basic block of up to
// 2 x 8 x 4 x 144 multiply-adds per input block, and LLVM's compile time grows faster than its
// size; the driver's front end also inlines every row pair before the override drops the ones
// past ROWS, so the rows this file does not have cost no build time (16-row two-column tiles
// run 1.36-1.41x the time of 8-row ones, `docs/perf/lavapipe-2026-11-23-s9.log`). Both columns
// in one pass (16 accumulators) give lanes8x4w2 fastest frames 0.94x those of one column per
// pass (`lavapipe-2026-11-23-s10.log`). On lavapipe the one-column 16 x 4 tile unrolled this way
// runs 0.89x `accumulate`'s column loop but takes 3x as long to compile cold, and the column
// loop with two rows at a time gains nothing (`lavapipe-2026-11-23-s9.log`). Two columns share each fetched column and weight twice, so a
// 4- or 8-row tile is the fast shape, and a short tile keeps the compile near the loop's.
fn accumulate_rows(acc0: ptr<function, Tile>, acc1: ptr<function, Tile>, acc2: ptr<function, Tile>, acc3: ptr<function, Tile>, acc4: ptr<function, Tile>, acc5: ptr<function, Tile>, acc6: ptr<function, Tile>, acc7: ptr<function, Tile>, cb: u32, w: u32, x: i32, y0: i32) {
    let k = window4(cb, x, y0);
    let k0 = k.k0;
    let k1 = k.k1;
    let k2 = k.k2;
    let k3 = k.k3;
    let s = spread(w + cb * 36u * OB);
    // Column 0 from input columns 0..2, column 1 from 1..3, block by block, both columns in
    // one pass (TW is 2 wherever this runs).
    if OB == 1u {
        add_block_rows(acc0, acc4, taps_1(s), k0, k1, k2, k3);
    } else if OB == 2u {
        add_block_rows(acc0, acc4, taps_2_0(s), k0, k1, k2, k3);
        add_block_rows(acc1, acc5, taps_2_1(s), k0, k1, k2, k3);
    } else {
        add_block_rows(acc0, acc4, taps_4_0(s), k0, k1, k2, k3);
        add_block_rows(acc1, acc5, taps_4_1(s), k0, k1, k2, k3);
        add_block_rows(acc2, acc6, taps_4_2(s), k0, k1, k2, k3);
        add_block_rows(acc3, acc7, taps_4_3(s), k0, k1, k2, k3);
    }
}

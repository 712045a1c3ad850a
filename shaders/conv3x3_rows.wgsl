// conv3x3.wgsl's `accumulate_rows` for two-column lanes tiles (kernels::Method::Lanes with
// 2 columns): appended in place of the empty one (kernels::ROWS_STUB) in the conv module that
// runs them, and in no other. It uses conv3x3.wgsl's declarations (Tile, fetch, weights, lane,
// lanes_*, mac3, the overrides).

// ROWS + 2 rows of one input column (the rows past them stay zero).
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
    v10: vec4<f32>,
    v11: vec4<f32>,
    v12: vec4<f32>,
    v13: vec4<f32>,
    v14: vec4<f32>,
    v15: vec4<f32>,
    v16: vec4<f32>,
    v17: vec4<f32>,
}

fn column(t: texture_2d_array<f32>, mode: u32, x: i32, y0: i32, layer: u32) -> Column {
    var c: Column;
    c.v0 = fetch(t, mode, x, y0 + -1, layer);
    c.v1 = fetch(t, mode, x, y0 + 0, layer);
    c.v2 = fetch(t, mode, x, y0 + 1, layer);
    if ROWS > 1u { c.v3 = fetch(t, mode, x, y0 + 2, layer); }
    if ROWS > 2u { c.v4 = fetch(t, mode, x, y0 + 3, layer); }
    if ROWS > 3u { c.v5 = fetch(t, mode, x, y0 + 4, layer); }
    if ROWS > 4u { c.v6 = fetch(t, mode, x, y0 + 5, layer); }
    if ROWS > 5u { c.v7 = fetch(t, mode, x, y0 + 6, layer); }
    if ROWS > 6u { c.v8 = fetch(t, mode, x, y0 + 7, layer); }
    if ROWS > 7u { c.v9 = fetch(t, mode, x, y0 + 8, layer); }
    if ROWS > 8u { c.v10 = fetch(t, mode, x, y0 + 9, layer); }
    if ROWS > 9u { c.v11 = fetch(t, mode, x, y0 + 10, layer); }
    if ROWS > 10u { c.v12 = fetch(t, mode, x, y0 + 11, layer); }
    if ROWS > 11u { c.v13 = fetch(t, mode, x, y0 + 12, layer); }
    if ROWS > 12u { c.v14 = fetch(t, mode, x, y0 + 13, layer); }
    if ROWS > 13u { c.v15 = fetch(t, mode, x, y0 + 14, layer); }
    if ROWS > 14u { c.v16 = fetch(t, mode, x, y0 + 15, layer); }
    if ROWS > 15u { c.v17 = fetch(t, mode, x, y0 + 16, layer); }
    return c;
}

// The nine taps of one output block, m<kx><ky>.
struct Taps {
    m00: mat4x4<f32>, m01: mat4x4<f32>, m02: mat4x4<f32>,
    m10: mat4x4<f32>, m11: mat4x4<f32>, m12: mat4x4<f32>,
    m20: mat4x4<f32>, m21: mat4x4<f32>, m22: mat4x4<f32>,
}

// Two rows' accumulators of one output block.
struct Pair {
    a: vec4<f32>,
    b: vec4<f32>,
}

// Two output rows (a: row r, b: row r + 1) of one block over all nine taps, from input rows
// r .. r + 3 of the columns l, c, r (kx = 0, 1, 2): each weight scalar feeds both rows while it
// is in a register, and the 8 accumulators stay in registers for the 72 multiply-adds each.
// Each row's products come in `add_column`'s order (kx, then ky, then input lane).
fn rows2(a: vec4<f32>, b: vec4<f32>, ta: Taps, l0: vec4<f32>, l1: vec4<f32>, l2: vec4<f32>, l3: vec4<f32>, c0: vec4<f32>, c1: vec4<f32>, c2: vec4<f32>, c3: vec4<f32>, r0: vec4<f32>, r1: vec4<f32>, r2: vec4<f32>, r3: vec4<f32>) -> Pair {
    var p = mac_rows(Pair(a, b), ta.m00, l0, l1);
    p = mac_rows(p, ta.m01, l1, l2);
    p = mac_rows(p, ta.m02, l2, l3);
    p = mac_rows(p, ta.m10, c0, c1);
    p = mac_rows(p, ta.m11, c1, c2);
    p = mac_rows(p, ta.m12, c2, c3);
    p = mac_rows(p, ta.m20, r0, r1);
    p = mac_rows(p, ta.m21, r1, r2);
    p = mac_rows(p, ta.m22, r2, r3);
    return p;
}

// `mac` on two rows of one block at once (inputs u for row a, v for row b), interleaved.
fn mac_rows(p: Pair, m: mat4x4<f32>, u: vec4<f32>, v: vec4<f32>) -> Pair {
    var a = fma(m[0], vec4<f32>(u.x), p.a);
    var b = fma(m[0], vec4<f32>(v.x), p.b);
    a = fma(m[1], vec4<f32>(u.y), a);
    b = fma(m[1], vec4<f32>(v.y), b);
    a = fma(m[2], vec4<f32>(u.z), a);
    b = fma(m[2], vec4<f32>(v.z), b);
    a = fma(m[3], vec4<f32>(u.w), a);
    b = fma(m[3], vec4<f32>(v.w), b);
    return Pair(a, b);
}

// Add input block `layer` of `t` at weight block `cb` to a two-column lanes tile (weights
// across the subgroup) whose top-left output is (x, y0), two rows at a time: the input columns
// x - 1 .. x + TW are fetched first, then each pair of rows of each block takes all its
// products in one pass (`rows2`), its accumulators loaded and stored once per input block
// rather than once per column. Column 0's blocks are in acc0..acc3, column 1's in acc4..acc7;
// every sum runs in `accumulate`'s order, so the output is bit-identical to the direct tile's.
// A ROWS = 1 tile computes a second row it never stores.
//
// Why only two-column tiles: this body is one basic block of up to 2 x 16 x 4 x 144
// multiply-adds per input block, and LLVM's compile time grows faster than its size. On
// lavapipe (docs/PERF.md, session 9) the one-column 16 x 4 tile unrolled this way ran 0.89x
// `accumulate`'s column loop but took 3x as long to compile cold; the column loop with two
// rows at a time gained nothing. Two columns share each fetched column and weight twice, so a
// 4- or 8-row tile is the fast shape, and a short tile keeps the compile near the loop's.
fn accumulate_rows(acc0: ptr<function, Tile>, acc1: ptr<function, Tile>, acc2: ptr<function, Tile>, acc3: ptr<function, Tile>, acc4: ptr<function, Tile>, acc5: ptr<function, Tile>, acc6: ptr<function, Tile>, acc7: ptr<function, Tile>, t: texture_2d_array<f32>, mode: u32, layer: u32, cb: u32, w: u32, x: i32, y0: i32) {
    let k0 = column(t, mode, x - 1, y0, layer);
    let k1 = column(t, mode, x, y0, layer);
    let k2 = column(t, mode, x + 1, y0, layer);
    var k3: Column;
    if TW > 1u { k3 = column(t, mode, x + 2, y0, layer); }
    // Tap (ky, kx)'s 4 x OB vec4s start at base + (ky * 3 + kx) * 4 * OB, spread over the lanes.
    let base = w + cb * 36u * OB;
    let a00 = weights[base + 0u * OB + lane];
    var b00 = vec4<f32>(0.0);
    if OB > 2u { b00 = weights[base + 0u * OB + 8u + lane]; }
    let a01 = weights[base + 12u * OB + lane];
    var b01 = vec4<f32>(0.0);
    if OB > 2u { b01 = weights[base + 12u * OB + 8u + lane]; }
    let a02 = weights[base + 24u * OB + lane];
    var b02 = vec4<f32>(0.0);
    if OB > 2u { b02 = weights[base + 24u * OB + 8u + lane]; }
    let a10 = weights[base + 4u * OB + lane];
    var b10 = vec4<f32>(0.0);
    if OB > 2u { b10 = weights[base + 4u * OB + 8u + lane]; }
    let a11 = weights[base + 16u * OB + lane];
    var b11 = vec4<f32>(0.0);
    if OB > 2u { b11 = weights[base + 16u * OB + 8u + lane]; }
    let a12 = weights[base + 28u * OB + lane];
    var b12 = vec4<f32>(0.0);
    if OB > 2u { b12 = weights[base + 28u * OB + 8u + lane]; }
    let a20 = weights[base + 8u * OB + lane];
    var b20 = vec4<f32>(0.0);
    if OB > 2u { b20 = weights[base + 8u * OB + 8u + lane]; }
    let a21 = weights[base + 20u * OB + lane];
    var b21 = vec4<f32>(0.0);
    if OB > 2u { b21 = weights[base + 20u * OB + 8u + lane]; }
    let a22 = weights[base + 32u * OB + lane];
    var b22 = vec4<f32>(0.0);
    if OB > 2u { b22 = weights[base + 32u * OB + 8u + lane]; }
    if OB == 1u {
        let t0 = Taps(lanes_1(a00), lanes_1(a01), lanes_1(a02), lanes_1(a10), lanes_1(a11), lanes_1(a12), lanes_1(a20), lanes_1(a21), lanes_1(a22));
        { let p = rows2((*acc0).r0, (*acc0).r1, t0, k0.v0, k0.v1, k0.v2, k0.v3, k1.v0, k1.v1, k1.v2, k1.v3, k2.v0, k2.v1, k2.v2, k2.v3); (*acc0).r0 = p.a; (*acc0).r1 = p.b; }
        if ROWS > 2u { let p = rows2((*acc0).r2, (*acc0).r3, t0, k0.v2, k0.v3, k0.v4, k0.v5, k1.v2, k1.v3, k1.v4, k1.v5, k2.v2, k2.v3, k2.v4, k2.v5); (*acc0).r2 = p.a; (*acc0).r3 = p.b; }
        if ROWS > 4u { let p = rows2((*acc0).r4, (*acc0).r5, t0, k0.v4, k0.v5, k0.v6, k0.v7, k1.v4, k1.v5, k1.v6, k1.v7, k2.v4, k2.v5, k2.v6, k2.v7); (*acc0).r4 = p.a; (*acc0).r5 = p.b; }
        if ROWS > 6u { let p = rows2((*acc0).r6, (*acc0).r7, t0, k0.v6, k0.v7, k0.v8, k0.v9, k1.v6, k1.v7, k1.v8, k1.v9, k2.v6, k2.v7, k2.v8, k2.v9); (*acc0).r6 = p.a; (*acc0).r7 = p.b; }
        if ROWS > 8u { let p = rows2((*acc0).r8, (*acc0).r9, t0, k0.v8, k0.v9, k0.v10, k0.v11, k1.v8, k1.v9, k1.v10, k1.v11, k2.v8, k2.v9, k2.v10, k2.v11); (*acc0).r8 = p.a; (*acc0).r9 = p.b; }
        if ROWS > 10u { let p = rows2((*acc0).r10, (*acc0).r11, t0, k0.v10, k0.v11, k0.v12, k0.v13, k1.v10, k1.v11, k1.v12, k1.v13, k2.v10, k2.v11, k2.v12, k2.v13); (*acc0).r10 = p.a; (*acc0).r11 = p.b; }
        if ROWS > 12u { let p = rows2((*acc0).r12, (*acc0).r13, t0, k0.v12, k0.v13, k0.v14, k0.v15, k1.v12, k1.v13, k1.v14, k1.v15, k2.v12, k2.v13, k2.v14, k2.v15); (*acc0).r12 = p.a; (*acc0).r13 = p.b; }
        if ROWS > 14u { let p = rows2((*acc0).r14, (*acc0).r15, t0, k0.v14, k0.v15, k0.v16, k0.v17, k1.v14, k1.v15, k1.v16, k1.v17, k2.v14, k2.v15, k2.v16, k2.v17); (*acc0).r14 = p.a; (*acc0).r15 = p.b; }
        if TW > 1u {
            { let p = rows2((*acc4).r0, (*acc4).r1, t0, k1.v0, k1.v1, k1.v2, k1.v3, k2.v0, k2.v1, k2.v2, k2.v3, k3.v0, k3.v1, k3.v2, k3.v3); (*acc4).r0 = p.a; (*acc4).r1 = p.b; }
            if ROWS > 2u { let p = rows2((*acc4).r2, (*acc4).r3, t0, k1.v2, k1.v3, k1.v4, k1.v5, k2.v2, k2.v3, k2.v4, k2.v5, k3.v2, k3.v3, k3.v4, k3.v5); (*acc4).r2 = p.a; (*acc4).r3 = p.b; }
            if ROWS > 4u { let p = rows2((*acc4).r4, (*acc4).r5, t0, k1.v4, k1.v5, k1.v6, k1.v7, k2.v4, k2.v5, k2.v6, k2.v7, k3.v4, k3.v5, k3.v6, k3.v7); (*acc4).r4 = p.a; (*acc4).r5 = p.b; }
            if ROWS > 6u { let p = rows2((*acc4).r6, (*acc4).r7, t0, k1.v6, k1.v7, k1.v8, k1.v9, k2.v6, k2.v7, k2.v8, k2.v9, k3.v6, k3.v7, k3.v8, k3.v9); (*acc4).r6 = p.a; (*acc4).r7 = p.b; }
            if ROWS > 8u { let p = rows2((*acc4).r8, (*acc4).r9, t0, k1.v8, k1.v9, k1.v10, k1.v11, k2.v8, k2.v9, k2.v10, k2.v11, k3.v8, k3.v9, k3.v10, k3.v11); (*acc4).r8 = p.a; (*acc4).r9 = p.b; }
            if ROWS > 10u { let p = rows2((*acc4).r10, (*acc4).r11, t0, k1.v10, k1.v11, k1.v12, k1.v13, k2.v10, k2.v11, k2.v12, k2.v13, k3.v10, k3.v11, k3.v12, k3.v13); (*acc4).r10 = p.a; (*acc4).r11 = p.b; }
            if ROWS > 12u { let p = rows2((*acc4).r12, (*acc4).r13, t0, k1.v12, k1.v13, k1.v14, k1.v15, k2.v12, k2.v13, k2.v14, k2.v15, k3.v12, k3.v13, k3.v14, k3.v15); (*acc4).r12 = p.a; (*acc4).r13 = p.b; }
            if ROWS > 14u { let p = rows2((*acc4).r14, (*acc4).r15, t0, k1.v14, k1.v15, k1.v16, k1.v17, k2.v14, k2.v15, k2.v16, k2.v17, k3.v14, k3.v15, k3.v16, k3.v17); (*acc4).r14 = p.a; (*acc4).r15 = p.b; }
        }
    } else if OB == 2u {
        let t0 = Taps(lanes_2_0(a00), lanes_2_0(a01), lanes_2_0(a02), lanes_2_0(a10), lanes_2_0(a11), lanes_2_0(a12), lanes_2_0(a20), lanes_2_0(a21), lanes_2_0(a22));
        let t1 = Taps(lanes_2_1(a00), lanes_2_1(a01), lanes_2_1(a02), lanes_2_1(a10), lanes_2_1(a11), lanes_2_1(a12), lanes_2_1(a20), lanes_2_1(a21), lanes_2_1(a22));
        let t2 = t0;
        let t3 = t1;
        { let p = rows2((*acc0).r0, (*acc0).r1, t0, k0.v0, k0.v1, k0.v2, k0.v3, k1.v0, k1.v1, k1.v2, k1.v3, k2.v0, k2.v1, k2.v2, k2.v3); (*acc0).r0 = p.a; (*acc0).r1 = p.b; }
        if ROWS > 2u { let p = rows2((*acc0).r2, (*acc0).r3, t0, k0.v2, k0.v3, k0.v4, k0.v5, k1.v2, k1.v3, k1.v4, k1.v5, k2.v2, k2.v3, k2.v4, k2.v5); (*acc0).r2 = p.a; (*acc0).r3 = p.b; }
        if ROWS > 4u { let p = rows2((*acc0).r4, (*acc0).r5, t0, k0.v4, k0.v5, k0.v6, k0.v7, k1.v4, k1.v5, k1.v6, k1.v7, k2.v4, k2.v5, k2.v6, k2.v7); (*acc0).r4 = p.a; (*acc0).r5 = p.b; }
        if ROWS > 6u { let p = rows2((*acc0).r6, (*acc0).r7, t0, k0.v6, k0.v7, k0.v8, k0.v9, k1.v6, k1.v7, k1.v8, k1.v9, k2.v6, k2.v7, k2.v8, k2.v9); (*acc0).r6 = p.a; (*acc0).r7 = p.b; }
        if ROWS > 8u { let p = rows2((*acc0).r8, (*acc0).r9, t0, k0.v8, k0.v9, k0.v10, k0.v11, k1.v8, k1.v9, k1.v10, k1.v11, k2.v8, k2.v9, k2.v10, k2.v11); (*acc0).r8 = p.a; (*acc0).r9 = p.b; }
        if ROWS > 10u { let p = rows2((*acc0).r10, (*acc0).r11, t0, k0.v10, k0.v11, k0.v12, k0.v13, k1.v10, k1.v11, k1.v12, k1.v13, k2.v10, k2.v11, k2.v12, k2.v13); (*acc0).r10 = p.a; (*acc0).r11 = p.b; }
        if ROWS > 12u { let p = rows2((*acc0).r12, (*acc0).r13, t0, k0.v12, k0.v13, k0.v14, k0.v15, k1.v12, k1.v13, k1.v14, k1.v15, k2.v12, k2.v13, k2.v14, k2.v15); (*acc0).r12 = p.a; (*acc0).r13 = p.b; }
        if ROWS > 14u { let p = rows2((*acc0).r14, (*acc0).r15, t0, k0.v14, k0.v15, k0.v16, k0.v17, k1.v14, k1.v15, k1.v16, k1.v17, k2.v14, k2.v15, k2.v16, k2.v17); (*acc0).r14 = p.a; (*acc0).r15 = p.b; }
        if OB > 1u { let p = rows2((*acc1).r0, (*acc1).r1, t1, k0.v0, k0.v1, k0.v2, k0.v3, k1.v0, k1.v1, k1.v2, k1.v3, k2.v0, k2.v1, k2.v2, k2.v3); (*acc1).r0 = p.a; (*acc1).r1 = p.b; }
        if ROWS > 2u && OB > 1u { let p = rows2((*acc1).r2, (*acc1).r3, t1, k0.v2, k0.v3, k0.v4, k0.v5, k1.v2, k1.v3, k1.v4, k1.v5, k2.v2, k2.v3, k2.v4, k2.v5); (*acc1).r2 = p.a; (*acc1).r3 = p.b; }
        if ROWS > 4u && OB > 1u { let p = rows2((*acc1).r4, (*acc1).r5, t1, k0.v4, k0.v5, k0.v6, k0.v7, k1.v4, k1.v5, k1.v6, k1.v7, k2.v4, k2.v5, k2.v6, k2.v7); (*acc1).r4 = p.a; (*acc1).r5 = p.b; }
        if ROWS > 6u && OB > 1u { let p = rows2((*acc1).r6, (*acc1).r7, t1, k0.v6, k0.v7, k0.v8, k0.v9, k1.v6, k1.v7, k1.v8, k1.v9, k2.v6, k2.v7, k2.v8, k2.v9); (*acc1).r6 = p.a; (*acc1).r7 = p.b; }
        if ROWS > 8u && OB > 1u { let p = rows2((*acc1).r8, (*acc1).r9, t1, k0.v8, k0.v9, k0.v10, k0.v11, k1.v8, k1.v9, k1.v10, k1.v11, k2.v8, k2.v9, k2.v10, k2.v11); (*acc1).r8 = p.a; (*acc1).r9 = p.b; }
        if ROWS > 10u && OB > 1u { let p = rows2((*acc1).r10, (*acc1).r11, t1, k0.v10, k0.v11, k0.v12, k0.v13, k1.v10, k1.v11, k1.v12, k1.v13, k2.v10, k2.v11, k2.v12, k2.v13); (*acc1).r10 = p.a; (*acc1).r11 = p.b; }
        if ROWS > 12u && OB > 1u { let p = rows2((*acc1).r12, (*acc1).r13, t1, k0.v12, k0.v13, k0.v14, k0.v15, k1.v12, k1.v13, k1.v14, k1.v15, k2.v12, k2.v13, k2.v14, k2.v15); (*acc1).r12 = p.a; (*acc1).r13 = p.b; }
        if ROWS > 14u && OB > 1u { let p = rows2((*acc1).r14, (*acc1).r15, t1, k0.v14, k0.v15, k0.v16, k0.v17, k1.v14, k1.v15, k1.v16, k1.v17, k2.v14, k2.v15, k2.v16, k2.v17); (*acc1).r14 = p.a; (*acc1).r15 = p.b; }
        if TW > 1u {
            { let p = rows2((*acc4).r0, (*acc4).r1, t0, k1.v0, k1.v1, k1.v2, k1.v3, k2.v0, k2.v1, k2.v2, k2.v3, k3.v0, k3.v1, k3.v2, k3.v3); (*acc4).r0 = p.a; (*acc4).r1 = p.b; }
            if ROWS > 2u { let p = rows2((*acc4).r2, (*acc4).r3, t0, k1.v2, k1.v3, k1.v4, k1.v5, k2.v2, k2.v3, k2.v4, k2.v5, k3.v2, k3.v3, k3.v4, k3.v5); (*acc4).r2 = p.a; (*acc4).r3 = p.b; }
            if ROWS > 4u { let p = rows2((*acc4).r4, (*acc4).r5, t0, k1.v4, k1.v5, k1.v6, k1.v7, k2.v4, k2.v5, k2.v6, k2.v7, k3.v4, k3.v5, k3.v6, k3.v7); (*acc4).r4 = p.a; (*acc4).r5 = p.b; }
            if ROWS > 6u { let p = rows2((*acc4).r6, (*acc4).r7, t0, k1.v6, k1.v7, k1.v8, k1.v9, k2.v6, k2.v7, k2.v8, k2.v9, k3.v6, k3.v7, k3.v8, k3.v9); (*acc4).r6 = p.a; (*acc4).r7 = p.b; }
            if ROWS > 8u { let p = rows2((*acc4).r8, (*acc4).r9, t0, k1.v8, k1.v9, k1.v10, k1.v11, k2.v8, k2.v9, k2.v10, k2.v11, k3.v8, k3.v9, k3.v10, k3.v11); (*acc4).r8 = p.a; (*acc4).r9 = p.b; }
            if ROWS > 10u { let p = rows2((*acc4).r10, (*acc4).r11, t0, k1.v10, k1.v11, k1.v12, k1.v13, k2.v10, k2.v11, k2.v12, k2.v13, k3.v10, k3.v11, k3.v12, k3.v13); (*acc4).r10 = p.a; (*acc4).r11 = p.b; }
            if ROWS > 12u { let p = rows2((*acc4).r12, (*acc4).r13, t0, k1.v12, k1.v13, k1.v14, k1.v15, k2.v12, k2.v13, k2.v14, k2.v15, k3.v12, k3.v13, k3.v14, k3.v15); (*acc4).r12 = p.a; (*acc4).r13 = p.b; }
            if ROWS > 14u { let p = rows2((*acc4).r14, (*acc4).r15, t0, k1.v14, k1.v15, k1.v16, k1.v17, k2.v14, k2.v15, k2.v16, k2.v17, k3.v14, k3.v15, k3.v16, k3.v17); (*acc4).r14 = p.a; (*acc4).r15 = p.b; }
            if OB > 1u { let p = rows2((*acc5).r0, (*acc5).r1, t1, k1.v0, k1.v1, k1.v2, k1.v3, k2.v0, k2.v1, k2.v2, k2.v3, k3.v0, k3.v1, k3.v2, k3.v3); (*acc5).r0 = p.a; (*acc5).r1 = p.b; }
            if ROWS > 2u && OB > 1u { let p = rows2((*acc5).r2, (*acc5).r3, t1, k1.v2, k1.v3, k1.v4, k1.v5, k2.v2, k2.v3, k2.v4, k2.v5, k3.v2, k3.v3, k3.v4, k3.v5); (*acc5).r2 = p.a; (*acc5).r3 = p.b; }
            if ROWS > 4u && OB > 1u { let p = rows2((*acc5).r4, (*acc5).r5, t1, k1.v4, k1.v5, k1.v6, k1.v7, k2.v4, k2.v5, k2.v6, k2.v7, k3.v4, k3.v5, k3.v6, k3.v7); (*acc5).r4 = p.a; (*acc5).r5 = p.b; }
            if ROWS > 6u && OB > 1u { let p = rows2((*acc5).r6, (*acc5).r7, t1, k1.v6, k1.v7, k1.v8, k1.v9, k2.v6, k2.v7, k2.v8, k2.v9, k3.v6, k3.v7, k3.v8, k3.v9); (*acc5).r6 = p.a; (*acc5).r7 = p.b; }
            if ROWS > 8u && OB > 1u { let p = rows2((*acc5).r8, (*acc5).r9, t1, k1.v8, k1.v9, k1.v10, k1.v11, k2.v8, k2.v9, k2.v10, k2.v11, k3.v8, k3.v9, k3.v10, k3.v11); (*acc5).r8 = p.a; (*acc5).r9 = p.b; }
            if ROWS > 10u && OB > 1u { let p = rows2((*acc5).r10, (*acc5).r11, t1, k1.v10, k1.v11, k1.v12, k1.v13, k2.v10, k2.v11, k2.v12, k2.v13, k3.v10, k3.v11, k3.v12, k3.v13); (*acc5).r10 = p.a; (*acc5).r11 = p.b; }
            if ROWS > 12u && OB > 1u { let p = rows2((*acc5).r12, (*acc5).r13, t1, k1.v12, k1.v13, k1.v14, k1.v15, k2.v12, k2.v13, k2.v14, k2.v15, k3.v12, k3.v13, k3.v14, k3.v15); (*acc5).r12 = p.a; (*acc5).r13 = p.b; }
            if ROWS > 14u && OB > 1u { let p = rows2((*acc5).r14, (*acc5).r15, t1, k1.v14, k1.v15, k1.v16, k1.v17, k2.v14, k2.v15, k2.v16, k2.v17, k3.v14, k3.v15, k3.v16, k3.v17); (*acc5).r14 = p.a; (*acc5).r15 = p.b; }
        }
    } else {
        let t0 = Taps(lanes_4_0(a00, b00), lanes_4_0(a01, b01), lanes_4_0(a02, b02), lanes_4_0(a10, b10), lanes_4_0(a11, b11), lanes_4_0(a12, b12), lanes_4_0(a20, b20), lanes_4_0(a21, b21), lanes_4_0(a22, b22));
        let t1 = Taps(lanes_4_1(a00, b00), lanes_4_1(a01, b01), lanes_4_1(a02, b02), lanes_4_1(a10, b10), lanes_4_1(a11, b11), lanes_4_1(a12, b12), lanes_4_1(a20, b20), lanes_4_1(a21, b21), lanes_4_1(a22, b22));
        let t2 = Taps(lanes_4_2(a00, b00), lanes_4_2(a01, b01), lanes_4_2(a02, b02), lanes_4_2(a10, b10), lanes_4_2(a11, b11), lanes_4_2(a12, b12), lanes_4_2(a20, b20), lanes_4_2(a21, b21), lanes_4_2(a22, b22));
        let t3 = Taps(lanes_4_3(a00, b00), lanes_4_3(a01, b01), lanes_4_3(a02, b02), lanes_4_3(a10, b10), lanes_4_3(a11, b11), lanes_4_3(a12, b12), lanes_4_3(a20, b20), lanes_4_3(a21, b21), lanes_4_3(a22, b22));
        { let p = rows2((*acc0).r0, (*acc0).r1, t0, k0.v0, k0.v1, k0.v2, k0.v3, k1.v0, k1.v1, k1.v2, k1.v3, k2.v0, k2.v1, k2.v2, k2.v3); (*acc0).r0 = p.a; (*acc0).r1 = p.b; }
        if ROWS > 2u { let p = rows2((*acc0).r2, (*acc0).r3, t0, k0.v2, k0.v3, k0.v4, k0.v5, k1.v2, k1.v3, k1.v4, k1.v5, k2.v2, k2.v3, k2.v4, k2.v5); (*acc0).r2 = p.a; (*acc0).r3 = p.b; }
        if ROWS > 4u { let p = rows2((*acc0).r4, (*acc0).r5, t0, k0.v4, k0.v5, k0.v6, k0.v7, k1.v4, k1.v5, k1.v6, k1.v7, k2.v4, k2.v5, k2.v6, k2.v7); (*acc0).r4 = p.a; (*acc0).r5 = p.b; }
        if ROWS > 6u { let p = rows2((*acc0).r6, (*acc0).r7, t0, k0.v6, k0.v7, k0.v8, k0.v9, k1.v6, k1.v7, k1.v8, k1.v9, k2.v6, k2.v7, k2.v8, k2.v9); (*acc0).r6 = p.a; (*acc0).r7 = p.b; }
        if ROWS > 8u { let p = rows2((*acc0).r8, (*acc0).r9, t0, k0.v8, k0.v9, k0.v10, k0.v11, k1.v8, k1.v9, k1.v10, k1.v11, k2.v8, k2.v9, k2.v10, k2.v11); (*acc0).r8 = p.a; (*acc0).r9 = p.b; }
        if ROWS > 10u { let p = rows2((*acc0).r10, (*acc0).r11, t0, k0.v10, k0.v11, k0.v12, k0.v13, k1.v10, k1.v11, k1.v12, k1.v13, k2.v10, k2.v11, k2.v12, k2.v13); (*acc0).r10 = p.a; (*acc0).r11 = p.b; }
        if ROWS > 12u { let p = rows2((*acc0).r12, (*acc0).r13, t0, k0.v12, k0.v13, k0.v14, k0.v15, k1.v12, k1.v13, k1.v14, k1.v15, k2.v12, k2.v13, k2.v14, k2.v15); (*acc0).r12 = p.a; (*acc0).r13 = p.b; }
        if ROWS > 14u { let p = rows2((*acc0).r14, (*acc0).r15, t0, k0.v14, k0.v15, k0.v16, k0.v17, k1.v14, k1.v15, k1.v16, k1.v17, k2.v14, k2.v15, k2.v16, k2.v17); (*acc0).r14 = p.a; (*acc0).r15 = p.b; }
        if OB > 1u { let p = rows2((*acc1).r0, (*acc1).r1, t1, k0.v0, k0.v1, k0.v2, k0.v3, k1.v0, k1.v1, k1.v2, k1.v3, k2.v0, k2.v1, k2.v2, k2.v3); (*acc1).r0 = p.a; (*acc1).r1 = p.b; }
        if ROWS > 2u && OB > 1u { let p = rows2((*acc1).r2, (*acc1).r3, t1, k0.v2, k0.v3, k0.v4, k0.v5, k1.v2, k1.v3, k1.v4, k1.v5, k2.v2, k2.v3, k2.v4, k2.v5); (*acc1).r2 = p.a; (*acc1).r3 = p.b; }
        if ROWS > 4u && OB > 1u { let p = rows2((*acc1).r4, (*acc1).r5, t1, k0.v4, k0.v5, k0.v6, k0.v7, k1.v4, k1.v5, k1.v6, k1.v7, k2.v4, k2.v5, k2.v6, k2.v7); (*acc1).r4 = p.a; (*acc1).r5 = p.b; }
        if ROWS > 6u && OB > 1u { let p = rows2((*acc1).r6, (*acc1).r7, t1, k0.v6, k0.v7, k0.v8, k0.v9, k1.v6, k1.v7, k1.v8, k1.v9, k2.v6, k2.v7, k2.v8, k2.v9); (*acc1).r6 = p.a; (*acc1).r7 = p.b; }
        if ROWS > 8u && OB > 1u { let p = rows2((*acc1).r8, (*acc1).r9, t1, k0.v8, k0.v9, k0.v10, k0.v11, k1.v8, k1.v9, k1.v10, k1.v11, k2.v8, k2.v9, k2.v10, k2.v11); (*acc1).r8 = p.a; (*acc1).r9 = p.b; }
        if ROWS > 10u && OB > 1u { let p = rows2((*acc1).r10, (*acc1).r11, t1, k0.v10, k0.v11, k0.v12, k0.v13, k1.v10, k1.v11, k1.v12, k1.v13, k2.v10, k2.v11, k2.v12, k2.v13); (*acc1).r10 = p.a; (*acc1).r11 = p.b; }
        if ROWS > 12u && OB > 1u { let p = rows2((*acc1).r12, (*acc1).r13, t1, k0.v12, k0.v13, k0.v14, k0.v15, k1.v12, k1.v13, k1.v14, k1.v15, k2.v12, k2.v13, k2.v14, k2.v15); (*acc1).r12 = p.a; (*acc1).r13 = p.b; }
        if ROWS > 14u && OB > 1u { let p = rows2((*acc1).r14, (*acc1).r15, t1, k0.v14, k0.v15, k0.v16, k0.v17, k1.v14, k1.v15, k1.v16, k1.v17, k2.v14, k2.v15, k2.v16, k2.v17); (*acc1).r14 = p.a; (*acc1).r15 = p.b; }
        if OB > 2u { let p = rows2((*acc2).r0, (*acc2).r1, t2, k0.v0, k0.v1, k0.v2, k0.v3, k1.v0, k1.v1, k1.v2, k1.v3, k2.v0, k2.v1, k2.v2, k2.v3); (*acc2).r0 = p.a; (*acc2).r1 = p.b; }
        if ROWS > 2u && OB > 2u { let p = rows2((*acc2).r2, (*acc2).r3, t2, k0.v2, k0.v3, k0.v4, k0.v5, k1.v2, k1.v3, k1.v4, k1.v5, k2.v2, k2.v3, k2.v4, k2.v5); (*acc2).r2 = p.a; (*acc2).r3 = p.b; }
        if ROWS > 4u && OB > 2u { let p = rows2((*acc2).r4, (*acc2).r5, t2, k0.v4, k0.v5, k0.v6, k0.v7, k1.v4, k1.v5, k1.v6, k1.v7, k2.v4, k2.v5, k2.v6, k2.v7); (*acc2).r4 = p.a; (*acc2).r5 = p.b; }
        if ROWS > 6u && OB > 2u { let p = rows2((*acc2).r6, (*acc2).r7, t2, k0.v6, k0.v7, k0.v8, k0.v9, k1.v6, k1.v7, k1.v8, k1.v9, k2.v6, k2.v7, k2.v8, k2.v9); (*acc2).r6 = p.a; (*acc2).r7 = p.b; }
        if ROWS > 8u && OB > 2u { let p = rows2((*acc2).r8, (*acc2).r9, t2, k0.v8, k0.v9, k0.v10, k0.v11, k1.v8, k1.v9, k1.v10, k1.v11, k2.v8, k2.v9, k2.v10, k2.v11); (*acc2).r8 = p.a; (*acc2).r9 = p.b; }
        if ROWS > 10u && OB > 2u { let p = rows2((*acc2).r10, (*acc2).r11, t2, k0.v10, k0.v11, k0.v12, k0.v13, k1.v10, k1.v11, k1.v12, k1.v13, k2.v10, k2.v11, k2.v12, k2.v13); (*acc2).r10 = p.a; (*acc2).r11 = p.b; }
        if ROWS > 12u && OB > 2u { let p = rows2((*acc2).r12, (*acc2).r13, t2, k0.v12, k0.v13, k0.v14, k0.v15, k1.v12, k1.v13, k1.v14, k1.v15, k2.v12, k2.v13, k2.v14, k2.v15); (*acc2).r12 = p.a; (*acc2).r13 = p.b; }
        if ROWS > 14u && OB > 2u { let p = rows2((*acc2).r14, (*acc2).r15, t2, k0.v14, k0.v15, k0.v16, k0.v17, k1.v14, k1.v15, k1.v16, k1.v17, k2.v14, k2.v15, k2.v16, k2.v17); (*acc2).r14 = p.a; (*acc2).r15 = p.b; }
        if OB > 2u { let p = rows2((*acc3).r0, (*acc3).r1, t3, k0.v0, k0.v1, k0.v2, k0.v3, k1.v0, k1.v1, k1.v2, k1.v3, k2.v0, k2.v1, k2.v2, k2.v3); (*acc3).r0 = p.a; (*acc3).r1 = p.b; }
        if ROWS > 2u && OB > 2u { let p = rows2((*acc3).r2, (*acc3).r3, t3, k0.v2, k0.v3, k0.v4, k0.v5, k1.v2, k1.v3, k1.v4, k1.v5, k2.v2, k2.v3, k2.v4, k2.v5); (*acc3).r2 = p.a; (*acc3).r3 = p.b; }
        if ROWS > 4u && OB > 2u { let p = rows2((*acc3).r4, (*acc3).r5, t3, k0.v4, k0.v5, k0.v6, k0.v7, k1.v4, k1.v5, k1.v6, k1.v7, k2.v4, k2.v5, k2.v6, k2.v7); (*acc3).r4 = p.a; (*acc3).r5 = p.b; }
        if ROWS > 6u && OB > 2u { let p = rows2((*acc3).r6, (*acc3).r7, t3, k0.v6, k0.v7, k0.v8, k0.v9, k1.v6, k1.v7, k1.v8, k1.v9, k2.v6, k2.v7, k2.v8, k2.v9); (*acc3).r6 = p.a; (*acc3).r7 = p.b; }
        if ROWS > 8u && OB > 2u { let p = rows2((*acc3).r8, (*acc3).r9, t3, k0.v8, k0.v9, k0.v10, k0.v11, k1.v8, k1.v9, k1.v10, k1.v11, k2.v8, k2.v9, k2.v10, k2.v11); (*acc3).r8 = p.a; (*acc3).r9 = p.b; }
        if ROWS > 10u && OB > 2u { let p = rows2((*acc3).r10, (*acc3).r11, t3, k0.v10, k0.v11, k0.v12, k0.v13, k1.v10, k1.v11, k1.v12, k1.v13, k2.v10, k2.v11, k2.v12, k2.v13); (*acc3).r10 = p.a; (*acc3).r11 = p.b; }
        if ROWS > 12u && OB > 2u { let p = rows2((*acc3).r12, (*acc3).r13, t3, k0.v12, k0.v13, k0.v14, k0.v15, k1.v12, k1.v13, k1.v14, k1.v15, k2.v12, k2.v13, k2.v14, k2.v15); (*acc3).r12 = p.a; (*acc3).r13 = p.b; }
        if ROWS > 14u && OB > 2u { let p = rows2((*acc3).r14, (*acc3).r15, t3, k0.v14, k0.v15, k0.v16, k0.v17, k1.v14, k1.v15, k1.v16, k1.v17, k2.v14, k2.v15, k2.v16, k2.v17); (*acc3).r14 = p.a; (*acc3).r15 = p.b; }
        if TW > 1u {
            { let p = rows2((*acc4).r0, (*acc4).r1, t0, k1.v0, k1.v1, k1.v2, k1.v3, k2.v0, k2.v1, k2.v2, k2.v3, k3.v0, k3.v1, k3.v2, k3.v3); (*acc4).r0 = p.a; (*acc4).r1 = p.b; }
            if ROWS > 2u { let p = rows2((*acc4).r2, (*acc4).r3, t0, k1.v2, k1.v3, k1.v4, k1.v5, k2.v2, k2.v3, k2.v4, k2.v5, k3.v2, k3.v3, k3.v4, k3.v5); (*acc4).r2 = p.a; (*acc4).r3 = p.b; }
            if ROWS > 4u { let p = rows2((*acc4).r4, (*acc4).r5, t0, k1.v4, k1.v5, k1.v6, k1.v7, k2.v4, k2.v5, k2.v6, k2.v7, k3.v4, k3.v5, k3.v6, k3.v7); (*acc4).r4 = p.a; (*acc4).r5 = p.b; }
            if ROWS > 6u { let p = rows2((*acc4).r6, (*acc4).r7, t0, k1.v6, k1.v7, k1.v8, k1.v9, k2.v6, k2.v7, k2.v8, k2.v9, k3.v6, k3.v7, k3.v8, k3.v9); (*acc4).r6 = p.a; (*acc4).r7 = p.b; }
            if ROWS > 8u { let p = rows2((*acc4).r8, (*acc4).r9, t0, k1.v8, k1.v9, k1.v10, k1.v11, k2.v8, k2.v9, k2.v10, k2.v11, k3.v8, k3.v9, k3.v10, k3.v11); (*acc4).r8 = p.a; (*acc4).r9 = p.b; }
            if ROWS > 10u { let p = rows2((*acc4).r10, (*acc4).r11, t0, k1.v10, k1.v11, k1.v12, k1.v13, k2.v10, k2.v11, k2.v12, k2.v13, k3.v10, k3.v11, k3.v12, k3.v13); (*acc4).r10 = p.a; (*acc4).r11 = p.b; }
            if ROWS > 12u { let p = rows2((*acc4).r12, (*acc4).r13, t0, k1.v12, k1.v13, k1.v14, k1.v15, k2.v12, k2.v13, k2.v14, k2.v15, k3.v12, k3.v13, k3.v14, k3.v15); (*acc4).r12 = p.a; (*acc4).r13 = p.b; }
            if ROWS > 14u { let p = rows2((*acc4).r14, (*acc4).r15, t0, k1.v14, k1.v15, k1.v16, k1.v17, k2.v14, k2.v15, k2.v16, k2.v17, k3.v14, k3.v15, k3.v16, k3.v17); (*acc4).r14 = p.a; (*acc4).r15 = p.b; }
            if OB > 1u { let p = rows2((*acc5).r0, (*acc5).r1, t1, k1.v0, k1.v1, k1.v2, k1.v3, k2.v0, k2.v1, k2.v2, k2.v3, k3.v0, k3.v1, k3.v2, k3.v3); (*acc5).r0 = p.a; (*acc5).r1 = p.b; }
            if ROWS > 2u && OB > 1u { let p = rows2((*acc5).r2, (*acc5).r3, t1, k1.v2, k1.v3, k1.v4, k1.v5, k2.v2, k2.v3, k2.v4, k2.v5, k3.v2, k3.v3, k3.v4, k3.v5); (*acc5).r2 = p.a; (*acc5).r3 = p.b; }
            if ROWS > 4u && OB > 1u { let p = rows2((*acc5).r4, (*acc5).r5, t1, k1.v4, k1.v5, k1.v6, k1.v7, k2.v4, k2.v5, k2.v6, k2.v7, k3.v4, k3.v5, k3.v6, k3.v7); (*acc5).r4 = p.a; (*acc5).r5 = p.b; }
            if ROWS > 6u && OB > 1u { let p = rows2((*acc5).r6, (*acc5).r7, t1, k1.v6, k1.v7, k1.v8, k1.v9, k2.v6, k2.v7, k2.v8, k2.v9, k3.v6, k3.v7, k3.v8, k3.v9); (*acc5).r6 = p.a; (*acc5).r7 = p.b; }
            if ROWS > 8u && OB > 1u { let p = rows2((*acc5).r8, (*acc5).r9, t1, k1.v8, k1.v9, k1.v10, k1.v11, k2.v8, k2.v9, k2.v10, k2.v11, k3.v8, k3.v9, k3.v10, k3.v11); (*acc5).r8 = p.a; (*acc5).r9 = p.b; }
            if ROWS > 10u && OB > 1u { let p = rows2((*acc5).r10, (*acc5).r11, t1, k1.v10, k1.v11, k1.v12, k1.v13, k2.v10, k2.v11, k2.v12, k2.v13, k3.v10, k3.v11, k3.v12, k3.v13); (*acc5).r10 = p.a; (*acc5).r11 = p.b; }
            if ROWS > 12u && OB > 1u { let p = rows2((*acc5).r12, (*acc5).r13, t1, k1.v12, k1.v13, k1.v14, k1.v15, k2.v12, k2.v13, k2.v14, k2.v15, k3.v12, k3.v13, k3.v14, k3.v15); (*acc5).r12 = p.a; (*acc5).r13 = p.b; }
            if ROWS > 14u && OB > 1u { let p = rows2((*acc5).r14, (*acc5).r15, t1, k1.v14, k1.v15, k1.v16, k1.v17, k2.v14, k2.v15, k2.v16, k2.v17, k3.v14, k3.v15, k3.v16, k3.v17); (*acc5).r14 = p.a; (*acc5).r15 = p.b; }
            if OB > 2u { let p = rows2((*acc6).r0, (*acc6).r1, t2, k1.v0, k1.v1, k1.v2, k1.v3, k2.v0, k2.v1, k2.v2, k2.v3, k3.v0, k3.v1, k3.v2, k3.v3); (*acc6).r0 = p.a; (*acc6).r1 = p.b; }
            if ROWS > 2u && OB > 2u { let p = rows2((*acc6).r2, (*acc6).r3, t2, k1.v2, k1.v3, k1.v4, k1.v5, k2.v2, k2.v3, k2.v4, k2.v5, k3.v2, k3.v3, k3.v4, k3.v5); (*acc6).r2 = p.a; (*acc6).r3 = p.b; }
            if ROWS > 4u && OB > 2u { let p = rows2((*acc6).r4, (*acc6).r5, t2, k1.v4, k1.v5, k1.v6, k1.v7, k2.v4, k2.v5, k2.v6, k2.v7, k3.v4, k3.v5, k3.v6, k3.v7); (*acc6).r4 = p.a; (*acc6).r5 = p.b; }
            if ROWS > 6u && OB > 2u { let p = rows2((*acc6).r6, (*acc6).r7, t2, k1.v6, k1.v7, k1.v8, k1.v9, k2.v6, k2.v7, k2.v8, k2.v9, k3.v6, k3.v7, k3.v8, k3.v9); (*acc6).r6 = p.a; (*acc6).r7 = p.b; }
            if ROWS > 8u && OB > 2u { let p = rows2((*acc6).r8, (*acc6).r9, t2, k1.v8, k1.v9, k1.v10, k1.v11, k2.v8, k2.v9, k2.v10, k2.v11, k3.v8, k3.v9, k3.v10, k3.v11); (*acc6).r8 = p.a; (*acc6).r9 = p.b; }
            if ROWS > 10u && OB > 2u { let p = rows2((*acc6).r10, (*acc6).r11, t2, k1.v10, k1.v11, k1.v12, k1.v13, k2.v10, k2.v11, k2.v12, k2.v13, k3.v10, k3.v11, k3.v12, k3.v13); (*acc6).r10 = p.a; (*acc6).r11 = p.b; }
            if ROWS > 12u && OB > 2u { let p = rows2((*acc6).r12, (*acc6).r13, t2, k1.v12, k1.v13, k1.v14, k1.v15, k2.v12, k2.v13, k2.v14, k2.v15, k3.v12, k3.v13, k3.v14, k3.v15); (*acc6).r12 = p.a; (*acc6).r13 = p.b; }
            if ROWS > 14u && OB > 2u { let p = rows2((*acc6).r14, (*acc6).r15, t2, k1.v14, k1.v15, k1.v16, k1.v17, k2.v14, k2.v15, k2.v16, k2.v17, k3.v14, k3.v15, k3.v16, k3.v17); (*acc6).r14 = p.a; (*acc6).r15 = p.b; }
            if OB > 2u { let p = rows2((*acc7).r0, (*acc7).r1, t3, k1.v0, k1.v1, k1.v2, k1.v3, k2.v0, k2.v1, k2.v2, k2.v3, k3.v0, k3.v1, k3.v2, k3.v3); (*acc7).r0 = p.a; (*acc7).r1 = p.b; }
            if ROWS > 2u && OB > 2u { let p = rows2((*acc7).r2, (*acc7).r3, t3, k1.v2, k1.v3, k1.v4, k1.v5, k2.v2, k2.v3, k2.v4, k2.v5, k3.v2, k3.v3, k3.v4, k3.v5); (*acc7).r2 = p.a; (*acc7).r3 = p.b; }
            if ROWS > 4u && OB > 2u { let p = rows2((*acc7).r4, (*acc7).r5, t3, k1.v4, k1.v5, k1.v6, k1.v7, k2.v4, k2.v5, k2.v6, k2.v7, k3.v4, k3.v5, k3.v6, k3.v7); (*acc7).r4 = p.a; (*acc7).r5 = p.b; }
            if ROWS > 6u && OB > 2u { let p = rows2((*acc7).r6, (*acc7).r7, t3, k1.v6, k1.v7, k1.v8, k1.v9, k2.v6, k2.v7, k2.v8, k2.v9, k3.v6, k3.v7, k3.v8, k3.v9); (*acc7).r6 = p.a; (*acc7).r7 = p.b; }
            if ROWS > 8u && OB > 2u { let p = rows2((*acc7).r8, (*acc7).r9, t3, k1.v8, k1.v9, k1.v10, k1.v11, k2.v8, k2.v9, k2.v10, k2.v11, k3.v8, k3.v9, k3.v10, k3.v11); (*acc7).r8 = p.a; (*acc7).r9 = p.b; }
            if ROWS > 10u && OB > 2u { let p = rows2((*acc7).r10, (*acc7).r11, t3, k1.v10, k1.v11, k1.v12, k1.v13, k2.v10, k2.v11, k2.v12, k2.v13, k3.v10, k3.v11, k3.v12, k3.v13); (*acc7).r10 = p.a; (*acc7).r11 = p.b; }
            if ROWS > 12u && OB > 2u { let p = rows2((*acc7).r12, (*acc7).r13, t3, k1.v12, k1.v13, k1.v14, k1.v15, k2.v12, k2.v13, k2.v14, k2.v15, k3.v12, k3.v13, k3.v14, k3.v15); (*acc7).r12 = p.a; (*acc7).r13 = p.b; }
            if ROWS > 14u && OB > 2u { let p = rows2((*acc7).r14, (*acc7).r15, t3, k1.v14, k1.v15, k1.v16, k1.v17, k2.v14, k2.v15, k2.v16, k2.v17, k3.v14, k3.v15, k3.v16, k3.v17); (*acc7).r14 = p.a; (*acc7).r15 = p.b; }
        }
    }
}

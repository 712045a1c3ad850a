// conv3x3.wgsl's Winograd F(2x2, 3x3) with its weights loaded across the subgroup: the entry
// point `winograd_lanes` (kernels::Method::WinogradLanes), for CPU drivers with subgroups of at
// least 8 lanes. Appended, with conv3x3_rows.wgsl, to the conv module that runs two-column lanes
// tiles; it uses conv3x3.wgsl's declarations (Quad, Wino, wino_v, wino_store, mac, lane, the
// overrides), conv3x3_rows.wgsl's Column and the gathers (Gather, gather, ob<OB>_<k>) of
// conv3x3_gather16.wgsl or, on subgroups of 8 lanes, conv3x3_gather8.wgsl.
//
// An invocation computes two stacked 2x2 output tiles (ROWS = 4) of 2 columns for OB output
// blocks (1, 2 or 4). Each input block costs 4 columns of 6 fetched texels, their
// transforms V = B^T d B (additions only), and per tile and output block 16 products of a 4x4
// weight matrix with a vec4: 256 multiply-adds per 4 outputs and input block where the direct
// sum takes 576. On lavapipe a texel fetch is about half of the time (each is ~100 instructions
// of per-lane addressing, loads and transposes), so the CPU tile takes OB = 4: each fetched
// texel feeds 16 output channels of 2 stacked tiles (kernels::Tile::CPU_WINOGRAD). Weights are
// texels of the plan's weight texture (conv3x3_wino4.wgsl's `weight_texel`: on lavapipe a
// buffer load at a per-lane address is a loop over the lanes, a texel load one gather), laid
// out as conv3x3.wgsl's `winograd` reads them from its buffer (input block cb, position p,
// input lane l, output block j at w + ((cb * 16 + p) * 4 + l) * OB + j, w =
// params.weight_texel + group z * group_stride); one input block's 64 x OB vec4s are loaded
// 16 at a time, lane k loading the k-th (`WinoGather`; in two loads on 8 lanes), and each
// position's matrix is taken from the lanes by subgroupBroadcast. The sums run in `winograd`'s
// order, so a tile's outputs are bit for bit those of `winograd` with the same OB.

// One input block's transformed weights spread over the lanes: vec4 16 i + k in lane k of g<i>
// (OB = 1 uses g0..g3, OB = 2 g0..g7).
struct WinoGather {
    g0: Gather, g1: Gather, g2: Gather, g3: Gather,
    g4: Gather, g5: Gather, g6: Gather, g7: Gather,
    g8: Gather, g9: Gather, g10: Gather, g11: Gather,
    g12: Gather, g13: Gather, g14: Gather, g15: Gather,
}

fn wino_gather(base: u32) -> WinoGather {
    var s: WinoGather;
    s.g0 = gather(base);
    s.g1 = gather(base + 16u);
    s.g2 = gather(base + 32u);
    s.g3 = gather(base + 48u);
    if OB > 1u {
        s.g4 = gather(base + 64u);
        s.g5 = gather(base + 80u);
        s.g6 = gather(base + 96u);
        s.g7 = gather(base + 112u);
    }
    if OB > 2u {
        s.g8 = gather(base + 128u);
        s.g9 = gather(base + 144u);
        s.g10 = gather(base + 160u);
        s.g11 = gather(base + 176u);
        s.g12 = gather(base + 192u);
        s.g13 = gather(base + 208u);
        s.g14 = gather(base + 224u);
        s.g15 = gather(base + 240u);
    }
    return s;
}

// Input row i of the window (columns x - 1 .. x + 2) times B.
fn wino_row_of(d0: vec4<f32>, d1: vec4<f32>, d2: vec4<f32>, d3: vec4<f32>) -> Quad {
    return Quad(d0 - d2, d1 + d2, d2 - d1, d1 - d3);
}

// Add input block `cb` of cat(a, b) (conv3x3_rows.wgsl's `window4`) to the transformed tiles
// m<t><j> (tile t from the top, output block j) whose top-left output is (x, y0): the window's
// columns are fetched once, each of its rows transformed once, and each position's weights,
// taken from the lanes once, go to both tiles before the next position's. The body is unrolled
// per OB, the overrides dropping the others: 4 x 2 x 16 products of a 4x4 and a vec4 at most
// (the 8 transformed tiles, 128 vec4s, stay in the stack between blocks), in two basic blocks of
// two tile rows each (conv_common.wgsl's `once`: one block takes 2.3x the compile time). It is
// generated (tests/engine/generated.rs). One loop runs it over both sources' blocks, so LLVM
// compiles it once.
// ---- generated: wino_step ----
fn wino_step(m00: ptr<function, Wino>, m01: ptr<function, Wino>, m02: ptr<function, Wino>, m03: ptr<function, Wino>, m10: ptr<function, Wino>, m11: ptr<function, Wino>, m12: ptr<function, Wino>, m13: ptr<function, Wino>, cb: u32, w: u32, x: i32, y0: i32) {
    let k = window4(cb, x, y0);
    let k0 = k.k0;
    let k1 = k.k1;
    let k2 = k.k2;
    let k3 = k.k3;
    let e0 = wino_row_of(k0.v0, k1.v0, k2.v0, k3.v0);
    let e1 = wino_row_of(k0.v1, k1.v1, k2.v1, k3.v1);
    let e2 = wino_row_of(k0.v2, k1.v2, k2.v2, k3.v2);
    let e3 = wino_row_of(k0.v3, k1.v3, k2.v3, k3.v3);
    let e4 = wino_row_of(k0.v4, k1.v4, k2.v4, k3.v4);
    let e5 = wino_row_of(k0.v5, k1.v5, k2.v5, k3.v5);
    let v0 = wino_v(e0, e1, e2, e3);
    let v1 = wino_v(e2, e3, e4, e5);
    let g = wino_gather(w + cb * 64u * OB);
    // Position p = 4 i + c of each tile (Wino's r<i>.c<c>), block by block; tile rows 0
    // and 1, then 2 and 3, each pair in a loop that runs once: a basic block of its own
    // for LLVM (conv_common.wgsl's `once`).
    if OB == 1u {
        loop {
            { let u = ob1_0(g.g0);
              (*m00).r0.c0 = mac((*m00).r0.c0, u, v0.r0.c0); (*m10).r0.c0 = mac((*m10).r0.c0, u, v1.r0.c0); }
            { let u = ob1_1(g.g0);
              (*m00).r0.c1 = mac((*m00).r0.c1, u, v0.r0.c1); (*m10).r0.c1 = mac((*m10).r0.c1, u, v1.r0.c1); }
            { let u = ob1_2(g.g0);
              (*m00).r0.c2 = mac((*m00).r0.c2, u, v0.r0.c2); (*m10).r0.c2 = mac((*m10).r0.c2, u, v1.r0.c2); }
            { let u = ob1_3(g.g0);
              (*m00).r0.c3 = mac((*m00).r0.c3, u, v0.r0.c3); (*m10).r0.c3 = mac((*m10).r0.c3, u, v1.r0.c3); }
            { let u = ob1_0(g.g1);
              (*m00).r1.c0 = mac((*m00).r1.c0, u, v0.r1.c0); (*m10).r1.c0 = mac((*m10).r1.c0, u, v1.r1.c0); }
            { let u = ob1_1(g.g1);
              (*m00).r1.c1 = mac((*m00).r1.c1, u, v0.r1.c1); (*m10).r1.c1 = mac((*m10).r1.c1, u, v1.r1.c1); }
            { let u = ob1_2(g.g1);
              (*m00).r1.c2 = mac((*m00).r1.c2, u, v0.r1.c2); (*m10).r1.c2 = mac((*m10).r1.c2, u, v1.r1.c2); }
            { let u = ob1_3(g.g1);
              (*m00).r1.c3 = mac((*m00).r1.c3, u, v0.r1.c3); (*m10).r1.c3 = mac((*m10).r1.c3, u, v1.r1.c3); }
            continuing { break if once(); }
        }
        loop {
            { let u = ob1_0(g.g2);
              (*m00).r2.c0 = mac((*m00).r2.c0, u, v0.r2.c0); (*m10).r2.c0 = mac((*m10).r2.c0, u, v1.r2.c0); }
            { let u = ob1_1(g.g2);
              (*m00).r2.c1 = mac((*m00).r2.c1, u, v0.r2.c1); (*m10).r2.c1 = mac((*m10).r2.c1, u, v1.r2.c1); }
            { let u = ob1_2(g.g2);
              (*m00).r2.c2 = mac((*m00).r2.c2, u, v0.r2.c2); (*m10).r2.c2 = mac((*m10).r2.c2, u, v1.r2.c2); }
            { let u = ob1_3(g.g2);
              (*m00).r2.c3 = mac((*m00).r2.c3, u, v0.r2.c3); (*m10).r2.c3 = mac((*m10).r2.c3, u, v1.r2.c3); }
            { let u = ob1_0(g.g3);
              (*m00).r3.c0 = mac((*m00).r3.c0, u, v0.r3.c0); (*m10).r3.c0 = mac((*m10).r3.c0, u, v1.r3.c0); }
            { let u = ob1_1(g.g3);
              (*m00).r3.c1 = mac((*m00).r3.c1, u, v0.r3.c1); (*m10).r3.c1 = mac((*m10).r3.c1, u, v1.r3.c1); }
            { let u = ob1_2(g.g3);
              (*m00).r3.c2 = mac((*m00).r3.c2, u, v0.r3.c2); (*m10).r3.c2 = mac((*m10).r3.c2, u, v1.r3.c2); }
            { let u = ob1_3(g.g3);
              (*m00).r3.c3 = mac((*m00).r3.c3, u, v0.r3.c3); (*m10).r3.c3 = mac((*m10).r3.c3, u, v1.r3.c3); }
            continuing { break if once(); }
        }
    } else if OB == 2u {
        loop {
            { let u = ob2_00(g.g0);
              (*m00).r0.c0 = mac((*m00).r0.c0, u, v0.r0.c0); (*m10).r0.c0 = mac((*m10).r0.c0, u, v1.r0.c0); }
            { let u = ob2_01(g.g0);
              (*m01).r0.c0 = mac((*m01).r0.c0, u, v0.r0.c0); (*m11).r0.c0 = mac((*m11).r0.c0, u, v1.r0.c0); }
            { let u = ob2_10(g.g0);
              (*m00).r0.c1 = mac((*m00).r0.c1, u, v0.r0.c1); (*m10).r0.c1 = mac((*m10).r0.c1, u, v1.r0.c1); }
            { let u = ob2_11(g.g0);
              (*m01).r0.c1 = mac((*m01).r0.c1, u, v0.r0.c1); (*m11).r0.c1 = mac((*m11).r0.c1, u, v1.r0.c1); }
            { let u = ob2_00(g.g1);
              (*m00).r0.c2 = mac((*m00).r0.c2, u, v0.r0.c2); (*m10).r0.c2 = mac((*m10).r0.c2, u, v1.r0.c2); }
            { let u = ob2_01(g.g1);
              (*m01).r0.c2 = mac((*m01).r0.c2, u, v0.r0.c2); (*m11).r0.c2 = mac((*m11).r0.c2, u, v1.r0.c2); }
            { let u = ob2_10(g.g1);
              (*m00).r0.c3 = mac((*m00).r0.c3, u, v0.r0.c3); (*m10).r0.c3 = mac((*m10).r0.c3, u, v1.r0.c3); }
            { let u = ob2_11(g.g1);
              (*m01).r0.c3 = mac((*m01).r0.c3, u, v0.r0.c3); (*m11).r0.c3 = mac((*m11).r0.c3, u, v1.r0.c3); }
            { let u = ob2_00(g.g2);
              (*m00).r1.c0 = mac((*m00).r1.c0, u, v0.r1.c0); (*m10).r1.c0 = mac((*m10).r1.c0, u, v1.r1.c0); }
            { let u = ob2_01(g.g2);
              (*m01).r1.c0 = mac((*m01).r1.c0, u, v0.r1.c0); (*m11).r1.c0 = mac((*m11).r1.c0, u, v1.r1.c0); }
            { let u = ob2_10(g.g2);
              (*m00).r1.c1 = mac((*m00).r1.c1, u, v0.r1.c1); (*m10).r1.c1 = mac((*m10).r1.c1, u, v1.r1.c1); }
            { let u = ob2_11(g.g2);
              (*m01).r1.c1 = mac((*m01).r1.c1, u, v0.r1.c1); (*m11).r1.c1 = mac((*m11).r1.c1, u, v1.r1.c1); }
            { let u = ob2_00(g.g3);
              (*m00).r1.c2 = mac((*m00).r1.c2, u, v0.r1.c2); (*m10).r1.c2 = mac((*m10).r1.c2, u, v1.r1.c2); }
            { let u = ob2_01(g.g3);
              (*m01).r1.c2 = mac((*m01).r1.c2, u, v0.r1.c2); (*m11).r1.c2 = mac((*m11).r1.c2, u, v1.r1.c2); }
            { let u = ob2_10(g.g3);
              (*m00).r1.c3 = mac((*m00).r1.c3, u, v0.r1.c3); (*m10).r1.c3 = mac((*m10).r1.c3, u, v1.r1.c3); }
            { let u = ob2_11(g.g3);
              (*m01).r1.c3 = mac((*m01).r1.c3, u, v0.r1.c3); (*m11).r1.c3 = mac((*m11).r1.c3, u, v1.r1.c3); }
            continuing { break if once(); }
        }
        loop {
            { let u = ob2_00(g.g4);
              (*m00).r2.c0 = mac((*m00).r2.c0, u, v0.r2.c0); (*m10).r2.c0 = mac((*m10).r2.c0, u, v1.r2.c0); }
            { let u = ob2_01(g.g4);
              (*m01).r2.c0 = mac((*m01).r2.c0, u, v0.r2.c0); (*m11).r2.c0 = mac((*m11).r2.c0, u, v1.r2.c0); }
            { let u = ob2_10(g.g4);
              (*m00).r2.c1 = mac((*m00).r2.c1, u, v0.r2.c1); (*m10).r2.c1 = mac((*m10).r2.c1, u, v1.r2.c1); }
            { let u = ob2_11(g.g4);
              (*m01).r2.c1 = mac((*m01).r2.c1, u, v0.r2.c1); (*m11).r2.c1 = mac((*m11).r2.c1, u, v1.r2.c1); }
            { let u = ob2_00(g.g5);
              (*m00).r2.c2 = mac((*m00).r2.c2, u, v0.r2.c2); (*m10).r2.c2 = mac((*m10).r2.c2, u, v1.r2.c2); }
            { let u = ob2_01(g.g5);
              (*m01).r2.c2 = mac((*m01).r2.c2, u, v0.r2.c2); (*m11).r2.c2 = mac((*m11).r2.c2, u, v1.r2.c2); }
            { let u = ob2_10(g.g5);
              (*m00).r2.c3 = mac((*m00).r2.c3, u, v0.r2.c3); (*m10).r2.c3 = mac((*m10).r2.c3, u, v1.r2.c3); }
            { let u = ob2_11(g.g5);
              (*m01).r2.c3 = mac((*m01).r2.c3, u, v0.r2.c3); (*m11).r2.c3 = mac((*m11).r2.c3, u, v1.r2.c3); }
            { let u = ob2_00(g.g6);
              (*m00).r3.c0 = mac((*m00).r3.c0, u, v0.r3.c0); (*m10).r3.c0 = mac((*m10).r3.c0, u, v1.r3.c0); }
            { let u = ob2_01(g.g6);
              (*m01).r3.c0 = mac((*m01).r3.c0, u, v0.r3.c0); (*m11).r3.c0 = mac((*m11).r3.c0, u, v1.r3.c0); }
            { let u = ob2_10(g.g6);
              (*m00).r3.c1 = mac((*m00).r3.c1, u, v0.r3.c1); (*m10).r3.c1 = mac((*m10).r3.c1, u, v1.r3.c1); }
            { let u = ob2_11(g.g6);
              (*m01).r3.c1 = mac((*m01).r3.c1, u, v0.r3.c1); (*m11).r3.c1 = mac((*m11).r3.c1, u, v1.r3.c1); }
            { let u = ob2_00(g.g7);
              (*m00).r3.c2 = mac((*m00).r3.c2, u, v0.r3.c2); (*m10).r3.c2 = mac((*m10).r3.c2, u, v1.r3.c2); }
            { let u = ob2_01(g.g7);
              (*m01).r3.c2 = mac((*m01).r3.c2, u, v0.r3.c2); (*m11).r3.c2 = mac((*m11).r3.c2, u, v1.r3.c2); }
            { let u = ob2_10(g.g7);
              (*m00).r3.c3 = mac((*m00).r3.c3, u, v0.r3.c3); (*m10).r3.c3 = mac((*m10).r3.c3, u, v1.r3.c3); }
            { let u = ob2_11(g.g7);
              (*m01).r3.c3 = mac((*m01).r3.c3, u, v0.r3.c3); (*m11).r3.c3 = mac((*m11).r3.c3, u, v1.r3.c3); }
            continuing { break if once(); }
        }
    } else {
        loop {
            { let u = ob4_0(g.g0);
              (*m00).r0.c0 = mac((*m00).r0.c0, u, v0.r0.c0); (*m10).r0.c0 = mac((*m10).r0.c0, u, v1.r0.c0); }
            { let u = ob4_1(g.g0);
              (*m01).r0.c0 = mac((*m01).r0.c0, u, v0.r0.c0); (*m11).r0.c0 = mac((*m11).r0.c0, u, v1.r0.c0); }
            { let u = ob4_2(g.g0);
              (*m02).r0.c0 = mac((*m02).r0.c0, u, v0.r0.c0); (*m12).r0.c0 = mac((*m12).r0.c0, u, v1.r0.c0); }
            { let u = ob4_3(g.g0);
              (*m03).r0.c0 = mac((*m03).r0.c0, u, v0.r0.c0); (*m13).r0.c0 = mac((*m13).r0.c0, u, v1.r0.c0); }
            { let u = ob4_0(g.g1);
              (*m00).r0.c1 = mac((*m00).r0.c1, u, v0.r0.c1); (*m10).r0.c1 = mac((*m10).r0.c1, u, v1.r0.c1); }
            { let u = ob4_1(g.g1);
              (*m01).r0.c1 = mac((*m01).r0.c1, u, v0.r0.c1); (*m11).r0.c1 = mac((*m11).r0.c1, u, v1.r0.c1); }
            { let u = ob4_2(g.g1);
              (*m02).r0.c1 = mac((*m02).r0.c1, u, v0.r0.c1); (*m12).r0.c1 = mac((*m12).r0.c1, u, v1.r0.c1); }
            { let u = ob4_3(g.g1);
              (*m03).r0.c1 = mac((*m03).r0.c1, u, v0.r0.c1); (*m13).r0.c1 = mac((*m13).r0.c1, u, v1.r0.c1); }
            { let u = ob4_0(g.g2);
              (*m00).r0.c2 = mac((*m00).r0.c2, u, v0.r0.c2); (*m10).r0.c2 = mac((*m10).r0.c2, u, v1.r0.c2); }
            { let u = ob4_1(g.g2);
              (*m01).r0.c2 = mac((*m01).r0.c2, u, v0.r0.c2); (*m11).r0.c2 = mac((*m11).r0.c2, u, v1.r0.c2); }
            { let u = ob4_2(g.g2);
              (*m02).r0.c2 = mac((*m02).r0.c2, u, v0.r0.c2); (*m12).r0.c2 = mac((*m12).r0.c2, u, v1.r0.c2); }
            { let u = ob4_3(g.g2);
              (*m03).r0.c2 = mac((*m03).r0.c2, u, v0.r0.c2); (*m13).r0.c2 = mac((*m13).r0.c2, u, v1.r0.c2); }
            { let u = ob4_0(g.g3);
              (*m00).r0.c3 = mac((*m00).r0.c3, u, v0.r0.c3); (*m10).r0.c3 = mac((*m10).r0.c3, u, v1.r0.c3); }
            { let u = ob4_1(g.g3);
              (*m01).r0.c3 = mac((*m01).r0.c3, u, v0.r0.c3); (*m11).r0.c3 = mac((*m11).r0.c3, u, v1.r0.c3); }
            { let u = ob4_2(g.g3);
              (*m02).r0.c3 = mac((*m02).r0.c3, u, v0.r0.c3); (*m12).r0.c3 = mac((*m12).r0.c3, u, v1.r0.c3); }
            { let u = ob4_3(g.g3);
              (*m03).r0.c3 = mac((*m03).r0.c3, u, v0.r0.c3); (*m13).r0.c3 = mac((*m13).r0.c3, u, v1.r0.c3); }
            { let u = ob4_0(g.g4);
              (*m00).r1.c0 = mac((*m00).r1.c0, u, v0.r1.c0); (*m10).r1.c0 = mac((*m10).r1.c0, u, v1.r1.c0); }
            { let u = ob4_1(g.g4);
              (*m01).r1.c0 = mac((*m01).r1.c0, u, v0.r1.c0); (*m11).r1.c0 = mac((*m11).r1.c0, u, v1.r1.c0); }
            { let u = ob4_2(g.g4);
              (*m02).r1.c0 = mac((*m02).r1.c0, u, v0.r1.c0); (*m12).r1.c0 = mac((*m12).r1.c0, u, v1.r1.c0); }
            { let u = ob4_3(g.g4);
              (*m03).r1.c0 = mac((*m03).r1.c0, u, v0.r1.c0); (*m13).r1.c0 = mac((*m13).r1.c0, u, v1.r1.c0); }
            { let u = ob4_0(g.g5);
              (*m00).r1.c1 = mac((*m00).r1.c1, u, v0.r1.c1); (*m10).r1.c1 = mac((*m10).r1.c1, u, v1.r1.c1); }
            { let u = ob4_1(g.g5);
              (*m01).r1.c1 = mac((*m01).r1.c1, u, v0.r1.c1); (*m11).r1.c1 = mac((*m11).r1.c1, u, v1.r1.c1); }
            { let u = ob4_2(g.g5);
              (*m02).r1.c1 = mac((*m02).r1.c1, u, v0.r1.c1); (*m12).r1.c1 = mac((*m12).r1.c1, u, v1.r1.c1); }
            { let u = ob4_3(g.g5);
              (*m03).r1.c1 = mac((*m03).r1.c1, u, v0.r1.c1); (*m13).r1.c1 = mac((*m13).r1.c1, u, v1.r1.c1); }
            { let u = ob4_0(g.g6);
              (*m00).r1.c2 = mac((*m00).r1.c2, u, v0.r1.c2); (*m10).r1.c2 = mac((*m10).r1.c2, u, v1.r1.c2); }
            { let u = ob4_1(g.g6);
              (*m01).r1.c2 = mac((*m01).r1.c2, u, v0.r1.c2); (*m11).r1.c2 = mac((*m11).r1.c2, u, v1.r1.c2); }
            { let u = ob4_2(g.g6);
              (*m02).r1.c2 = mac((*m02).r1.c2, u, v0.r1.c2); (*m12).r1.c2 = mac((*m12).r1.c2, u, v1.r1.c2); }
            { let u = ob4_3(g.g6);
              (*m03).r1.c2 = mac((*m03).r1.c2, u, v0.r1.c2); (*m13).r1.c2 = mac((*m13).r1.c2, u, v1.r1.c2); }
            { let u = ob4_0(g.g7);
              (*m00).r1.c3 = mac((*m00).r1.c3, u, v0.r1.c3); (*m10).r1.c3 = mac((*m10).r1.c3, u, v1.r1.c3); }
            { let u = ob4_1(g.g7);
              (*m01).r1.c3 = mac((*m01).r1.c3, u, v0.r1.c3); (*m11).r1.c3 = mac((*m11).r1.c3, u, v1.r1.c3); }
            { let u = ob4_2(g.g7);
              (*m02).r1.c3 = mac((*m02).r1.c3, u, v0.r1.c3); (*m12).r1.c3 = mac((*m12).r1.c3, u, v1.r1.c3); }
            { let u = ob4_3(g.g7);
              (*m03).r1.c3 = mac((*m03).r1.c3, u, v0.r1.c3); (*m13).r1.c3 = mac((*m13).r1.c3, u, v1.r1.c3); }
            continuing { break if once(); }
        }
        loop {
            { let u = ob4_0(g.g8);
              (*m00).r2.c0 = mac((*m00).r2.c0, u, v0.r2.c0); (*m10).r2.c0 = mac((*m10).r2.c0, u, v1.r2.c0); }
            { let u = ob4_1(g.g8);
              (*m01).r2.c0 = mac((*m01).r2.c0, u, v0.r2.c0); (*m11).r2.c0 = mac((*m11).r2.c0, u, v1.r2.c0); }
            { let u = ob4_2(g.g8);
              (*m02).r2.c0 = mac((*m02).r2.c0, u, v0.r2.c0); (*m12).r2.c0 = mac((*m12).r2.c0, u, v1.r2.c0); }
            { let u = ob4_3(g.g8);
              (*m03).r2.c0 = mac((*m03).r2.c0, u, v0.r2.c0); (*m13).r2.c0 = mac((*m13).r2.c0, u, v1.r2.c0); }
            { let u = ob4_0(g.g9);
              (*m00).r2.c1 = mac((*m00).r2.c1, u, v0.r2.c1); (*m10).r2.c1 = mac((*m10).r2.c1, u, v1.r2.c1); }
            { let u = ob4_1(g.g9);
              (*m01).r2.c1 = mac((*m01).r2.c1, u, v0.r2.c1); (*m11).r2.c1 = mac((*m11).r2.c1, u, v1.r2.c1); }
            { let u = ob4_2(g.g9);
              (*m02).r2.c1 = mac((*m02).r2.c1, u, v0.r2.c1); (*m12).r2.c1 = mac((*m12).r2.c1, u, v1.r2.c1); }
            { let u = ob4_3(g.g9);
              (*m03).r2.c1 = mac((*m03).r2.c1, u, v0.r2.c1); (*m13).r2.c1 = mac((*m13).r2.c1, u, v1.r2.c1); }
            { let u = ob4_0(g.g10);
              (*m00).r2.c2 = mac((*m00).r2.c2, u, v0.r2.c2); (*m10).r2.c2 = mac((*m10).r2.c2, u, v1.r2.c2); }
            { let u = ob4_1(g.g10);
              (*m01).r2.c2 = mac((*m01).r2.c2, u, v0.r2.c2); (*m11).r2.c2 = mac((*m11).r2.c2, u, v1.r2.c2); }
            { let u = ob4_2(g.g10);
              (*m02).r2.c2 = mac((*m02).r2.c2, u, v0.r2.c2); (*m12).r2.c2 = mac((*m12).r2.c2, u, v1.r2.c2); }
            { let u = ob4_3(g.g10);
              (*m03).r2.c2 = mac((*m03).r2.c2, u, v0.r2.c2); (*m13).r2.c2 = mac((*m13).r2.c2, u, v1.r2.c2); }
            { let u = ob4_0(g.g11);
              (*m00).r2.c3 = mac((*m00).r2.c3, u, v0.r2.c3); (*m10).r2.c3 = mac((*m10).r2.c3, u, v1.r2.c3); }
            { let u = ob4_1(g.g11);
              (*m01).r2.c3 = mac((*m01).r2.c3, u, v0.r2.c3); (*m11).r2.c3 = mac((*m11).r2.c3, u, v1.r2.c3); }
            { let u = ob4_2(g.g11);
              (*m02).r2.c3 = mac((*m02).r2.c3, u, v0.r2.c3); (*m12).r2.c3 = mac((*m12).r2.c3, u, v1.r2.c3); }
            { let u = ob4_3(g.g11);
              (*m03).r2.c3 = mac((*m03).r2.c3, u, v0.r2.c3); (*m13).r2.c3 = mac((*m13).r2.c3, u, v1.r2.c3); }
            { let u = ob4_0(g.g12);
              (*m00).r3.c0 = mac((*m00).r3.c0, u, v0.r3.c0); (*m10).r3.c0 = mac((*m10).r3.c0, u, v1.r3.c0); }
            { let u = ob4_1(g.g12);
              (*m01).r3.c0 = mac((*m01).r3.c0, u, v0.r3.c0); (*m11).r3.c0 = mac((*m11).r3.c0, u, v1.r3.c0); }
            { let u = ob4_2(g.g12);
              (*m02).r3.c0 = mac((*m02).r3.c0, u, v0.r3.c0); (*m12).r3.c0 = mac((*m12).r3.c0, u, v1.r3.c0); }
            { let u = ob4_3(g.g12);
              (*m03).r3.c0 = mac((*m03).r3.c0, u, v0.r3.c0); (*m13).r3.c0 = mac((*m13).r3.c0, u, v1.r3.c0); }
            { let u = ob4_0(g.g13);
              (*m00).r3.c1 = mac((*m00).r3.c1, u, v0.r3.c1); (*m10).r3.c1 = mac((*m10).r3.c1, u, v1.r3.c1); }
            { let u = ob4_1(g.g13);
              (*m01).r3.c1 = mac((*m01).r3.c1, u, v0.r3.c1); (*m11).r3.c1 = mac((*m11).r3.c1, u, v1.r3.c1); }
            { let u = ob4_2(g.g13);
              (*m02).r3.c1 = mac((*m02).r3.c1, u, v0.r3.c1); (*m12).r3.c1 = mac((*m12).r3.c1, u, v1.r3.c1); }
            { let u = ob4_3(g.g13);
              (*m03).r3.c1 = mac((*m03).r3.c1, u, v0.r3.c1); (*m13).r3.c1 = mac((*m13).r3.c1, u, v1.r3.c1); }
            { let u = ob4_0(g.g14);
              (*m00).r3.c2 = mac((*m00).r3.c2, u, v0.r3.c2); (*m10).r3.c2 = mac((*m10).r3.c2, u, v1.r3.c2); }
            { let u = ob4_1(g.g14);
              (*m01).r3.c2 = mac((*m01).r3.c2, u, v0.r3.c2); (*m11).r3.c2 = mac((*m11).r3.c2, u, v1.r3.c2); }
            { let u = ob4_2(g.g14);
              (*m02).r3.c2 = mac((*m02).r3.c2, u, v0.r3.c2); (*m12).r3.c2 = mac((*m12).r3.c2, u, v1.r3.c2); }
            { let u = ob4_3(g.g14);
              (*m03).r3.c2 = mac((*m03).r3.c2, u, v0.r3.c2); (*m13).r3.c2 = mac((*m13).r3.c2, u, v1.r3.c2); }
            { let u = ob4_0(g.g15);
              (*m00).r3.c3 = mac((*m00).r3.c3, u, v0.r3.c3); (*m10).r3.c3 = mac((*m10).r3.c3, u, v1.r3.c3); }
            { let u = ob4_1(g.g15);
              (*m01).r3.c3 = mac((*m01).r3.c3, u, v0.r3.c3); (*m11).r3.c3 = mac((*m11).r3.c3, u, v1.r3.c3); }
            { let u = ob4_2(g.g15);
              (*m02).r3.c3 = mac((*m02).r3.c3, u, v0.r3.c3); (*m12).r3.c3 = mac((*m12).r3.c3, u, v1.r3.c3); }
            { let u = ob4_3(g.g15);
              (*m03).r3.c3 = mac((*m03).r3.c3, u, v0.r3.c3); (*m13).r3.c3 = mac((*m13).r3.c3, u, v1.r3.c3); }
            continuing { break if once(); }
        }
    }
}
// ---- end generated ----

// `winograd` with its weights loaded across the subgroup, in one-dimensional workgroups of WG_X x
// WG_Y invocations (subgroup builtins need them) laid out as `winograd`'s.
@compute @workgroup_size(64, 1, 1)
fn winograd_lanes(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_id) l: vec3<u32>, @builtin(subgroup_invocation_id) sg: u32) {
    lane = sg;
    let x = (wg.x * WG_X + l.x % WG_X) * 2u;
    let y0 = (wg.y * WG_Y + l.x / WG_X) * ROWS;
    let ob0 = params.ob0 + wg.z * OB;
    let w = params.weight_texel + wg.z * params.group_stride;
    if ob0 >= params.cout4 {
        return;
    }
    // Lanes past the edge load weights for the others (a broadcast from an inactive lane is
    // undefined) and store nothing.
    let inside = x < params.width && y0 < params.height;
    if !subgroupAny(inside) {
        return;
    }
    let z = Quad(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
    var m00 = Wino(z, z, z, z);
    var m01 = m00;
    var m02 = m00;
    var m03 = m00;
    var m10 = m00;
    var m11 = m00;
    var m12 = m00;
    var m13 = m00;
    let xi = i32(x);
    let yi = i32(y0);
    // Source a's blocks, then b's, in one loop (none of b on a reset frame's hidden state).
    let blocks = params.cin4_a + select(0u, params.cin4_b, SOURCE_B);
    for (var c = 0u; c < blocks; c++) {
        wino_step(&m00, &m01, &m02, &m03, &m10, &m11, &m12, &m13, c, w, xi, yi);
    }
    if !inside {
        return;
    }
    let bias_at = w + params.cin4_total * 64u * OB;
    let second = OB > 1u && ob0 + 1u < params.cout4;
    let b = texel_biases(bias_at);
    let b0 = b.c0;
    let b1 = b.c1;
    let b2 = b.c2;
    let b3 = b.c3;
    let third = OB > 2u && ob0 + 2u < params.cout4;
    let fourth = OB > 2u && ob0 + 3u < params.cout4;
    // Tile t's outputs at rows y0 + 2t, y0 + 2t + 1 (wino_store drops a row past the bottom).
    wino_store(m00, b0, x, y0, ob0);
    if second { wino_store(m01, b1, x, y0, ob0 + 1u); }
    if third { wino_store(m02, b2, x, y0, ob0 + 2u); }
    if fourth { wino_store(m03, b3, x, y0, ob0 + 3u); }
    if y0 + 2u < params.height {
        wino_store(m10, b0, x, y0 + 2u, ob0);
        if second { wino_store(m11, b1, x, y0 + 2u, ob0 + 1u); }
        if third { wino_store(m12, b2, x, y0 + 2u, ob0 + 2u); }
        if fourth { wino_store(m13, b3, x, y0 + 2u, ob0 + 3u); }
    }
}

// Winograd F(4x4, 3x3) with its weights loaded across the subgroup: the entry point
// `winograd4_lanes` (kernels::Method::Winograd4Lanes), for CPU drivers with subgroups of at
// least 8 lanes. Appended, with conv3x3_rows.wgsl, conv3x3_wino.wgsl and the gathers
// (conv3x3_gather16.wgsl, or conv3x3_gather8.wgsl on 8 lanes), to the conv module that runs
// two-column lanes tiles; it uses their declarations (Quad, mac, lane, Column, Gather, gather,
// the ob<OB>_<k> broadcasts, the overrides).
//
// An invocation computes one 4x4 output tile (ROWS = 4) of 4 columns for OB output blocks (1, 2
// or 4). Each input block costs 6 columns of 6 fetched texels, their
// transforms V = B^T d B (additions and multiplies by 2, 4, 5), and per tile and output block 36
// products of a 6x6 weight matrix with a vec4: 144 multiply-adds per 16 outputs and input block
// where F(2x2, 3x3) takes 256 and the direct sum 576, and 60 fetched texels per 32 outputs where
// `winograd_lanes` fetches 40 per 16. The price is rounding: the transforms' coefficients (up to
// 8 in A, 5 in B, 1/24 in G) lose a few more bits than F(2x2)'s (within the golden tolerance,
// tests/engine/kernels.rs).
//
// Its weights are texels of the plan's weight texture (binding 7, kernels::ConvPlan), not the
// weight buffer: on lavapipe a storage- or uniform-buffer load at a per-lane address is a loop
// over the lanes, a texel load one vector gather, and the gathers were about 40% of this kernel's
// time from a storage buffer (`docs/perf/lavapipe-2026-11-25-s23.log`). They sit as `winograd_lanes` reads them
// with 36 positions for 16: input block cb, position p = 6 i + c, input lane l, output block j at
// texel w + ((cb * 36 + p) * 4 + l) * OB + j (w = params.weight_texel + group z * group_stride),
// then OB biases; each 16 of them are gathered over the lanes (`gather`) just before their
// positions' products and taken from the lanes by subgroupBroadcast (the ob1_*, ob2_*, ob4_*).
//
// With points 0, 1, -1, 2, -2 and infinity (Lavin and Gray, 2016):
//   B^T = [4 0 -5 0 1 0; 0 -4 -4 1 1 0; 0 4 -4 -1 1 0; 0 -2 -1 2 1 0; 0 2 -1 -2 1 0; 0 4 0 -5 0 1]
//   A^T = [1 1 1 1 1 0; 0 1 -1 2 -2 0; 0 1 1 4 4 0; 0 1 -1 8 -8 1]
// and G in kernels::winograd4_taps.

// The weight texture's type: sampled, or read-only storage where the sources are (Kernels
// rewrites this alias and `weight_texel`'s load with the sources', kernels::STORAGE_SOURCES).
alias WeightTexels = texture_2d<f32>;
@group(0) @binding(7) var weight_texels: WeightTexels;
// Texels per row of the weight texture (kernels::WEIGHT_TEXELS_WIDTH).
override WEIGHT_TEXELS_WIDTH: u32 = 4096u;

// Texel i of the weight texture, in rows of WEIGHT_TEXELS_WIDTH.
fn weight_texel(i: u32) -> vec4<f32> {
    return textureLoad(weight_texels, vec2<u32>(i % WEIGHT_TEXELS_WIDTH, i / WEIGHT_TEXELS_WIDTH), 0);
}

// The OB biases of a Winograd lanes group from texel `at` on (block j in c<j>; the blocks past
// OB repeat block 0's).
fn texel_biases(at: u32) -> Quad {
    let b0 = weight_texel(at);
    var b = Quad(b0, b0, b0, b0);
    if OB > 1u {
        b.c1 = weight_texel(at + 1u);
    }
    if OB > 2u {
        b.c2 = weight_texel(at + 2u);
        b.c3 = weight_texel(at + 3u);
    }
    return b;
}

// Six vec4s along a row of a 6x6 tile (input row after d B, or a row of V or M).
struct Hex {
    c0: vec4<f32>,
    c1: vec4<f32>,
    c2: vec4<f32>,
    c3: vec4<f32>,
    c4: vec4<f32>,
    c5: vec4<f32>,
}

// A 6x6 tile in the transformed domain (V of one input block, or M of one output block).
struct Wino6 {
    r0: Hex,
    r1: Hex,
    r2: Hex,
    r3: Hex,
    r4: Hex,
    r5: Hex,
}

// Six values times B: the row (d0 .. d5) B, or a column of B^T (d B) read down the rows.
fn hex_b(d0: vec4<f32>, d1: vec4<f32>, d2: vec4<f32>, d3: vec4<f32>, d4: vec4<f32>, d5: vec4<f32>) -> Hex {
    let a = fma(vec4<f32>(-4.0), d2, d4);
    let b = fma(vec4<f32>(-4.0), d1, d3);
    let c = d4 - d2;
    let e = 2.0 * (d3 - d1);
    return Hex(fma(vec4<f32>(4.0), d0, fma(vec4<f32>(-5.0), d2, d4)), a + b, a - b, c + e, c - e, fma(vec4<f32>(4.0), d1, fma(vec4<f32>(-5.0), d3, d5)));
}

// V = B^T (d B) from six consecutive rows of d B.
fn wino6_v(e0: Hex, e1: Hex, e2: Hex, e3: Hex, e4: Hex, e5: Hex) -> Wino6 {
    let c0 = hex_b(e0.c0, e1.c0, e2.c0, e3.c0, e4.c0, e5.c0);
    let c1 = hex_b(e0.c1, e1.c1, e2.c1, e3.c1, e4.c1, e5.c1);
    let c2 = hex_b(e0.c2, e1.c2, e2.c2, e3.c2, e4.c2, e5.c2);
    let c3 = hex_b(e0.c3, e1.c3, e2.c3, e3.c3, e4.c3, e5.c3);
    let c4 = hex_b(e0.c4, e1.c4, e2.c4, e3.c4, e4.c4, e5.c4);
    let c5 = hex_b(e0.c5, e1.c5, e2.c5, e3.c5, e4.c5, e5.c5);
    return Wino6(
        Hex(c0.c0, c1.c0, c2.c0, c3.c0, c4.c0, c5.c0),
        Hex(c0.c1, c1.c1, c2.c1, c3.c1, c4.c1, c5.c1),
        Hex(c0.c2, c1.c2, c2.c2, c3.c2, c4.c2, c5.c2),
        Hex(c0.c3, c1.c3, c2.c3, c3.c3, c4.c3, c5.c3),
        Hex(c0.c4, c1.c4, c2.c4, c3.c4, c4.c4, c5.c4),
        Hex(c0.c5, c1.c5, c2.c5, c3.c5, c4.c5, c5.c5),
    );
}

// Six values times A: a row of M times A, or a column of (M A) read down the rows.
fn hex_a(m0: vec4<f32>, m1: vec4<f32>, m2: vec4<f32>, m3: vec4<f32>, m4: vec4<f32>, m5: vec4<f32>) -> Quad {
    let p = m1 + m2;
    let q = m1 - m2;
    let u = m3 + m4;
    let v = m3 - m4;
    return Quad(m0 + p + u, fma(vec4<f32>(2.0), v, q), fma(vec4<f32>(4.0), u, p), fma(vec4<f32>(8.0), v, q) + m5);
}

// Y = A^T M A plus the bias, stored at (x .. x + 3, y0 .. y0 + 3) where inside the output; with
// `pools` also the max of each 2x2 window, activated, into `pooled` at (x / 2 .. x / 2 + 1,
// y0 / 2 .. y0 / 2 + 1), as `store_pooled` pools (x and y0 are multiples of 4, and levels have
// even sizes, so a window is whole once its top-left pixel is inside).
fn wino4_store(m: Wino6, bias: vec4<f32>, x: u32, y0: u32, layer: u32) {
    // Row i of M A, then the columns of A^T (M A).
    let s0 = hex_a(m.r0.c0, m.r0.c1, m.r0.c2, m.r0.c3, m.r0.c4, m.r0.c5);
    let s1 = hex_a(m.r1.c0, m.r1.c1, m.r1.c2, m.r1.c3, m.r1.c4, m.r1.c5);
    let s2 = hex_a(m.r2.c0, m.r2.c1, m.r2.c2, m.r2.c3, m.r2.c4, m.r2.c5);
    let s3 = hex_a(m.r3.c0, m.r3.c1, m.r3.c2, m.r3.c3, m.r3.c4, m.r3.c5);
    let s4 = hex_a(m.r4.c0, m.r4.c1, m.r4.c2, m.r4.c3, m.r4.c4, m.r4.c5);
    let s5 = hex_a(m.r5.c0, m.r5.c1, m.r5.c2, m.r5.c3, m.r5.c4, m.r5.c5);
    // Column k of the output: o<k>.c<r> is row r.
    let o0 = hex_a(s0.c0, s1.c0, s2.c0, s3.c0, s4.c0, s5.c0);
    let o1 = hex_a(s0.c1, s1.c1, s2.c1, s3.c1, s4.c1, s5.c1);
    let o2 = hex_a(s0.c2, s1.c2, s2.c2, s3.c2, s4.c2, s5.c2);
    let o3 = hex_a(s0.c3, s1.c3, s2.c3, s3.c3, s4.c3, s5.c3);
    let h = params.height;
    let at = dst_cell(layer);
    wino4_row(x, y0, layer, at, bias + o0.c0, bias + o1.c0, bias + o2.c0, bias + o3.c0);
    if y0 + 1u < h { wino4_row(x, y0 + 1u, layer, at, bias + o0.c1, bias + o1.c1, bias + o2.c1, bias + o3.c1); }
    if y0 + 2u < h { wino4_row(x, y0 + 2u, layer, at, bias + o0.c2, bias + o1.c2, bias + o2.c2, bias + o3.c2); }
    if y0 + 3u < h { wino4_row(x, y0 + 3u, layer, at, bias + o0.c3, bias + o1.c3, bias + o2.c3, bias + o3.c3); }
    if pools() {
        let p = vec2<u32>(x / 2u, y0 / 2u);
        let right = x + 2u < params.width;
        let pat = pool_cell(layer);
        store_pool(p, pat, activate(bias + max(max(o0.c0, o1.c0), max(o0.c1, o1.c1))));
        if right { store_pool(p + vec2<u32>(1u, 0u), pat, activate(bias + max(max(o2.c0, o3.c0), max(o2.c1, o3.c1)))); }
        if y0 + 2u < h {
            store_pool(p + vec2<u32>(0u, 1u), pat, activate(bias + max(max(o0.c2, o1.c2), max(o0.c3, o1.c3))));
            if right { store_pool(p + vec2<u32>(1u, 1u), pat, activate(bias + max(max(o2.c2, o3.c2), max(o2.c3, o3.c3)))); }
        }
    }
}

// The output goes into binding 5 (`partial`) as the texture's rows, layer by layer, and the
// frame copies it into `dst` after the conv (kernels::ConvVariant::staged, CPU drivers only).
// On lavapipe a texel store of rgba32float is four loops over the lanes, one per 32-bit word,
// and a buffer store of a vec4 is one: 0.68-0.86x the time (`docs/perf/lavapipe-2026-12-01-s25.log`, `docs/perf/lavapipe-2026-12-02-s28.log`).
override OUT_BUFFER: bool = false;

// The four pixels of a row from pixel `i` of the staged buffer on, in 32-bit words (where the
// device has 64-bit integers, kernels::lanes_module_source calls conv3x3_stage64.wgsl's
// `stage_row64` instead: half the store loops).
fn stage_row(i: u32, a: vec4<f32>, b: vec4<f32>, c: vec4<f32>, d: vec4<f32>) {
    partial[i] = a;
    partial[i + 1u] = b;
    partial[i + 2u] = c;
    partial[i + 3u] = d;
}

// One output row of a 4x4 tile at (x .. x + 3, y) of block `layer` (its cell `at`), columns past
// the right edge dropped.
fn wino4_row(x: u32, y: u32, layer: u32, at: vec3<u32>, a: vec4<f32>, b: vec4<f32>, c: vec4<f32>, d: vec4<f32>) {
    let w = params.width;
    if OUT_BUFFER {
        // A staged level is a multiple of 16 wide, so the row's four pixels are inside.
        stage_row((layer * params.height + y) * w + x, activate(a), activate(b), activate(c), activate(d));
    } else {
        store_dst(vec2<u32>(x, y), at, activate(a));
        if x + 1u < w { store_dst(vec2<u32>(x + 1u, y), at, activate(b)); }
        if x + 2u < w { store_dst(vec2<u32>(x + 2u, y), at, activate(c)); }
        if x + 3u < w { store_dst(vec2<u32>(x + 3u, y), at, activate(d)); }
    }
}

// The 6 columns of an input window, x - 1 .. x + 4.
struct Window6 {
    k0: Column,
    k1: Column,
    k2: Column,
    k3: Column,
    k4: Column,
    k5: Column,
}

fn window6(t: Source, mode: u32, layer: u32, x: i32, y0: i32) -> Window6 {
    let at = cell(mode, layer);
    return Window6(column(t, mode, x - 1, y0, at), column(t, mode, x, y0, at), column(t, mode, x + 1, y0, at), column(t, mode, x + 2, y0, at), column(t, mode, x + 3, y0, at), column(t, mode, x + 4, y0, at));
}

// Add input block `cb` of cat(a, b) (source a's block cb, or source b's block cb - cin4_a) to
// the transformed tiles m<t><j> (tile t from the top, output block j) whose top-left output is
// (x, y0): the window's 6 columns are fetched once, each of its rows transformed once, and
// each position's weights, taken from the lanes once, go to both tiles before the next
// position's. The body is unrolled per OB, the overrides dropping the others: 36 x 4 products
// of a 4x4 and a vec4 at most (the 4 transformed tiles, 144 vec4s, stay in the stack between
// blocks), in three basic blocks of two tile rows each (`once`: one block takes twice the
// compile time). It is generated (tests/engine/generated.rs). As written it is the kernel's
// only copy of that body: one loop runs over
// both sources' blocks, the window alone chosen per source, so LLVM compiles the body once.
// The module of two-source convs runs it from a loop per source instead
// (kernels::TWO_SOURCE_LOOPS: lavapipe fetched both windows for every block).
// ---- generated: wino4_step ----
fn wino4_step(m00: ptr<function, Wino6>, m01: ptr<function, Wino6>, m02: ptr<function, Wino6>, m03: ptr<function, Wino6>, cb: u32, w: u32, x: i32, y0: i32) {
    var k: Window6;
    if !SOURCE_B || cb < params.cin4_a {
        k = window6(src_a, MODE_A, cb, x, y0);
    } else {
        k = window6(src_b, MODE_B, cb - params.cin4_a, x, y0);
    }
    let k0 = k.k0;
    let k1 = k.k1;
    let k2 = k.k2;
    let k3 = k.k3;
    let k4 = k.k4;
    let k5 = k.k5;
    let e0 = hex_b(k0.v0, k1.v0, k2.v0, k3.v0, k4.v0, k5.v0);
    let e1 = hex_b(k0.v1, k1.v1, k2.v1, k3.v1, k4.v1, k5.v1);
    let e2 = hex_b(k0.v2, k1.v2, k2.v2, k3.v2, k4.v2, k5.v2);
    let e3 = hex_b(k0.v3, k1.v3, k2.v3, k3.v3, k4.v3, k5.v3);
    let e4 = hex_b(k0.v4, k1.v4, k2.v4, k3.v4, k4.v4, k5.v4);
    let e5 = hex_b(k0.v5, k1.v5, k2.v5, k3.v5, k4.v5, k5.v5);
    let v0 = wino6_v(e0, e1, e2, e3, e4, e5);
    let base = w + cb * 144u * OB;
    // Position p = 6 i + c of the tile (Wino6's r<i>.c<c>), block by block; tile rows 0 and
    // 1, 2 and 3, 4 and 5, each pair in a loop that runs once: a basic block of its own for
    // LLVM (conv_common.wgsl's `once`).
    if OB == 1u {
        loop {
            {
            let g = gather(base + 0u);
            { let u = ob1_0(g); (*m00).r0.c0 = mac((*m00).r0.c0, u, v0.r0.c0); }
            { let u = ob1_1(g); (*m00).r0.c1 = mac((*m00).r0.c1, u, v0.r0.c1); }
            { let u = ob1_2(g); (*m00).r0.c2 = mac((*m00).r0.c2, u, v0.r0.c2); }
            { let u = ob1_3(g); (*m00).r0.c3 = mac((*m00).r0.c3, u, v0.r0.c3); }
            }
            {
            let g = gather(base + 16u);
            { let u = ob1_0(g); (*m00).r0.c4 = mac((*m00).r0.c4, u, v0.r0.c4); }
            { let u = ob1_1(g); (*m00).r0.c5 = mac((*m00).r0.c5, u, v0.r0.c5); }
            { let u = ob1_2(g); (*m00).r1.c0 = mac((*m00).r1.c0, u, v0.r1.c0); }
            { let u = ob1_3(g); (*m00).r1.c1 = mac((*m00).r1.c1, u, v0.r1.c1); }
            }
            {
            let g = gather(base + 32u);
            { let u = ob1_0(g); (*m00).r1.c2 = mac((*m00).r1.c2, u, v0.r1.c2); }
            { let u = ob1_1(g); (*m00).r1.c3 = mac((*m00).r1.c3, u, v0.r1.c3); }
            { let u = ob1_2(g); (*m00).r1.c4 = mac((*m00).r1.c4, u, v0.r1.c4); }
            { let u = ob1_3(g); (*m00).r1.c5 = mac((*m00).r1.c5, u, v0.r1.c5); }
            }
            continuing { break if once(); }
        }
        loop {
            {
            let g = gather(base + 48u);
            { let u = ob1_0(g); (*m00).r2.c0 = mac((*m00).r2.c0, u, v0.r2.c0); }
            { let u = ob1_1(g); (*m00).r2.c1 = mac((*m00).r2.c1, u, v0.r2.c1); }
            { let u = ob1_2(g); (*m00).r2.c2 = mac((*m00).r2.c2, u, v0.r2.c2); }
            { let u = ob1_3(g); (*m00).r2.c3 = mac((*m00).r2.c3, u, v0.r2.c3); }
            }
            {
            let g = gather(base + 64u);
            { let u = ob1_0(g); (*m00).r2.c4 = mac((*m00).r2.c4, u, v0.r2.c4); }
            { let u = ob1_1(g); (*m00).r2.c5 = mac((*m00).r2.c5, u, v0.r2.c5); }
            { let u = ob1_2(g); (*m00).r3.c0 = mac((*m00).r3.c0, u, v0.r3.c0); }
            { let u = ob1_3(g); (*m00).r3.c1 = mac((*m00).r3.c1, u, v0.r3.c1); }
            }
            {
            let g = gather(base + 80u);
            { let u = ob1_0(g); (*m00).r3.c2 = mac((*m00).r3.c2, u, v0.r3.c2); }
            { let u = ob1_1(g); (*m00).r3.c3 = mac((*m00).r3.c3, u, v0.r3.c3); }
            { let u = ob1_2(g); (*m00).r3.c4 = mac((*m00).r3.c4, u, v0.r3.c4); }
            { let u = ob1_3(g); (*m00).r3.c5 = mac((*m00).r3.c5, u, v0.r3.c5); }
            }
            continuing { break if once(); }
        }
        loop {
            {
            let g = gather(base + 96u);
            { let u = ob1_0(g); (*m00).r4.c0 = mac((*m00).r4.c0, u, v0.r4.c0); }
            { let u = ob1_1(g); (*m00).r4.c1 = mac((*m00).r4.c1, u, v0.r4.c1); }
            { let u = ob1_2(g); (*m00).r4.c2 = mac((*m00).r4.c2, u, v0.r4.c2); }
            { let u = ob1_3(g); (*m00).r4.c3 = mac((*m00).r4.c3, u, v0.r4.c3); }
            }
            {
            let g = gather(base + 112u);
            { let u = ob1_0(g); (*m00).r4.c4 = mac((*m00).r4.c4, u, v0.r4.c4); }
            { let u = ob1_1(g); (*m00).r4.c5 = mac((*m00).r4.c5, u, v0.r4.c5); }
            { let u = ob1_2(g); (*m00).r5.c0 = mac((*m00).r5.c0, u, v0.r5.c0); }
            { let u = ob1_3(g); (*m00).r5.c1 = mac((*m00).r5.c1, u, v0.r5.c1); }
            }
            {
            let g = gather(base + 128u);
            { let u = ob1_0(g); (*m00).r5.c2 = mac((*m00).r5.c2, u, v0.r5.c2); }
            { let u = ob1_1(g); (*m00).r5.c3 = mac((*m00).r5.c3, u, v0.r5.c3); }
            { let u = ob1_2(g); (*m00).r5.c4 = mac((*m00).r5.c4, u, v0.r5.c4); }
            { let u = ob1_3(g); (*m00).r5.c5 = mac((*m00).r5.c5, u, v0.r5.c5); }
            }
            continuing { break if once(); }
        }
    } else if OB == 2u {
        loop {
            {
            let g = gather(base + 0u);
            { let u = ob2_00(g); (*m00).r0.c0 = mac((*m00).r0.c0, u, v0.r0.c0); }
            { let u = ob2_01(g); (*m01).r0.c0 = mac((*m01).r0.c0, u, v0.r0.c0); }
            { let u = ob2_10(g); (*m00).r0.c1 = mac((*m00).r0.c1, u, v0.r0.c1); }
            { let u = ob2_11(g); (*m01).r0.c1 = mac((*m01).r0.c1, u, v0.r0.c1); }
            }
            {
            let g = gather(base + 16u);
            { let u = ob2_00(g); (*m00).r0.c2 = mac((*m00).r0.c2, u, v0.r0.c2); }
            { let u = ob2_01(g); (*m01).r0.c2 = mac((*m01).r0.c2, u, v0.r0.c2); }
            { let u = ob2_10(g); (*m00).r0.c3 = mac((*m00).r0.c3, u, v0.r0.c3); }
            { let u = ob2_11(g); (*m01).r0.c3 = mac((*m01).r0.c3, u, v0.r0.c3); }
            }
            {
            let g = gather(base + 32u);
            { let u = ob2_00(g); (*m00).r0.c4 = mac((*m00).r0.c4, u, v0.r0.c4); }
            { let u = ob2_01(g); (*m01).r0.c4 = mac((*m01).r0.c4, u, v0.r0.c4); }
            { let u = ob2_10(g); (*m00).r0.c5 = mac((*m00).r0.c5, u, v0.r0.c5); }
            { let u = ob2_11(g); (*m01).r0.c5 = mac((*m01).r0.c5, u, v0.r0.c5); }
            }
            {
            let g = gather(base + 48u);
            { let u = ob2_00(g); (*m00).r1.c0 = mac((*m00).r1.c0, u, v0.r1.c0); }
            { let u = ob2_01(g); (*m01).r1.c0 = mac((*m01).r1.c0, u, v0.r1.c0); }
            { let u = ob2_10(g); (*m00).r1.c1 = mac((*m00).r1.c1, u, v0.r1.c1); }
            { let u = ob2_11(g); (*m01).r1.c1 = mac((*m01).r1.c1, u, v0.r1.c1); }
            }
            {
            let g = gather(base + 64u);
            { let u = ob2_00(g); (*m00).r1.c2 = mac((*m00).r1.c2, u, v0.r1.c2); }
            { let u = ob2_01(g); (*m01).r1.c2 = mac((*m01).r1.c2, u, v0.r1.c2); }
            { let u = ob2_10(g); (*m00).r1.c3 = mac((*m00).r1.c3, u, v0.r1.c3); }
            { let u = ob2_11(g); (*m01).r1.c3 = mac((*m01).r1.c3, u, v0.r1.c3); }
            }
            {
            let g = gather(base + 80u);
            { let u = ob2_00(g); (*m00).r1.c4 = mac((*m00).r1.c4, u, v0.r1.c4); }
            { let u = ob2_01(g); (*m01).r1.c4 = mac((*m01).r1.c4, u, v0.r1.c4); }
            { let u = ob2_10(g); (*m00).r1.c5 = mac((*m00).r1.c5, u, v0.r1.c5); }
            { let u = ob2_11(g); (*m01).r1.c5 = mac((*m01).r1.c5, u, v0.r1.c5); }
            }
            continuing { break if once(); }
        }
        loop {
            {
            let g = gather(base + 96u);
            { let u = ob2_00(g); (*m00).r2.c0 = mac((*m00).r2.c0, u, v0.r2.c0); }
            { let u = ob2_01(g); (*m01).r2.c0 = mac((*m01).r2.c0, u, v0.r2.c0); }
            { let u = ob2_10(g); (*m00).r2.c1 = mac((*m00).r2.c1, u, v0.r2.c1); }
            { let u = ob2_11(g); (*m01).r2.c1 = mac((*m01).r2.c1, u, v0.r2.c1); }
            }
            {
            let g = gather(base + 112u);
            { let u = ob2_00(g); (*m00).r2.c2 = mac((*m00).r2.c2, u, v0.r2.c2); }
            { let u = ob2_01(g); (*m01).r2.c2 = mac((*m01).r2.c2, u, v0.r2.c2); }
            { let u = ob2_10(g); (*m00).r2.c3 = mac((*m00).r2.c3, u, v0.r2.c3); }
            { let u = ob2_11(g); (*m01).r2.c3 = mac((*m01).r2.c3, u, v0.r2.c3); }
            }
            {
            let g = gather(base + 128u);
            { let u = ob2_00(g); (*m00).r2.c4 = mac((*m00).r2.c4, u, v0.r2.c4); }
            { let u = ob2_01(g); (*m01).r2.c4 = mac((*m01).r2.c4, u, v0.r2.c4); }
            { let u = ob2_10(g); (*m00).r2.c5 = mac((*m00).r2.c5, u, v0.r2.c5); }
            { let u = ob2_11(g); (*m01).r2.c5 = mac((*m01).r2.c5, u, v0.r2.c5); }
            }
            {
            let g = gather(base + 144u);
            { let u = ob2_00(g); (*m00).r3.c0 = mac((*m00).r3.c0, u, v0.r3.c0); }
            { let u = ob2_01(g); (*m01).r3.c0 = mac((*m01).r3.c0, u, v0.r3.c0); }
            { let u = ob2_10(g); (*m00).r3.c1 = mac((*m00).r3.c1, u, v0.r3.c1); }
            { let u = ob2_11(g); (*m01).r3.c1 = mac((*m01).r3.c1, u, v0.r3.c1); }
            }
            {
            let g = gather(base + 160u);
            { let u = ob2_00(g); (*m00).r3.c2 = mac((*m00).r3.c2, u, v0.r3.c2); }
            { let u = ob2_01(g); (*m01).r3.c2 = mac((*m01).r3.c2, u, v0.r3.c2); }
            { let u = ob2_10(g); (*m00).r3.c3 = mac((*m00).r3.c3, u, v0.r3.c3); }
            { let u = ob2_11(g); (*m01).r3.c3 = mac((*m01).r3.c3, u, v0.r3.c3); }
            }
            {
            let g = gather(base + 176u);
            { let u = ob2_00(g); (*m00).r3.c4 = mac((*m00).r3.c4, u, v0.r3.c4); }
            { let u = ob2_01(g); (*m01).r3.c4 = mac((*m01).r3.c4, u, v0.r3.c4); }
            { let u = ob2_10(g); (*m00).r3.c5 = mac((*m00).r3.c5, u, v0.r3.c5); }
            { let u = ob2_11(g); (*m01).r3.c5 = mac((*m01).r3.c5, u, v0.r3.c5); }
            }
            continuing { break if once(); }
        }
        loop {
            {
            let g = gather(base + 192u);
            { let u = ob2_00(g); (*m00).r4.c0 = mac((*m00).r4.c0, u, v0.r4.c0); }
            { let u = ob2_01(g); (*m01).r4.c0 = mac((*m01).r4.c0, u, v0.r4.c0); }
            { let u = ob2_10(g); (*m00).r4.c1 = mac((*m00).r4.c1, u, v0.r4.c1); }
            { let u = ob2_11(g); (*m01).r4.c1 = mac((*m01).r4.c1, u, v0.r4.c1); }
            }
            {
            let g = gather(base + 208u);
            { let u = ob2_00(g); (*m00).r4.c2 = mac((*m00).r4.c2, u, v0.r4.c2); }
            { let u = ob2_01(g); (*m01).r4.c2 = mac((*m01).r4.c2, u, v0.r4.c2); }
            { let u = ob2_10(g); (*m00).r4.c3 = mac((*m00).r4.c3, u, v0.r4.c3); }
            { let u = ob2_11(g); (*m01).r4.c3 = mac((*m01).r4.c3, u, v0.r4.c3); }
            }
            {
            let g = gather(base + 224u);
            { let u = ob2_00(g); (*m00).r4.c4 = mac((*m00).r4.c4, u, v0.r4.c4); }
            { let u = ob2_01(g); (*m01).r4.c4 = mac((*m01).r4.c4, u, v0.r4.c4); }
            { let u = ob2_10(g); (*m00).r4.c5 = mac((*m00).r4.c5, u, v0.r4.c5); }
            { let u = ob2_11(g); (*m01).r4.c5 = mac((*m01).r4.c5, u, v0.r4.c5); }
            }
            {
            let g = gather(base + 240u);
            { let u = ob2_00(g); (*m00).r5.c0 = mac((*m00).r5.c0, u, v0.r5.c0); }
            { let u = ob2_01(g); (*m01).r5.c0 = mac((*m01).r5.c0, u, v0.r5.c0); }
            { let u = ob2_10(g); (*m00).r5.c1 = mac((*m00).r5.c1, u, v0.r5.c1); }
            { let u = ob2_11(g); (*m01).r5.c1 = mac((*m01).r5.c1, u, v0.r5.c1); }
            }
            {
            let g = gather(base + 256u);
            { let u = ob2_00(g); (*m00).r5.c2 = mac((*m00).r5.c2, u, v0.r5.c2); }
            { let u = ob2_01(g); (*m01).r5.c2 = mac((*m01).r5.c2, u, v0.r5.c2); }
            { let u = ob2_10(g); (*m00).r5.c3 = mac((*m00).r5.c3, u, v0.r5.c3); }
            { let u = ob2_11(g); (*m01).r5.c3 = mac((*m01).r5.c3, u, v0.r5.c3); }
            }
            {
            let g = gather(base + 272u);
            { let u = ob2_00(g); (*m00).r5.c4 = mac((*m00).r5.c4, u, v0.r5.c4); }
            { let u = ob2_01(g); (*m01).r5.c4 = mac((*m01).r5.c4, u, v0.r5.c4); }
            { let u = ob2_10(g); (*m00).r5.c5 = mac((*m00).r5.c5, u, v0.r5.c5); }
            { let u = ob2_11(g); (*m01).r5.c5 = mac((*m01).r5.c5, u, v0.r5.c5); }
            }
            continuing { break if once(); }
        }
    } else {
        loop {
            {
            let g = gather(base + 0u);
            { let u = ob4_0(g); (*m00).r0.c0 = mac((*m00).r0.c0, u, v0.r0.c0); }
            { let u = ob4_1(g); (*m01).r0.c0 = mac((*m01).r0.c0, u, v0.r0.c0); }
            { let u = ob4_2(g); (*m02).r0.c0 = mac((*m02).r0.c0, u, v0.r0.c0); }
            { let u = ob4_3(g); (*m03).r0.c0 = mac((*m03).r0.c0, u, v0.r0.c0); }
            }
            {
            let g = gather(base + 16u);
            { let u = ob4_0(g); (*m00).r0.c1 = mac((*m00).r0.c1, u, v0.r0.c1); }
            { let u = ob4_1(g); (*m01).r0.c1 = mac((*m01).r0.c1, u, v0.r0.c1); }
            { let u = ob4_2(g); (*m02).r0.c1 = mac((*m02).r0.c1, u, v0.r0.c1); }
            { let u = ob4_3(g); (*m03).r0.c1 = mac((*m03).r0.c1, u, v0.r0.c1); }
            }
            {
            let g = gather(base + 32u);
            { let u = ob4_0(g); (*m00).r0.c2 = mac((*m00).r0.c2, u, v0.r0.c2); }
            { let u = ob4_1(g); (*m01).r0.c2 = mac((*m01).r0.c2, u, v0.r0.c2); }
            { let u = ob4_2(g); (*m02).r0.c2 = mac((*m02).r0.c2, u, v0.r0.c2); }
            { let u = ob4_3(g); (*m03).r0.c2 = mac((*m03).r0.c2, u, v0.r0.c2); }
            }
            {
            let g = gather(base + 48u);
            { let u = ob4_0(g); (*m00).r0.c3 = mac((*m00).r0.c3, u, v0.r0.c3); }
            { let u = ob4_1(g); (*m01).r0.c3 = mac((*m01).r0.c3, u, v0.r0.c3); }
            { let u = ob4_2(g); (*m02).r0.c3 = mac((*m02).r0.c3, u, v0.r0.c3); }
            { let u = ob4_3(g); (*m03).r0.c3 = mac((*m03).r0.c3, u, v0.r0.c3); }
            }
            {
            let g = gather(base + 64u);
            { let u = ob4_0(g); (*m00).r0.c4 = mac((*m00).r0.c4, u, v0.r0.c4); }
            { let u = ob4_1(g); (*m01).r0.c4 = mac((*m01).r0.c4, u, v0.r0.c4); }
            { let u = ob4_2(g); (*m02).r0.c4 = mac((*m02).r0.c4, u, v0.r0.c4); }
            { let u = ob4_3(g); (*m03).r0.c4 = mac((*m03).r0.c4, u, v0.r0.c4); }
            }
            {
            let g = gather(base + 80u);
            { let u = ob4_0(g); (*m00).r0.c5 = mac((*m00).r0.c5, u, v0.r0.c5); }
            { let u = ob4_1(g); (*m01).r0.c5 = mac((*m01).r0.c5, u, v0.r0.c5); }
            { let u = ob4_2(g); (*m02).r0.c5 = mac((*m02).r0.c5, u, v0.r0.c5); }
            { let u = ob4_3(g); (*m03).r0.c5 = mac((*m03).r0.c5, u, v0.r0.c5); }
            }
            {
            let g = gather(base + 96u);
            { let u = ob4_0(g); (*m00).r1.c0 = mac((*m00).r1.c0, u, v0.r1.c0); }
            { let u = ob4_1(g); (*m01).r1.c0 = mac((*m01).r1.c0, u, v0.r1.c0); }
            { let u = ob4_2(g); (*m02).r1.c0 = mac((*m02).r1.c0, u, v0.r1.c0); }
            { let u = ob4_3(g); (*m03).r1.c0 = mac((*m03).r1.c0, u, v0.r1.c0); }
            }
            {
            let g = gather(base + 112u);
            { let u = ob4_0(g); (*m00).r1.c1 = mac((*m00).r1.c1, u, v0.r1.c1); }
            { let u = ob4_1(g); (*m01).r1.c1 = mac((*m01).r1.c1, u, v0.r1.c1); }
            { let u = ob4_2(g); (*m02).r1.c1 = mac((*m02).r1.c1, u, v0.r1.c1); }
            { let u = ob4_3(g); (*m03).r1.c1 = mac((*m03).r1.c1, u, v0.r1.c1); }
            }
            {
            let g = gather(base + 128u);
            { let u = ob4_0(g); (*m00).r1.c2 = mac((*m00).r1.c2, u, v0.r1.c2); }
            { let u = ob4_1(g); (*m01).r1.c2 = mac((*m01).r1.c2, u, v0.r1.c2); }
            { let u = ob4_2(g); (*m02).r1.c2 = mac((*m02).r1.c2, u, v0.r1.c2); }
            { let u = ob4_3(g); (*m03).r1.c2 = mac((*m03).r1.c2, u, v0.r1.c2); }
            }
            {
            let g = gather(base + 144u);
            { let u = ob4_0(g); (*m00).r1.c3 = mac((*m00).r1.c3, u, v0.r1.c3); }
            { let u = ob4_1(g); (*m01).r1.c3 = mac((*m01).r1.c3, u, v0.r1.c3); }
            { let u = ob4_2(g); (*m02).r1.c3 = mac((*m02).r1.c3, u, v0.r1.c3); }
            { let u = ob4_3(g); (*m03).r1.c3 = mac((*m03).r1.c3, u, v0.r1.c3); }
            }
            {
            let g = gather(base + 160u);
            { let u = ob4_0(g); (*m00).r1.c4 = mac((*m00).r1.c4, u, v0.r1.c4); }
            { let u = ob4_1(g); (*m01).r1.c4 = mac((*m01).r1.c4, u, v0.r1.c4); }
            { let u = ob4_2(g); (*m02).r1.c4 = mac((*m02).r1.c4, u, v0.r1.c4); }
            { let u = ob4_3(g); (*m03).r1.c4 = mac((*m03).r1.c4, u, v0.r1.c4); }
            }
            {
            let g = gather(base + 176u);
            { let u = ob4_0(g); (*m00).r1.c5 = mac((*m00).r1.c5, u, v0.r1.c5); }
            { let u = ob4_1(g); (*m01).r1.c5 = mac((*m01).r1.c5, u, v0.r1.c5); }
            { let u = ob4_2(g); (*m02).r1.c5 = mac((*m02).r1.c5, u, v0.r1.c5); }
            { let u = ob4_3(g); (*m03).r1.c5 = mac((*m03).r1.c5, u, v0.r1.c5); }
            }
            continuing { break if once(); }
        }
        loop {
            {
            let g = gather(base + 192u);
            { let u = ob4_0(g); (*m00).r2.c0 = mac((*m00).r2.c0, u, v0.r2.c0); }
            { let u = ob4_1(g); (*m01).r2.c0 = mac((*m01).r2.c0, u, v0.r2.c0); }
            { let u = ob4_2(g); (*m02).r2.c0 = mac((*m02).r2.c0, u, v0.r2.c0); }
            { let u = ob4_3(g); (*m03).r2.c0 = mac((*m03).r2.c0, u, v0.r2.c0); }
            }
            {
            let g = gather(base + 208u);
            { let u = ob4_0(g); (*m00).r2.c1 = mac((*m00).r2.c1, u, v0.r2.c1); }
            { let u = ob4_1(g); (*m01).r2.c1 = mac((*m01).r2.c1, u, v0.r2.c1); }
            { let u = ob4_2(g); (*m02).r2.c1 = mac((*m02).r2.c1, u, v0.r2.c1); }
            { let u = ob4_3(g); (*m03).r2.c1 = mac((*m03).r2.c1, u, v0.r2.c1); }
            }
            {
            let g = gather(base + 224u);
            { let u = ob4_0(g); (*m00).r2.c2 = mac((*m00).r2.c2, u, v0.r2.c2); }
            { let u = ob4_1(g); (*m01).r2.c2 = mac((*m01).r2.c2, u, v0.r2.c2); }
            { let u = ob4_2(g); (*m02).r2.c2 = mac((*m02).r2.c2, u, v0.r2.c2); }
            { let u = ob4_3(g); (*m03).r2.c2 = mac((*m03).r2.c2, u, v0.r2.c2); }
            }
            {
            let g = gather(base + 240u);
            { let u = ob4_0(g); (*m00).r2.c3 = mac((*m00).r2.c3, u, v0.r2.c3); }
            { let u = ob4_1(g); (*m01).r2.c3 = mac((*m01).r2.c3, u, v0.r2.c3); }
            { let u = ob4_2(g); (*m02).r2.c3 = mac((*m02).r2.c3, u, v0.r2.c3); }
            { let u = ob4_3(g); (*m03).r2.c3 = mac((*m03).r2.c3, u, v0.r2.c3); }
            }
            {
            let g = gather(base + 256u);
            { let u = ob4_0(g); (*m00).r2.c4 = mac((*m00).r2.c4, u, v0.r2.c4); }
            { let u = ob4_1(g); (*m01).r2.c4 = mac((*m01).r2.c4, u, v0.r2.c4); }
            { let u = ob4_2(g); (*m02).r2.c4 = mac((*m02).r2.c4, u, v0.r2.c4); }
            { let u = ob4_3(g); (*m03).r2.c4 = mac((*m03).r2.c4, u, v0.r2.c4); }
            }
            {
            let g = gather(base + 272u);
            { let u = ob4_0(g); (*m00).r2.c5 = mac((*m00).r2.c5, u, v0.r2.c5); }
            { let u = ob4_1(g); (*m01).r2.c5 = mac((*m01).r2.c5, u, v0.r2.c5); }
            { let u = ob4_2(g); (*m02).r2.c5 = mac((*m02).r2.c5, u, v0.r2.c5); }
            { let u = ob4_3(g); (*m03).r2.c5 = mac((*m03).r2.c5, u, v0.r2.c5); }
            }
            {
            let g = gather(base + 288u);
            { let u = ob4_0(g); (*m00).r3.c0 = mac((*m00).r3.c0, u, v0.r3.c0); }
            { let u = ob4_1(g); (*m01).r3.c0 = mac((*m01).r3.c0, u, v0.r3.c0); }
            { let u = ob4_2(g); (*m02).r3.c0 = mac((*m02).r3.c0, u, v0.r3.c0); }
            { let u = ob4_3(g); (*m03).r3.c0 = mac((*m03).r3.c0, u, v0.r3.c0); }
            }
            {
            let g = gather(base + 304u);
            { let u = ob4_0(g); (*m00).r3.c1 = mac((*m00).r3.c1, u, v0.r3.c1); }
            { let u = ob4_1(g); (*m01).r3.c1 = mac((*m01).r3.c1, u, v0.r3.c1); }
            { let u = ob4_2(g); (*m02).r3.c1 = mac((*m02).r3.c1, u, v0.r3.c1); }
            { let u = ob4_3(g); (*m03).r3.c1 = mac((*m03).r3.c1, u, v0.r3.c1); }
            }
            {
            let g = gather(base + 320u);
            { let u = ob4_0(g); (*m00).r3.c2 = mac((*m00).r3.c2, u, v0.r3.c2); }
            { let u = ob4_1(g); (*m01).r3.c2 = mac((*m01).r3.c2, u, v0.r3.c2); }
            { let u = ob4_2(g); (*m02).r3.c2 = mac((*m02).r3.c2, u, v0.r3.c2); }
            { let u = ob4_3(g); (*m03).r3.c2 = mac((*m03).r3.c2, u, v0.r3.c2); }
            }
            {
            let g = gather(base + 336u);
            { let u = ob4_0(g); (*m00).r3.c3 = mac((*m00).r3.c3, u, v0.r3.c3); }
            { let u = ob4_1(g); (*m01).r3.c3 = mac((*m01).r3.c3, u, v0.r3.c3); }
            { let u = ob4_2(g); (*m02).r3.c3 = mac((*m02).r3.c3, u, v0.r3.c3); }
            { let u = ob4_3(g); (*m03).r3.c3 = mac((*m03).r3.c3, u, v0.r3.c3); }
            }
            {
            let g = gather(base + 352u);
            { let u = ob4_0(g); (*m00).r3.c4 = mac((*m00).r3.c4, u, v0.r3.c4); }
            { let u = ob4_1(g); (*m01).r3.c4 = mac((*m01).r3.c4, u, v0.r3.c4); }
            { let u = ob4_2(g); (*m02).r3.c4 = mac((*m02).r3.c4, u, v0.r3.c4); }
            { let u = ob4_3(g); (*m03).r3.c4 = mac((*m03).r3.c4, u, v0.r3.c4); }
            }
            {
            let g = gather(base + 368u);
            { let u = ob4_0(g); (*m00).r3.c5 = mac((*m00).r3.c5, u, v0.r3.c5); }
            { let u = ob4_1(g); (*m01).r3.c5 = mac((*m01).r3.c5, u, v0.r3.c5); }
            { let u = ob4_2(g); (*m02).r3.c5 = mac((*m02).r3.c5, u, v0.r3.c5); }
            { let u = ob4_3(g); (*m03).r3.c5 = mac((*m03).r3.c5, u, v0.r3.c5); }
            }
            continuing { break if once(); }
        }
        loop {
            {
            let g = gather(base + 384u);
            { let u = ob4_0(g); (*m00).r4.c0 = mac((*m00).r4.c0, u, v0.r4.c0); }
            { let u = ob4_1(g); (*m01).r4.c0 = mac((*m01).r4.c0, u, v0.r4.c0); }
            { let u = ob4_2(g); (*m02).r4.c0 = mac((*m02).r4.c0, u, v0.r4.c0); }
            { let u = ob4_3(g); (*m03).r4.c0 = mac((*m03).r4.c0, u, v0.r4.c0); }
            }
            {
            let g = gather(base + 400u);
            { let u = ob4_0(g); (*m00).r4.c1 = mac((*m00).r4.c1, u, v0.r4.c1); }
            { let u = ob4_1(g); (*m01).r4.c1 = mac((*m01).r4.c1, u, v0.r4.c1); }
            { let u = ob4_2(g); (*m02).r4.c1 = mac((*m02).r4.c1, u, v0.r4.c1); }
            { let u = ob4_3(g); (*m03).r4.c1 = mac((*m03).r4.c1, u, v0.r4.c1); }
            }
            {
            let g = gather(base + 416u);
            { let u = ob4_0(g); (*m00).r4.c2 = mac((*m00).r4.c2, u, v0.r4.c2); }
            { let u = ob4_1(g); (*m01).r4.c2 = mac((*m01).r4.c2, u, v0.r4.c2); }
            { let u = ob4_2(g); (*m02).r4.c2 = mac((*m02).r4.c2, u, v0.r4.c2); }
            { let u = ob4_3(g); (*m03).r4.c2 = mac((*m03).r4.c2, u, v0.r4.c2); }
            }
            {
            let g = gather(base + 432u);
            { let u = ob4_0(g); (*m00).r4.c3 = mac((*m00).r4.c3, u, v0.r4.c3); }
            { let u = ob4_1(g); (*m01).r4.c3 = mac((*m01).r4.c3, u, v0.r4.c3); }
            { let u = ob4_2(g); (*m02).r4.c3 = mac((*m02).r4.c3, u, v0.r4.c3); }
            { let u = ob4_3(g); (*m03).r4.c3 = mac((*m03).r4.c3, u, v0.r4.c3); }
            }
            {
            let g = gather(base + 448u);
            { let u = ob4_0(g); (*m00).r4.c4 = mac((*m00).r4.c4, u, v0.r4.c4); }
            { let u = ob4_1(g); (*m01).r4.c4 = mac((*m01).r4.c4, u, v0.r4.c4); }
            { let u = ob4_2(g); (*m02).r4.c4 = mac((*m02).r4.c4, u, v0.r4.c4); }
            { let u = ob4_3(g); (*m03).r4.c4 = mac((*m03).r4.c4, u, v0.r4.c4); }
            }
            {
            let g = gather(base + 464u);
            { let u = ob4_0(g); (*m00).r4.c5 = mac((*m00).r4.c5, u, v0.r4.c5); }
            { let u = ob4_1(g); (*m01).r4.c5 = mac((*m01).r4.c5, u, v0.r4.c5); }
            { let u = ob4_2(g); (*m02).r4.c5 = mac((*m02).r4.c5, u, v0.r4.c5); }
            { let u = ob4_3(g); (*m03).r4.c5 = mac((*m03).r4.c5, u, v0.r4.c5); }
            }
            {
            let g = gather(base + 480u);
            { let u = ob4_0(g); (*m00).r5.c0 = mac((*m00).r5.c0, u, v0.r5.c0); }
            { let u = ob4_1(g); (*m01).r5.c0 = mac((*m01).r5.c0, u, v0.r5.c0); }
            { let u = ob4_2(g); (*m02).r5.c0 = mac((*m02).r5.c0, u, v0.r5.c0); }
            { let u = ob4_3(g); (*m03).r5.c0 = mac((*m03).r5.c0, u, v0.r5.c0); }
            }
            {
            let g = gather(base + 496u);
            { let u = ob4_0(g); (*m00).r5.c1 = mac((*m00).r5.c1, u, v0.r5.c1); }
            { let u = ob4_1(g); (*m01).r5.c1 = mac((*m01).r5.c1, u, v0.r5.c1); }
            { let u = ob4_2(g); (*m02).r5.c1 = mac((*m02).r5.c1, u, v0.r5.c1); }
            { let u = ob4_3(g); (*m03).r5.c1 = mac((*m03).r5.c1, u, v0.r5.c1); }
            }
            {
            let g = gather(base + 512u);
            { let u = ob4_0(g); (*m00).r5.c2 = mac((*m00).r5.c2, u, v0.r5.c2); }
            { let u = ob4_1(g); (*m01).r5.c2 = mac((*m01).r5.c2, u, v0.r5.c2); }
            { let u = ob4_2(g); (*m02).r5.c2 = mac((*m02).r5.c2, u, v0.r5.c2); }
            { let u = ob4_3(g); (*m03).r5.c2 = mac((*m03).r5.c2, u, v0.r5.c2); }
            }
            {
            let g = gather(base + 528u);
            { let u = ob4_0(g); (*m00).r5.c3 = mac((*m00).r5.c3, u, v0.r5.c3); }
            { let u = ob4_1(g); (*m01).r5.c3 = mac((*m01).r5.c3, u, v0.r5.c3); }
            { let u = ob4_2(g); (*m02).r5.c3 = mac((*m02).r5.c3, u, v0.r5.c3); }
            { let u = ob4_3(g); (*m03).r5.c3 = mac((*m03).r5.c3, u, v0.r5.c3); }
            }
            {
            let g = gather(base + 544u);
            { let u = ob4_0(g); (*m00).r5.c4 = mac((*m00).r5.c4, u, v0.r5.c4); }
            { let u = ob4_1(g); (*m01).r5.c4 = mac((*m01).r5.c4, u, v0.r5.c4); }
            { let u = ob4_2(g); (*m02).r5.c4 = mac((*m02).r5.c4, u, v0.r5.c4); }
            { let u = ob4_3(g); (*m03).r5.c4 = mac((*m03).r5.c4, u, v0.r5.c4); }
            }
            {
            let g = gather(base + 560u);
            { let u = ob4_0(g); (*m00).r5.c5 = mac((*m00).r5.c5, u, v0.r5.c5); }
            { let u = ob4_1(g); (*m01).r5.c5 = mac((*m01).r5.c5, u, v0.r5.c5); }
            { let u = ob4_2(g); (*m02).r5.c5 = mac((*m02).r5.c5, u, v0.r5.c5); }
            { let u = ob4_3(g); (*m03).r5.c5 = mac((*m03).r5.c5, u, v0.r5.c5); }
            }
            continuing { break if once(); }
        }
    }
}
// ---- end generated ----

// `winograd4_lanes`: F(4x4, 3x3) tiles in one-dimensional workgroups of WG_X x WG_Y invocations
// (subgroup builtins need them), each WG_X invocations of a row 4 columns apart.
@compute @workgroup_size(64, 1, 1)
fn winograd4_lanes(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_id) l: vec3<u32>, @builtin(subgroup_invocation_id) sg: u32) {
    lane = sg;
    let x = (wg.x * WG_X + l.x % WG_X) * 4u;
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
    let z = Hex(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
    var m00 = Wino6(z, z, z, z, z, z);
    var m01 = m00;
    var m02 = m00;
    var m03 = m00;
    let xi = i32(x);
    let yi = i32(y0);
    // Source a's blocks, then b's (none on a reset frame's hidden state: cin4_b = 0).
    let blocks = params.cin4_a + select(0u, params.cin4_b, SOURCE_B);
    for (var c = 0u; c < blocks; c++) {
        wino4_step(&m00, &m01, &m02, &m03, c, w, xi, yi);
    }
    if !inside {
        return;
    }
    let bias_at = w + params.cin4_total * 144u * OB;
    let second = OB > 1u && ob0 + 1u < params.cout4;
    let third = OB > 2u && ob0 + 2u < params.cout4;
    let fourth = OB > 2u && ob0 + 3u < params.cout4;
    // The tile's outputs at rows y0 .. y0 + 3 (wino4_store drops rows past the bottom).
    let b = texel_biases(bias_at);
    let b0 = b.c0;
    let b1 = b.c1;
    let b2 = b.c2;
    let b3 = b.c3;
    wino4_store(m00, b0, x, y0, ob0);
    if second { wino4_store(m01, b1, x, y0, ob0 + 1u); }
    if third { wino4_store(m02, b2, x, y0, ob0 + 2u); }
    if fourth { wino4_store(m03, b3, x, y0, ob0 + 3u); }
}

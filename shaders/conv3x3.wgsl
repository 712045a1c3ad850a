// 3x3 convolution (zero padding) with bias and optional LeakyReLU fused into the store, over the
// channel concatenation cat(a, b) of two sources read in place (no concat copy). Each source is
// read as-is, max-pooled 2x2, nearest-upsampled 2x, or max-pooled then upsampled, so pooling and
// upsampling never run as passes of their own.
//
// Activations are rgba32float texture arrays: layer l holds channels 4l..4l+3 (texture loads are
// vectorised on lavapipe, storage-buffer loads run lane by lane). Weights sit in a uniform
// binding of 64 KiB: every invocation reads the same weight at the same time, which lavapipe
// turns into one load and a broadcast (and a discrete GPU serves from its constant cache). A
// conv's weights are split into groups of OB output blocks; as many groups as fit share one
// 64 KiB binding (bound by dynamic offset) and one dispatch, workgroup z picking the group, so
// narrow convs and small levels pay for few dispatches.
//
// Specialised per layer kind by override constants (read modes, activation, output blocks per
// invocation); sizes come in the uniform, so one pipeline serves every resolution and width.
// Entry points: `main` (the direct sum, optionally split-K), `lanes` (the same with each weight
// loaded once per subgroup, for CPU drivers), `reduce` (split-K's second pass) and `winograd`
// (Winograd F(2x2, 3x3)); kernels::Method picks. What it shares with conv3x3_mma.wgsl (the
// parameter block, the sources and the output, the read modes, `fetch`, `activate`) is in
// conv_common.wgsl, appended by kernels::conv_module_source.

// Output blocks (4 channels each) per invocation: 1, 2, or 4 with TW = 1 (kernels::Tile,
// kernels::blocks_per_invocation). Every fetched input texel feeds 4 * OB output channels: on
// lavapipe each fetch is a call into the driver's texel-fetch function, so OB = 4 pays off there.
override OB: u32 = 2u;

// Register tile: each invocation computes ROWS output rows (at most 16) x OB output blocks at TW
// adjacent columns (1 or 2), in named accumulators: no indexable local arrays, which lavapipe would keep in per-lane
// scratch memory. Rows and input rows past ROWS sit behind `if ROWS > k` on the override, which
// the compiler removes: levels only a few pixels high (the deepest, on small frames) do not pay
// for 16 rows (kernels::rows_per_invocation).
override ROWS: u32 = 16u;
// Output columns per invocation: 1 or 2 (a 2-wide tile fetches 4 input columns for 2 outputs).
override TW: u32 = 1u;
// vec4s in one weight chunk (64 KiB, the uniform binding limit).
const CHUNK: u32 = 4096u;
// Split-K: the input blocks are divided among SPLIT invocations per output (workgroup z runs
// over groups x SPLIT parts), each adding its share to a partial sum in `partial`, and the
// entry point `reduce` adds the parts, the activation and the clamp. The deep levels are a few
// thousand outputs deep in 200-channel sums: one long dependent loop per invocation and too
// few invocations to fill a GPU; SPLIT shortens the loop and multiplies the invocations.
override SPLIT: u32 = 1u;
// Weights loaded across the subgroup (entry point `lanes`, subgroups of at least 8 lanes): a
// tap's 4 x OB vec4s are read 8 at a time, lane k loading the k-th, and handed to every lane by
// subgroupBroadcast. Every lane needs the same weights, but lavapipe proves a uniform-buffer
// load lane-uniform only when its offset is a constant or push constant, so `tap` costs one
// lane-by-lane gather per vec4; here a gather fetches 8 vec4s and each broadcast is a shuffle.
override LANES: bool = false;
// The conv's output may also be written max-pooled 2x2 into `pooled` (two-column lanes tiles with
// an even number of rows, unsplit, and the Winograd lanes tiles: each invocation holds whole 2x2
// windows; kernels::ConvPlan decides). It replaces pool.wgsl's pass after an encoder block's
// last conv, whose four loads a pooled texel and dispatch cost more on lavapipe than one more
// store here. POOL_OUT compiles the pooled store in, params.pool_out asks for it per conv (see
// `pools`).
override POOL_OUT: bool = false;

// Whether this conv writes its pooled output: compiled in (POOL_OUT) and asked for
// (params.pool_out). The tiles that can pool compile it in wherever they run, so a conv that
// pools and one that does not share a pipeline (kernels::ConvVariant::pool).
fn pools() -> bool {
    return POOL_OUT && params.pool_out != 0u;
}

// Weights of group z, from w = z * group_stride: taps at w + ((in block * 9 + tap) * 4 + in lane)
// * OB + j, a vec4 over the 4 output channels of block ob0 + z * OB + j; then the bias of block j
// at w + cin4_total * 36 * OB + j.
@group(0) @binding(3) var<uniform> weights: array<vec4<f32>, CHUNK>;
// Partial sums when SPLIT > 1: part p of output block l at ((p * cout4 + l) * height + y) * width
// + x (kernels::ConvPlan sizes one buffer for its largest split conv; convs run one at a time).
@group(0) @binding(5) var<storage, read_write> partial: array<vec4<f32>>;
// `pools`: the output max-pooled 2x2, at half the resolution (else the conv's own output, never
// written here: kernels::ConvPlan::bind_group).
@group(0) @binding(6) var pooled: texture_storage_2d_array<rgba32float, write>;

// Where pooled channel block `layer` is: a pooled value is a level below full resolution, so
// carved into an arena's cells (params.carve_pool).
fn pool_cell(layer: u32) -> vec3<u32> {
    return carved(params.carve_pool, layer);
}

// Store pooled texel p of the block in the cell `at` (`pool_cell`).
fn store_pool(p: vec2<u32>, at: vec3<u32>, v: vec4<f32>) {
    textureStore(pooled, p + at.xy, at.z, v);
}
// The part of the input blocks this invocation sums (SPLIT > 1).
var<private> part: u32;
// This invocation's lane in its subgroup (LANES).
var<private> lane: u32;

// The 16 accumulated rows of one output block.
struct Tile {
    r0: vec4<f32>,
    r1: vec4<f32>,
    r2: vec4<f32>,
    r3: vec4<f32>,
    r4: vec4<f32>,
    r5: vec4<f32>,
    r6: vec4<f32>,
    r7: vec4<f32>,
    r8: vec4<f32>,
    r9: vec4<f32>,
    r10: vec4<f32>,
    r11: vec4<f32>,
    r12: vec4<f32>,
    r13: vec4<f32>,
    r14: vec4<f32>,
    r15: vec4<f32>,
}

// Weight vec4 `i` of the conv's group (`w`-relative as laid out above). The module of the
// two-column lanes and Winograd lanes tiles reads it from the plan's weight texture instead
// (kernels::TEXEL_WEIGHTS), where lavapipe loads 16 lanes' vec4s in one gather rather than a
// storage or uniform load per lane.
fn weight(i: u32) -> vec4<f32> {
    return weights[i];
}

// The 4x4 weights of one tap and output block j: column l maps input lane l to 4 outputs.
fn tap(i: u32, j: u32) -> mat4x4<f32> {
    return mat4x4<f32>(weight(i + j), weight(i + OB + j), weight(i + 2u * OB + j), weight(i + 3u * OB + j));
}

// acc + m * v as four fused multiply-adds: the sum `acc + m0 * v0 + m1 * v1 + ...` would cost
// a multiply and an add per matrix product on top of its FMAs (the compiler may not reassociate).
fn mac(acc: vec4<f32>, m: mat4x4<f32>, v: vec4<f32>) -> vec4<f32> {
    return fma(m[3], vec4<f32>(v.w), fma(m[2], vec4<f32>(v.z), fma(m[1], vec4<f32>(v.y), fma(m[0], vec4<f32>(v.x), acc))));
}

// One output row of one column: the taps m0, m1, m2 (ky = 0, 1, 2) over three input rows.
fn mac3(acc: vec4<f32>, m0: mat4x4<f32>, m1: mat4x4<f32>, m2: mat4x4<f32>, a: vec4<f32>, b: vec4<f32>, c: vec4<f32>) -> vec4<f32> {
    return mac(mac(mac(acc, m0, a), m1, b), m2, c);
}

// Add the 3 taps of column kx, for output block j, to a tile (input column v0..v17).
fn add_column(acc: ptr<function, Tile>, base: u32, j: u32, v0: vec4<f32>, v1: vec4<f32>, v2: vec4<f32>, v3: vec4<f32>, v4: vec4<f32>, v5: vec4<f32>, v6: vec4<f32>, v7: vec4<f32>, v8: vec4<f32>, v9: vec4<f32>, v10: vec4<f32>, v11: vec4<f32>, v12: vec4<f32>, v13: vec4<f32>, v14: vec4<f32>, v15: vec4<f32>, v16: vec4<f32>, v17: vec4<f32>) {
    add_taps(acc, tap(base, j), tap(base + 12u * OB, j), tap(base + 24u * OB, j), v0, v1, v2, v3, v4, v5, v6, v7, v8, v9, v10, v11, v12, v13, v14, v15, v16, v17);
}

// The tap matrices of block j from a tap's vec4s spread over the lanes (LANES): vec4 k of the
// tap, (input lane l, block j) at k = l * OB + j, sits in lane k of `a` (k < 8) or k - 8 of `b`.
fn lanes_1(a: vec4<f32>) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a, 0u), subgroupBroadcast(a, 1u), subgroupBroadcast(a, 2u), subgroupBroadcast(a, 3u));
}
fn lanes_2_0(a: vec4<f32>) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a, 0u), subgroupBroadcast(a, 2u), subgroupBroadcast(a, 4u), subgroupBroadcast(a, 6u));
}
fn lanes_2_1(a: vec4<f32>) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a, 1u), subgroupBroadcast(a, 3u), subgroupBroadcast(a, 5u), subgroupBroadcast(a, 7u));
}
fn lanes_4_0(a: vec4<f32>, b: vec4<f32>) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a, 0u), subgroupBroadcast(a, 4u), subgroupBroadcast(b, 0u), subgroupBroadcast(b, 4u));
}
fn lanes_4_1(a: vec4<f32>, b: vec4<f32>) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a, 1u), subgroupBroadcast(a, 5u), subgroupBroadcast(b, 1u), subgroupBroadcast(b, 5u));
}
fn lanes_4_2(a: vec4<f32>, b: vec4<f32>) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a, 2u), subgroupBroadcast(a, 6u), subgroupBroadcast(b, 2u), subgroupBroadcast(b, 6u));
}
fn lanes_4_3(a: vec4<f32>, b: vec4<f32>) -> mat4x4<f32> {
    return mat4x4<f32>(subgroupBroadcast(a, 3u), subgroupBroadcast(a, 7u), subgroupBroadcast(b, 3u), subgroupBroadcast(b, 7u));
}

// add_column for every block of the tile (one column, TW = 1), weights read across the lanes.
fn add_column_lanes(acc0: ptr<function, Tile>, acc1: ptr<function, Tile>, acc2: ptr<function, Tile>, acc3: ptr<function, Tile>, base: u32, v0: vec4<f32>, v1: vec4<f32>, v2: vec4<f32>, v3: vec4<f32>, v4: vec4<f32>, v5: vec4<f32>, v6: vec4<f32>, v7: vec4<f32>, v8: vec4<f32>, v9: vec4<f32>, v10: vec4<f32>, v11: vec4<f32>, v12: vec4<f32>, v13: vec4<f32>, v14: vec4<f32>, v15: vec4<f32>, v16: vec4<f32>, v17: vec4<f32>) {
    // Tap ky's 4 x OB vec4s start at base + ky * 12 * OB; lanes past them load unused vec4s.
    let a0 = weight(base + lane);
    let a1 = weight(base + 12u * OB + lane);
    let a2 = weight(base + 24u * OB + lane);
    if OB == 1u {
        add_taps(acc0, lanes_1(a0), lanes_1(a1), lanes_1(a2), v0, v1, v2, v3, v4, v5, v6, v7, v8, v9, v10, v11, v12, v13, v14, v15, v16, v17);
    } else if OB == 2u {
        add_taps(acc0, lanes_2_0(a0), lanes_2_0(a1), lanes_2_0(a2), v0, v1, v2, v3, v4, v5, v6, v7, v8, v9, v10, v11, v12, v13, v14, v15, v16, v17);
        add_taps(acc1, lanes_2_1(a0), lanes_2_1(a1), lanes_2_1(a2), v0, v1, v2, v3, v4, v5, v6, v7, v8, v9, v10, v11, v12, v13, v14, v15, v16, v17);
    } else {
        let b0 = weight(base + 8u + lane);
        let b1 = weight(base + 12u * OB + 8u + lane);
        let b2 = weight(base + 24u * OB + 8u + lane);
        add_taps(acc0, lanes_4_0(a0, b0), lanes_4_0(a1, b1), lanes_4_0(a2, b2), v0, v1, v2, v3, v4, v5, v6, v7, v8, v9, v10, v11, v12, v13, v14, v15, v16, v17);
        add_taps(acc1, lanes_4_1(a0, b0), lanes_4_1(a1, b1), lanes_4_1(a2, b2), v0, v1, v2, v3, v4, v5, v6, v7, v8, v9, v10, v11, v12, v13, v14, v15, v16, v17);
        add_taps(acc2, lanes_4_2(a0, b0), lanes_4_2(a1, b1), lanes_4_2(a2, b2), v0, v1, v2, v3, v4, v5, v6, v7, v8, v9, v10, v11, v12, v13, v14, v15, v16, v17);
        add_taps(acc3, lanes_4_3(a0, b0), lanes_4_3(a1, b1), lanes_4_3(a2, b2), v0, v1, v2, v3, v4, v5, v6, v7, v8, v9, v10, v11, v12, v13, v14, v15, v16, v17);
    }
}

// Add the taps m0, m1, m2 (ky = 0, 1, 2) of one column and block to a tile.
fn add_taps(acc: ptr<function, Tile>, m0: mat4x4<f32>, m1: mat4x4<f32>, m2: mat4x4<f32>, v0: vec4<f32>, v1: vec4<f32>, v2: vec4<f32>, v3: vec4<f32>, v4: vec4<f32>, v5: vec4<f32>, v6: vec4<f32>, v7: vec4<f32>, v8: vec4<f32>, v9: vec4<f32>, v10: vec4<f32>, v11: vec4<f32>, v12: vec4<f32>, v13: vec4<f32>, v14: vec4<f32>, v15: vec4<f32>, v16: vec4<f32>, v17: vec4<f32>) {
    (*acc).r0 = mac3((*acc).r0, m0, m1, m2, v0, v1, v2);
    if ROWS > 1u { (*acc).r1 = mac3((*acc).r1, m0, m1, m2, v1, v2, v3); }
    if ROWS > 2u { (*acc).r2 = mac3((*acc).r2, m0, m1, m2, v2, v3, v4); }
    if ROWS > 3u { (*acc).r3 = mac3((*acc).r3, m0, m1, m2, v3, v4, v5); }
    if ROWS > 4u { (*acc).r4 = mac3((*acc).r4, m0, m1, m2, v4, v5, v6); }
    if ROWS > 5u { (*acc).r5 = mac3((*acc).r5, m0, m1, m2, v5, v6, v7); }
    if ROWS > 6u { (*acc).r6 = mac3((*acc).r6, m0, m1, m2, v6, v7, v8); }
    if ROWS > 7u { (*acc).r7 = mac3((*acc).r7, m0, m1, m2, v7, v8, v9); }
    if ROWS > 8u { (*acc).r8 = mac3((*acc).r8, m0, m1, m2, v8, v9, v10); }
    if ROWS > 9u { (*acc).r9 = mac3((*acc).r9, m0, m1, m2, v9, v10, v11); }
    if ROWS > 10u { (*acc).r10 = mac3((*acc).r10, m0, m1, m2, v10, v11, v12); }
    if ROWS > 11u { (*acc).r11 = mac3((*acc).r11, m0, m1, m2, v11, v12, v13); }
    if ROWS > 12u { (*acc).r12 = mac3((*acc).r12, m0, m1, m2, v12, v13, v14); }
    if ROWS > 13u { (*acc).r13 = mac3((*acc).r13, m0, m1, m2, v13, v14, v15); }
    if ROWS > 14u { (*acc).r14 = mac3((*acc).r14, m0, m1, m2, v14, v15, v16); }
    if ROWS > 15u { (*acc).r15 = mac3((*acc).r15, m0, m1, m2, v15, v16, v17); }
}

// Add input block `layer` of `t` (read with `mode`) at weight block `cb` to the tiles whose
// top-left output is (x, y0): output column 0 in acc0/acc1 (blocks 0, 1), column 1 in acc2/acc3
// when TW = 2, or column 0's blocks 2 and 3 in acc2/acc3 when OB = 4 (never both). Input column
// ic (x - 1 + ic) feeds output column 0 through tap kx = ic and output column 1 through
// kx = ic - 1, so a 2-wide tile fetches 4 columns for 2 outputs instead of 6.
fn accumulate(acc0: ptr<function, Tile>, acc1: ptr<function, Tile>, acc2: ptr<function, Tile>, acc3: ptr<function, Tile>, t: Source, mode: u32, layer: u32, cb: u32, w: u32, x: i32, y0: i32) {
    let at = cell(mode, layer);
    for (var ic = 0u; ic < TW + 2u; ic++) {
        let sx = x + i32(ic) - 1;
        // Column ic of the (ROWS + 2)-row input window.
        let zero = vec4<f32>(0.0);
        let v0 = fetch(t, mode, sx, y0 + -1, at);
        let v1 = fetch(t, mode, sx, y0 + 0, at);
        let v2 = fetch(t, mode, sx, y0 + 1, at);
        var v3 = zero;
        if ROWS > 1u { v3 = fetch(t, mode, sx, y0 + 2, at); }
        var v4 = zero;
        if ROWS > 2u { v4 = fetch(t, mode, sx, y0 + 3, at); }
        var v5 = zero;
        if ROWS > 3u { v5 = fetch(t, mode, sx, y0 + 4, at); }
        var v6 = zero;
        if ROWS > 4u { v6 = fetch(t, mode, sx, y0 + 5, at); }
        var v7 = zero;
        if ROWS > 5u { v7 = fetch(t, mode, sx, y0 + 6, at); }
        var v8 = zero;
        if ROWS > 6u { v8 = fetch(t, mode, sx, y0 + 7, at); }
        var v9 = zero;
        if ROWS > 7u { v9 = fetch(t, mode, sx, y0 + 8, at); }
        var v10 = zero;
        if ROWS > 8u { v10 = fetch(t, mode, sx, y0 + 9, at); }
        var v11 = zero;
        if ROWS > 9u { v11 = fetch(t, mode, sx, y0 + 10, at); }
        var v12 = zero;
        if ROWS > 10u { v12 = fetch(t, mode, sx, y0 + 11, at); }
        var v13 = zero;
        if ROWS > 11u { v13 = fetch(t, mode, sx, y0 + 12, at); }
        var v14 = zero;
        if ROWS > 12u { v14 = fetch(t, mode, sx, y0 + 13, at); }
        var v15 = zero;
        if ROWS > 13u { v15 = fetch(t, mode, sx, y0 + 14, at); }
        var v16 = zero;
        if ROWS > 14u { v16 = fetch(t, mode, sx, y0 + 15, at); }
        var v17 = zero;
        if ROWS > 15u { v17 = fetch(t, mode, sx, y0 + 16, at); }
        // Tap (ky, kx) starts at w + ((cb * 9 + ky * 3 + kx) * 4) * OB.
        if ic < 3u {
            let base = w + (cb * 36u + ic * 4u) * OB;
            if LANES {
                add_column_lanes(acc0, acc1, acc2, acc3, base, v0, v1, v2, v3, v4, v5, v6, v7, v8, v9, v10, v11, v12, v13, v14, v15, v16, v17);
            } else {
                add_column(acc0, base, 0u, v0, v1, v2, v3, v4, v5, v6, v7, v8, v9, v10, v11, v12, v13, v14, v15, v16, v17);
                if OB > 1u {
                    add_column(acc1, base, 1u, v0, v1, v2, v3, v4, v5, v6, v7, v8, v9, v10, v11, v12, v13, v14, v15, v16, v17);
                }
                if OB > 2u {
                    add_column(acc2, base, 2u, v0, v1, v2, v3, v4, v5, v6, v7, v8, v9, v10, v11, v12, v13, v14, v15, v16, v17);
                    add_column(acc3, base, 3u, v0, v1, v2, v3, v4, v5, v6, v7, v8, v9, v10, v11, v12, v13, v14, v15, v16, v17);
                }
            }
        }
        if TW > 1u && ic > 0u {
            let base = w + (cb * 36u + (ic - 1u) * 4u) * OB;
            add_column(acc2, base, 0u, v0, v1, v2, v3, v4, v5, v6, v7, v8, v9, v10, v11, v12, v13, v14, v15, v16, v17);
            if OB > 1u {
                add_column(acc3, base, 1u, v0, v1, v2, v3, v4, v5, v6, v7, v8, v9, v10, v11, v12, v13, v14, v15, v16, v17);
            }
        }
    }
}

// A two-column lanes tile's step over one input block. This empty one is what every module
// has; kernels::Kernels::new swaps it (kernels::ROWS_STUB, the line below) for
// conv3x3_rows.wgsl's in the module that runs such tiles: that body is unrolled, and a front
// end that inlines it before dropping the dead branch spends seconds on every pipeline.
fn accumulate_rows(acc0: ptr<function, Tile>, acc1: ptr<function, Tile>, acc2: ptr<function, Tile>, acc3: ptr<function, Tile>, acc4: ptr<function, Tile>, acc5: ptr<function, Tile>, acc6: ptr<function, Tile>, acc7: ptr<function, Tile>, cb: u32, w: u32, x: i32, y0: i32) {}

// One output: activated into dst, or (SPLIT > 1) this part's raw sum into `partial`.
fn put(x: u32, y: u32, layer: u32, at: vec3<u32>, v: vec4<f32>) {
    if SPLIT > 1u {
        partial[((part * params.cout4 + layer) * params.height + y) * params.width + x] = v;
    } else {
        store_dst(vec2<u32>(x, y), at, activate(v));
    }
}

fn store(acc: Tile, x: u32, y0: u32, layer: u32) {
    // Rows past the bottom edge are dropped.
    let h = params.height;
    let at = dst_cell(layer);
    put(x, y0, layer, at, acc.r0);
    if ROWS > 1u && y0 + 1u < h { put(x, y0 + 1u, layer, at, acc.r1); }
    if ROWS > 2u && y0 + 2u < h { put(x, y0 + 2u, layer, at, acc.r2); }
    if ROWS > 3u && y0 + 3u < h { put(x, y0 + 3u, layer, at, acc.r3); }
    if ROWS > 4u && y0 + 4u < h { put(x, y0 + 4u, layer, at, acc.r4); }
    if ROWS > 5u && y0 + 5u < h { put(x, y0 + 5u, layer, at, acc.r5); }
    if ROWS > 6u && y0 + 6u < h { put(x, y0 + 6u, layer, at, acc.r6); }
    if ROWS > 7u && y0 + 7u < h { put(x, y0 + 7u, layer, at, acc.r7); }
    if ROWS > 8u && y0 + 8u < h { put(x, y0 + 8u, layer, at, acc.r8); }
    if ROWS > 9u && y0 + 9u < h { put(x, y0 + 9u, layer, at, acc.r9); }
    if ROWS > 10u && y0 + 10u < h { put(x, y0 + 10u, layer, at, acc.r10); }
    if ROWS > 11u && y0 + 11u < h { put(x, y0 + 11u, layer, at, acc.r11); }
    if ROWS > 12u && y0 + 12u < h { put(x, y0 + 12u, layer, at, acc.r12); }
    if ROWS > 13u && y0 + 13u < h { put(x, y0 + 13u, layer, at, acc.r13); }
    if ROWS > 14u && y0 + 14u < h { put(x, y0 + 14u, layer, at, acc.r14); }
    if ROWS > 15u && y0 + 15u < h { put(x, y0 + 15u, layer, at, acc.r15); }
}

// `pools`: one block's two columns `a` and `b` of rows y0 .. y0 + ROWS at columns x, x + 1,
// max-pooled into `pooled` at (x / 2, y0 / 2 + k). The max is taken before the activation and the
// clamp: both are non-decreasing, so it is pool.wgsl's max of the stored values (and rounding
// to f16 at the store is too). x and y0 are even and levels have even sizes (a multiple of 32
// at full resolution), so a window is whole once its top row is inside.
fn store_pooled(a: Tile, b: Tile, x: u32, y0: u32, layer: u32) {
    let h = params.height;
    let p = vec2<u32>(x / 2u, y0 / 2u);
    let at = pool_cell(layer);
    store_pool(p, at, activate(max(max(a.r0, a.r1), max(b.r0, b.r1))));
    if ROWS > 2u && y0 + 2u < h { store_pool(p + vec2<u32>(0u, 1u), at, activate(max(max(a.r2, a.r3), max(b.r2, b.r3)))); }
    if ROWS > 4u && y0 + 4u < h { store_pool(p + vec2<u32>(0u, 2u), at, activate(max(max(a.r4, a.r5), max(b.r4, b.r5)))); }
    if ROWS > 6u && y0 + 6u < h { store_pool(p + vec2<u32>(0u, 3u), at, activate(max(max(a.r6, a.r7), max(b.r6, b.r7)))); }
    if ROWS > 8u && y0 + 8u < h { store_pool(p + vec2<u32>(0u, 4u), at, activate(max(max(a.r8, a.r9), max(b.r8, b.r9)))); }
    if ROWS > 10u && y0 + 10u < h { store_pool(p + vec2<u32>(0u, 5u), at, activate(max(max(a.r10, a.r11), max(b.r10, b.r11)))); }
    if ROWS > 12u && y0 + 12u < h { store_pool(p + vec2<u32>(0u, 6u), at, activate(max(max(a.r12, a.r13), max(b.r12, b.r13)))); }
    if ROWS > 14u && y0 + 14u < h { store_pool(p + vec2<u32>(0u, 7u), at, activate(max(max(a.r14, a.r15), max(b.r14, b.r15)))); }
}

// Workgroup shape (64 invocations: 8 x 8, 16 x 4, 32 x 2 or 64 x 1; kernels::Tile::group_x):
// on the H100 the wider shapes win for most convs (tuned per conv on GPUs).
override WG_X: u32 = 8u;
override WG_Y: u32 = 8u;

@compute @workgroup_size(WG_X, WG_Y, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    conv(gid);
}

// `main` with LANES, in one-dimensional workgroups of WG_X x WG_Y invocations (subgroup
// builtins need them) laid out as main's.
@compute @workgroup_size(64, 1, 1)
fn lanes(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_id) l: vec3<u32>, @builtin(subgroup_invocation_id) sg: u32) {
    lane = sg;
    conv(vec3<u32>(wg.x * WG_X + l.x % WG_X, wg.y * WG_Y + l.x / WG_X, wg.z));
}

// What subgroupBroadcast becomes on devices without subgroups (kernels::WITHOUT_SUBGROUPS,
// which also drops the subgroup builtin): there `lanes` is never used.
fn no_subgroups(v: vec4<f32>, id: u32) -> vec4<f32> {
    return v;
}

// What subgroupAny becomes there.
fn no_subgroups_any(e: bool) -> bool {
    return e;
}

fn conv(gid: vec3<u32>) {
    let x = gid.x * TW;
    let y0 = gid.y * ROWS;
    // This workgroup's group: its first output block and its weights (uniform over the group),
    // and its part of the input blocks.
    let group = gid.z / SPLIT;
    part = gid.z % SPLIT;
    let ob0 = params.ob0 + group * OB;
    let w = group * params.group_stride;
    if ob0 >= params.cout4 {
        return;
    }
    // Invocations past the edge return, except with LANES where the subgroup has lanes inside:
    // a broadcast from an inactive lane is undefined, so they load weights for the others and
    // store nothing.
    let inside = x < params.width && y0 < params.height;
    if LANES {
        if !subgroupAny(inside) {
            return;
        }
    } else if !inside {
        return;
    }
    let bias_at = w + params.cin4_total * 36u * OB;
    // The bias goes into part 0's sum only.
    let with_bias = part == 0u;
    let b0 = select(vec4<f32>(0.0), weight(bias_at), with_bias);
    var acc0 = Tile(b0, b0, b0, b0, b0, b0, b0, b0, b0, b0, b0, b0, b0, b0, b0, b0);
    var acc1 = acc0;
    if OB > 1u {
        let b1 = select(vec4<f32>(0.0), weight(bias_at + 1u), with_bias);
        acc1 = Tile(b1, b1, b1, b1, b1, b1, b1, b1, b1, b1, b1, b1, b1, b1, b1, b1);
    }
    var acc2 = acc0;
    var acc3 = acc1;
    // Blocks 2 and 3 of a 4-block tile.
    if OB > 2u {
        let b2 = select(vec4<f32>(0.0), weight(bias_at + 2u), with_bias);
        acc2 = Tile(b2, b2, b2, b2, b2, b2, b2, b2, b2, b2, b2, b2, b2, b2, b2, b2);
        let b3 = select(vec4<f32>(0.0), weight(bias_at + 3u), with_bias);
        acc3 = Tile(b3, b3, b3, b3, b3, b3, b3, b3, b3, b3, b3, b3, b3, b3, b3, b3);
    }
    // Column 1 of a two-column lanes tile, blocks 0 to 3.
    var acc4 = acc0;
    var acc5 = acc1;
    var acc6 = acc2;
    var acc7 = acc3;
    let xi = i32(x);
    let yi = i32(y0);
    // This part's input blocks k0 .. k1 of cat(a, b) (all of them when SPLIT = 1).
    let total = params.cin4_a + params.cin4_b;
    let per = (total + SPLIT - 1u) / SPLIT;
    let k0 = part * per;
    let k1 = min(k0 + per, total);
    // Source a: input blocks 0 .. cin4_a; then source b: blocks cin4_a .. cin4_a + cin4_b. The
    // two-column lanes tiles take both in one loop (its body compiled once; `accumulate_rows`
    // picks the window's source per block), the others in two.
    if LANES && TW > 1u {
        for (var c = k0; c < k1; c++) {
            accumulate_rows(&acc0, &acc1, &acc2, &acc3, &acc4, &acc5, &acc6, &acc7, c, w, xi, yi);
        }
    } else {
        for (var c = k0; c < min(k1, params.cin4_a); c++) {
            accumulate(&acc0, &acc1, &acc2, &acc3, src_a, MODE_A, c, c, w, xi, yi);
        }
        if SOURCE_B {
            for (var c = max(k0, params.cin4_a); c < k1; c++) {
                accumulate(&acc0, &acc1, &acc2, &acc3, src_b, MODE_B, c - params.cin4_a, c, w, xi, yi);
            }
        }
    }
    if !inside {
        return;
    }
    let second = OB > 1u && ob0 + 1u < params.cout4;
    store(acc0, x, y0, ob0);
    if second {
        store(acc1, x, y0, ob0 + 1u);
    }
    if OB > 2u {
        if ob0 + 2u < params.cout4 { store(acc2, x, y0, ob0 + 2u); }
        if ob0 + 3u < params.cout4 { store(acc3, x, y0, ob0 + 3u); }
    }
    // The second column, unless it is past the right edge.
    if TW > 1u && x + 1u < params.width {
        if LANES {
            store(acc4, x + 1u, y0, ob0);
            if second {
                store(acc5, x + 1u, y0, ob0 + 1u);
            }
            if OB > 2u {
                if ob0 + 2u < params.cout4 { store(acc6, x + 1u, y0, ob0 + 2u); }
                if ob0 + 3u < params.cout4 { store(acc7, x + 1u, y0, ob0 + 3u); }
            }
            if pools() {
                store_pooled(acc0, acc4, x, y0, ob0);
                if second {
                    store_pooled(acc1, acc5, x, y0, ob0 + 1u);
                }
                if OB > 2u {
                    if ob0 + 2u < params.cout4 { store_pooled(acc2, acc6, x, y0, ob0 + 2u); }
                    if ob0 + 3u < params.cout4 { store_pooled(acc3, acc7, x, y0, ob0 + 3u); }
                }
            }
        } else {
            store(acc2, x + 1u, y0, ob0);
            if second {
                store(acc3, x + 1u, y0, ob0 + 1u);
            }
        }
    }
}

// Split-K's second pass: the SPLIT partial sums of each output, activated and clamped into dst
// (one invocation per output texel; the same bindings and parameters as the conv).
@compute @workgroup_size(8, 8, 1)
fn reduce(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= params.width || gid.y >= params.height || gid.z >= params.cout4 {
        return;
    }
    var sum = vec4<f32>(0.0);
    for (var p = 0u; p < SPLIT; p++) {
        sum += partial[((p * params.cout4 + gid.z) * params.height + gid.y) * params.width + gid.x];
    }
    store_dst(gid.xy, dst_cell(gid.z), activate(sum));
}

// ---- Winograd F(2x2, 3x3): entry point `winograd` ----
//
// The same convolution in 16 multiplies per 2x2 outputs and input channel instead of 36
// (Lavin & Gray 2016): each 4x4 input window d becomes V = B^T d B (additions only), V is
// multiplied element by element with the transformed taps U = G g G^T (kernels::winograd_taps,
// 16 instead of 9 per channel pair) and summed over input channels, and the 2x2 outputs are
// A^T M A (additions only). The transforms' coefficients are 0, +-1 (and +-1/2 in G, applied
// to the weights in f64 on the host), so the rounding is that of a few more additions.
//
// An invocation computes one 2x2 tile (ROWS = 2) or two stacked (ROWS = 4, sharing two input
// rows and every weight load) for OB output blocks; weights of input block cb and transformed
// position p (row-major in the 4x4) for output block j sit where the direct kernel's taps do,
// with 16 positions for its 9: w + ((cb * 16 + p) * 4 + lane) * OB + j, then OB biases.

// Four vec4s along a row of a 4x4 tile (input row after d B, or a row of V or M).
struct Quad {
    c0: vec4<f32>,
    c1: vec4<f32>,
    c2: vec4<f32>,
    c3: vec4<f32>,
}

// A 4x4 tile in the transformed domain (V of one input block, or M of one output block).
struct Wino {
    r0: Quad,
    r1: Quad,
    r2: Quad,
    r3: Quad,
}

fn quad_add(a: Quad, b: Quad) -> Quad {
    return Quad(a.c0 + b.c0, a.c1 + b.c1, a.c2 + b.c2, a.c3 + b.c3);
}

fn quad_sub(a: Quad, b: Quad) -> Quad {
    return Quad(a.c0 - b.c0, a.c1 - b.c1, a.c2 - b.c2, a.c3 - b.c3);
}

// Input row y at columns x - 1 .. x + 2, times B (B^T = [1 0 -1 0; 0 1 1 0; 0 -1 1 0; 0 1 0 -1]).
fn wino_row(t: Source, mode: u32, x: i32, y: i32, at: vec3<u32>) -> Quad {
    let d0 = fetch(t, mode, x - 1, y, at);
    let d1 = fetch(t, mode, x, y, at);
    let d2 = fetch(t, mode, x + 1, y, at);
    let d3 = fetch(t, mode, x + 2, y, at);
    return Quad(d0 - d2, d1 + d2, d2 - d1, d1 - d3);
}

// V = B^T (d B) from four consecutive rows of d B.
fn wino_v(e0: Quad, e1: Quad, e2: Quad, e3: Quad) -> Wino {
    return Wino(quad_sub(e0, e2), quad_add(e1, e2), quad_sub(e2, e1), quad_sub(e1, e3));
}

// Row i of M for tile a and (ROWS = 4) tile b.
struct QuadPair {
    a: Quad,
    b: Quad,
}

// Row i of M += U * V for output block j, in tile a (V row v) and, when ROWS = 4, in tile b
// (V row u) with the same four weight matrices; `base` is the row's first position.
fn wino_mac(a: Quad, b: Quad, base: u32, j: u32, v: Quad, u: Quad) -> QuadPair {
    let m0 = tap(base, j);
    let m1 = tap(base + 4u * OB, j);
    let m2 = tap(base + 8u * OB, j);
    let m3 = tap(base + 12u * OB, j);
    var r = QuadPair(Quad(mac(a.c0, m0, v.c0), mac(a.c1, m1, v.c1), mac(a.c2, m2, v.c2), mac(a.c3, m3, v.c3)), b);
    if ROWS > 2u {
        r.b = Quad(mac(b.c0, m0, u.c0), mac(b.c1, m1, u.c1), mac(b.c2, m2, u.c2), mac(b.c3, m3, u.c3));
    }
    return r;
}

// M += U * V over the whole 4x4 for output block j (tiles a and b as in wino_mac).
fn wino_tile(a: ptr<function, Wino>, b: ptr<function, Wino>, base: u32, j: u32, v: Wino, u: Wino) {
    let r0 = wino_mac((*a).r0, (*b).r0, base, j, v.r0, u.r0);
    let r1 = wino_mac((*a).r1, (*b).r1, base + 16u * OB, j, v.r1, u.r1);
    let r2 = wino_mac((*a).r2, (*b).r2, base + 32u * OB, j, v.r2, u.r2);
    let r3 = wino_mac((*a).r3, (*b).r3, base + 48u * OB, j, v.r3, u.r3);
    *a = Wino(r0.a, r1.a, r2.a, r3.a);
    *b = Wino(r0.b, r1.b, r2.b, r3.b);
}

// Add input block `layer` of `t` at weight block `cb` to the tiles whose top-left output is
// (x, y0): the upper tile in m0 (block 0) and m1 (block 1), the lower (ROWS = 4) in m2 and m3.
fn wino_accumulate(m0: ptr<function, Wino>, m1: ptr<function, Wino>, m2: ptr<function, Wino>, m3: ptr<function, Wino>, t: Source, mode: u32, layer: u32, cb: u32, w: u32, x: i32, y0: i32) {
    let base = w + cb * 64u * OB;
    let at = cell(mode, layer);
    let e0 = wino_row(t, mode, x, y0 - 1, at);
    let e1 = wino_row(t, mode, x, y0, at);
    let e2 = wino_row(t, mode, x, y0 + 1, at);
    let e3 = wino_row(t, mode, x, y0 + 2, at);
    let v = wino_v(e0, e1, e2, e3);
    var u = v;
    if ROWS > 2u {
        let e4 = wino_row(t, mode, x, y0 + 3, at);
        let e5 = wino_row(t, mode, x, y0 + 4, at);
        u = wino_v(e2, e3, e4, e5);
    }
    wino_tile(m0, m2, base, 0u, v, u);
    if OB > 1u {
        wino_tile(m1, m3, base, 1u, v, u);
    }
}

// Y = A^T M A (A^T = [1 1 1 0; 0 1 -1 -1]) plus the bias, stored at (x .. x + 1, y0 .. y0 + 1)
// where inside the output; where it `pools` (winograd_lanes only) also their max, activated, into
// `pooled` at (x / 2, y0 / 2), as `store_pooled` pools (x and y0 are even there, and levels have
// even sizes, so a tile inside is a whole 2x2 window).
fn wino_store(m: Wino, bias: vec4<f32>, x: u32, y0: u32, layer: u32) {
    // Row i of M times A: columns 0 and 1 of the 4x2 product.
    let s00 = m.r0.c0 + m.r0.c1 + m.r0.c2;
    let s01 = m.r0.c1 - m.r0.c2 - m.r0.c3;
    let s10 = m.r1.c0 + m.r1.c1 + m.r1.c2;
    let s11 = m.r1.c1 - m.r1.c2 - m.r1.c3;
    let s20 = m.r2.c0 + m.r2.c1 + m.r2.c2;
    let s21 = m.r2.c1 - m.r2.c2 - m.r2.c3;
    let s30 = m.r3.c0 + m.r3.c1 + m.r3.c2;
    let s31 = m.r3.c1 - m.r3.c2 - m.r3.c3;
    let o00 = bias + s00 + s10 + s20;
    let o01 = bias + s01 + s11 + s21;
    let o10 = bias + s10 - s20 - s30;
    let o11 = bias + s11 - s21 - s31;
    let right = x + 1u < params.width;
    let at = dst_cell(layer);
    store_dst(vec2<u32>(x, y0), at, activate(o00));
    if right { store_dst(vec2<u32>(x + 1u, y0), at, activate(o01)); }
    if y0 + 1u < params.height {
        store_dst(vec2<u32>(x, y0 + 1u), at, activate(o10));
        if right { store_dst(vec2<u32>(x + 1u, y0 + 1u), at, activate(o11)); }
    }
    if pools() {
        store_pool(vec2<u32>(x / 2u, y0 / 2u), pool_cell(layer), activate(max(max(o00, o01), max(o10, o11))));
    }
}

@compute @workgroup_size(WG_X, WG_Y, 1)
fn winograd(@builtin(global_invocation_id) gid: vec3<u32>) {
    let x = gid.x * 2u;
    let y0 = gid.y * ROWS;
    let ob0 = params.ob0 + gid.z * OB;
    let w = gid.z * params.group_stride;
    if x >= params.width || y0 >= params.height || ob0 >= params.cout4 {
        return;
    }
    let z = Quad(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
    var m0 = Wino(z, z, z, z);
    var m1 = m0;
    var m2 = m0;
    var m3 = m0;
    let xi = i32(x);
    let yi = i32(y0);
    for (var c = 0u; c < params.cin4_a; c++) {
        wino_accumulate(&m0, &m1, &m2, &m3, src_a, MODE_A, c, c, w, xi, yi);
    }
    if SOURCE_B {
        for (var c = 0u; c < params.cin4_b; c++) {
            wino_accumulate(&m0, &m1, &m2, &m3, src_b, MODE_B, c, params.cin4_a + c, w, xi, yi);
        }
    }
    let bias_at = w + params.cin4_total * 64u * OB;
    let second = OB > 1u && ob0 + 1u < params.cout4;
    wino_store(m0, weight(bias_at), x, y0, ob0);
    if second {
        wino_store(m1, weight(bias_at + 1u), x, y0, ob0 + 1u);
    }
    if ROWS > 2u && y0 + 2u < params.height {
        wino_store(m2, weight(bias_at), x, y0 + 2u, ob0);
        if second {
            wino_store(m3, weight(bias_at + 1u), x, y0 + 2u, ob0 + 1u);
        }
    }
}

// ---- Cooperative matrices: entry points `mma` and `mma_split` ----
//
// Appended to conv3x3_mma.wgsl by kernels::Kernels where the device has 16 x 16 x 16
// f16 -> f32 cooperative matrices and subgroups of 32 lanes (with `enable
// wgpu_cooperative_matrix;` added to the module's enables; kernels::matrix_units_supported):
// `mma_emulated`'s and `mma_split_emulated`'s products in the matrix units. Subgroup sg is invocations 32 sg .. 32 sg + 31
// of the one-dimensional workgroup, so sg is uniform over each subgroup, as the cooperative
// operations need. The accumulators are named, not an array, so that no driver has to prove
// an index constant to keep them in registers; tiles past NT sit behind `if NT > n`, which the
// override removes. `mma` is written for MT 4 (four pixel tiles a row), `mma_split` for MT 2.

alias Acc = coop_mat16x16<f32, C>;
alias TileA = coop_mat16x16<f16, A>;
alias TileB = coop_mat16x16<f16, B>;

// ---- generated: mma ----
@compute @workgroup_size(128, 1, 1)
fn mma(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let x0 = wg.x * pixels();
    let y0 = wg.y * ROWS;
    let w = wg.z * params.group_stride;
    let sg = li / 32u;
    let lane = li % 32u;
    // Accumulator (mt, nt): pixels 16 mt .. 16 mt + 15 of row y0 + sg x output tile nt.
    var c00 = Acc(); var c01 = Acc(); var c02 = Acc(); var c03 = Acc();
    var c10 = Acc(); var c11 = Acc(); var c12 = Acc(); var c13 = Acc();
    var c20 = Acc(); var c21 = Acc(); var c22 = Acc(); var c23 = Acc();
    var c30 = Acc(); var c31 = Acc(); var c32 = Acc(); var c33 = Acc();
    for (var c = 0u; c < chunks(); c++) {
        // The previous chunk's products are done before its window is overwritten.
        workgroupBarrier();
        stage_chunk(li, c, x0, y0);
        workgroupBarrier();
        for (var t = 0u; t < 9u; t++) {
            let ky = t / 3u;
            let kx = t % 3u;
            let a0 = coopLoadT<TileA>(&win[a_at(sg, 0u, ky, kx)], 16u);
            let a1 = coopLoadT<TileA>(&win[a_at(sg, 1u, ky, kx)], 16u);
            let a2 = coopLoadT<TileA>(&win[a_at(sg, 2u, ky, kx)], 16u);
            let a3 = coopLoadT<TileA>(&win[a_at(sg, 3u, ky, kx)], 16u);
            let b0 = coopLoadT<TileB>(&weights[b_at(w, c, t, 0u)], 16u);
            c00 = coopMultiplyAdd(a0, b0, c00);
            c10 = coopMultiplyAdd(a1, b0, c10);
            c20 = coopMultiplyAdd(a2, b0, c20);
            c30 = coopMultiplyAdd(a3, b0, c30);
            if NT > 1u {
                let b1 = coopLoadT<TileB>(&weights[b_at(w, c, t, 1u)], 16u);
                c01 = coopMultiplyAdd(a0, b1, c01);
                c11 = coopMultiplyAdd(a1, b1, c11);
                c21 = coopMultiplyAdd(a2, b1, c21);
                c31 = coopMultiplyAdd(a3, b1, c31);
            }
            if NT > 2u {
                let b2 = coopLoadT<TileB>(&weights[b_at(w, c, t, 2u)], 16u);
                c02 = coopMultiplyAdd(a0, b2, c02);
                c12 = coopMultiplyAdd(a1, b2, c12);
                c22 = coopMultiplyAdd(a2, b2, c22);
                c32 = coopMultiplyAdd(a3, b2, c32);
            }
            if NT > 3u {
                let b3 = coopLoadT<TileB>(&weights[b_at(w, c, t, 3u)], 16u);
                c03 = coopMultiplyAdd(a0, b3, c03);
                c13 = coopMultiplyAdd(a1, b3, c13);
                c23 = coopMultiplyAdd(a2, b3, c23);
                c33 = coopMultiplyAdd(a3, b3, c33);
            }
        }
    }
    // Each accumulator through this subgroup's part of `stage` to the output.
    workgroupBarrier();
    coopStoreT(c00, &stage[sg * TILE], 16u);
    workgroupBarrier();
    emit(sg, lane, 0u, 0u, x0, y0, wg.z);
    workgroupBarrier();
    coopStoreT(c10, &stage[sg * TILE], 16u);
    workgroupBarrier();
    emit(sg, lane, 1u, 0u, x0, y0, wg.z);
    workgroupBarrier();
    coopStoreT(c20, &stage[sg * TILE], 16u);
    workgroupBarrier();
    emit(sg, lane, 2u, 0u, x0, y0, wg.z);
    workgroupBarrier();
    coopStoreT(c30, &stage[sg * TILE], 16u);
    workgroupBarrier();
    emit(sg, lane, 3u, 0u, x0, y0, wg.z);
    if NT > 1u {
        workgroupBarrier();
        coopStoreT(c01, &stage[sg * TILE], 16u);
        workgroupBarrier();
        emit(sg, lane, 0u, 1u, x0, y0, wg.z);
        workgroupBarrier();
        coopStoreT(c11, &stage[sg * TILE], 16u);
        workgroupBarrier();
        emit(sg, lane, 1u, 1u, x0, y0, wg.z);
        workgroupBarrier();
        coopStoreT(c21, &stage[sg * TILE], 16u);
        workgroupBarrier();
        emit(sg, lane, 2u, 1u, x0, y0, wg.z);
        workgroupBarrier();
        coopStoreT(c31, &stage[sg * TILE], 16u);
        workgroupBarrier();
        emit(sg, lane, 3u, 1u, x0, y0, wg.z);
    }
    if NT > 2u {
        workgroupBarrier();
        coopStoreT(c02, &stage[sg * TILE], 16u);
        workgroupBarrier();
        emit(sg, lane, 0u, 2u, x0, y0, wg.z);
        workgroupBarrier();
        coopStoreT(c12, &stage[sg * TILE], 16u);
        workgroupBarrier();
        emit(sg, lane, 1u, 2u, x0, y0, wg.z);
        workgroupBarrier();
        coopStoreT(c22, &stage[sg * TILE], 16u);
        workgroupBarrier();
        emit(sg, lane, 2u, 2u, x0, y0, wg.z);
        workgroupBarrier();
        coopStoreT(c32, &stage[sg * TILE], 16u);
        workgroupBarrier();
        emit(sg, lane, 3u, 2u, x0, y0, wg.z);
    }
    if NT > 3u {
        workgroupBarrier();
        coopStoreT(c03, &stage[sg * TILE], 16u);
        workgroupBarrier();
        emit(sg, lane, 0u, 3u, x0, y0, wg.z);
        workgroupBarrier();
        coopStoreT(c13, &stage[sg * TILE], 16u);
        workgroupBarrier();
        emit(sg, lane, 1u, 3u, x0, y0, wg.z);
        workgroupBarrier();
        coopStoreT(c23, &stage[sg * TILE], 16u);
        workgroupBarrier();
        emit(sg, lane, 2u, 3u, x0, y0, wg.z);
        workgroupBarrier();
        coopStoreT(c33, &stage[sg * TILE], 16u);
        workgroupBarrier();
        emit(sg, lane, 3u, 3u, x0, y0, wg.z);
    }
}
// ---- end generated ----

// ---- Split operands in matrix units: entry point `mma_split` ----
//
// `mma_split_emulated`'s products in the matrix units (MT 2, NT 1 to 4): accumulator (mt, nt)
// is c<mt><nt> for the hi products and d<mt><nt> for the remainders' (hi(a) lo(b), and lo(a)
// hi(b) with SPLIT_A). At the store each pair is joined in the matrix registers, c + d /
// LO_SCALE (elementwise, as in the emulation), and goes out through `stage` as `mma`'s
// accumulators do. Two pixel tiles per row rather than
// `mma`'s four keep the window and its remainders in `win` (kernels::MMA_WORKGROUP_BYTES):
// with its own 12.7 KB array for the remainders (29.4 KB a workgroup) the H100 runs this
// kernel 2.5 times slower than `mma` (`docs/perf/h100-2026-11-24-s15.log`).

// ---- generated: mma_split ----
@compute @workgroup_size(128, 1, 1)
fn mma_split(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let x0 = wg.x * pixels();
    let y0 = wg.y * ROWS;
    let w = wg.z * params.group_stride;
    let sg = li / 32u;
    let lane = li % 32u;
    // Accumulators (mt, nt): pixels 16 mt .. 16 mt + 15 of row y0 + sg x output tile nt.
    var c00 = Acc(); var c01 = Acc(); var c02 = Acc(); var c03 = Acc();
    var c10 = Acc(); var c11 = Acc(); var c12 = Acc(); var c13 = Acc();
    var d00 = Acc(); var d01 = Acc(); var d02 = Acc(); var d03 = Acc();
    var d10 = Acc(); var d11 = Acc(); var d12 = Acc(); var d13 = Acc();
    for (var c = 0u; c < chunks(); c++) {
        // The previous chunk's products are done before its window is overwritten.
        workgroupBarrier();
        stage_chunk_split(li, c, x0, y0);
        workgroupBarrier();
        for (var t = 0u; t < 9u; t++) {
            let ky = t / 3u;
            let kx = t % 3u;
            let a0 = coopLoadT<TileA>(&win[a_at(sg, 0u, ky, kx)], 16u);
            let a1 = coopLoadT<TileA>(&win[a_at(sg, 1u, ky, kx)], 16u);
            var l0 = TileA();
            var l1 = TileA();
            if SPLIT_A {
                l0 = coopLoadT<TileA>(&win[lo_at() + a_at(sg, 0u, ky, kx)], 16u);
                l1 = coopLoadT<TileA>(&win[lo_at() + a_at(sg, 1u, ky, kx)], 16u);
            }
            let b0 = coopLoadT<TileB>(&weights[b_at(w, c, t, 0u)], 16u);
            let e0 = coopLoadT<TileB>(&weights[b_at(w, c, t, 0u) + lo_tiles()], 16u);
            c00 = coopMultiplyAdd(a0, b0, c00);
            c10 = coopMultiplyAdd(a1, b0, c10);
            d00 = coopMultiplyAdd(a0, e0, d00);
            d10 = coopMultiplyAdd(a1, e0, d10);
            if SPLIT_A {
                d00 = coopMultiplyAdd(l0, b0, d00);
                d10 = coopMultiplyAdd(l1, b0, d10);
            }
            if NT > 1u {
                let b1 = coopLoadT<TileB>(&weights[b_at(w, c, t, 1u)], 16u);
                let e1 = coopLoadT<TileB>(&weights[b_at(w, c, t, 1u) + lo_tiles()], 16u);
                c01 = coopMultiplyAdd(a0, b1, c01);
                c11 = coopMultiplyAdd(a1, b1, c11);
                d01 = coopMultiplyAdd(a0, e1, d01);
                d11 = coopMultiplyAdd(a1, e1, d11);
                if SPLIT_A {
                    d01 = coopMultiplyAdd(l0, b1, d01);
                    d11 = coopMultiplyAdd(l1, b1, d11);
                }
            }
            if NT > 2u {
                let b2 = coopLoadT<TileB>(&weights[b_at(w, c, t, 2u)], 16u);
                let e2 = coopLoadT<TileB>(&weights[b_at(w, c, t, 2u) + lo_tiles()], 16u);
                c02 = coopMultiplyAdd(a0, b2, c02);
                c12 = coopMultiplyAdd(a1, b2, c12);
                d02 = coopMultiplyAdd(a0, e2, d02);
                d12 = coopMultiplyAdd(a1, e2, d12);
                if SPLIT_A {
                    d02 = coopMultiplyAdd(l0, b2, d02);
                    d12 = coopMultiplyAdd(l1, b2, d12);
                }
            }
            if NT > 3u {
                let b3 = coopLoadT<TileB>(&weights[b_at(w, c, t, 3u)], 16u);
                let e3 = coopLoadT<TileB>(&weights[b_at(w, c, t, 3u) + lo_tiles()], 16u);
                c03 = coopMultiplyAdd(a0, b3, c03);
                c13 = coopMultiplyAdd(a1, b3, c13);
                d03 = coopMultiplyAdd(a0, e3, d03);
                d13 = coopMultiplyAdd(a1, e3, d13);
                if SPLIT_A {
                    d03 = coopMultiplyAdd(l0, b3, d03);
                    d13 = coopMultiplyAdd(l1, b3, d13);
                }
            }
        }
    }
    // Each pair of accumulators joined, through this subgroup's part of `stage` to the output.
    workgroupBarrier();
    coopStoreT(c00 + d00 * (1.0 / LO_SCALE), &stage[sg * TILE], 16u);
    workgroupBarrier();
    emit(sg, lane, 0u, 0u, x0, y0, wg.z);
    workgroupBarrier();
    coopStoreT(c10 + d10 * (1.0 / LO_SCALE), &stage[sg * TILE], 16u);
    workgroupBarrier();
    emit(sg, lane, 1u, 0u, x0, y0, wg.z);
    if NT > 1u {
        workgroupBarrier();
        coopStoreT(c01 + d01 * (1.0 / LO_SCALE), &stage[sg * TILE], 16u);
        workgroupBarrier();
        emit(sg, lane, 0u, 1u, x0, y0, wg.z);
        workgroupBarrier();
        coopStoreT(c11 + d11 * (1.0 / LO_SCALE), &stage[sg * TILE], 16u);
        workgroupBarrier();
        emit(sg, lane, 1u, 1u, x0, y0, wg.z);
    }
    if NT > 2u {
        workgroupBarrier();
        coopStoreT(c02 + d02 * (1.0 / LO_SCALE), &stage[sg * TILE], 16u);
        workgroupBarrier();
        emit(sg, lane, 0u, 2u, x0, y0, wg.z);
        workgroupBarrier();
        coopStoreT(c12 + d12 * (1.0 / LO_SCALE), &stage[sg * TILE], 16u);
        workgroupBarrier();
        emit(sg, lane, 1u, 2u, x0, y0, wg.z);
    }
    if NT > 3u {
        workgroupBarrier();
        coopStoreT(c03 + d03 * (1.0 / LO_SCALE), &stage[sg * TILE], 16u);
        workgroupBarrier();
        emit(sg, lane, 0u, 3u, x0, y0, wg.z);
        workgroupBarrier();
        coopStoreT(c13 + d13 * (1.0 / LO_SCALE), &stage[sg * TILE], 16u);
        workgroupBarrier();
        emit(sg, lane, 1u, 3u, x0, y0, wg.z);
    }
}
// ---- end generated ----

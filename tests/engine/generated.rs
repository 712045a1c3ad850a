//! The generator of the unrolled WGSL: the Winograd lanes steps `wino_step`
//! (conv3x3_wino.wgsl, F(2x2, 3x3)) and `wino4_step` (conv3x3_wino4.wgsl, F(4x4, 3x3)), whose
//! bodies are one product of a 4x4 weight matrix with a vec4 per tile position, output block
//! and stacked tile, and the cooperative-matrix entry points `mma` and `mma_split`
//! (conv3x3_mma_coop.wgsl), one named accumulator per pixel tile and output tile: written out
//! so that no driver keeps an indexable array in scratch memory.
//!
//! Each shader holds its step between the markers `// ---- generated: NAME ----` and
//! `// ---- end generated ----`. The test below holds the committed text to this generator's;
//! after changing the generator, write its output into the shaders with
//!
//!     RAE_REGENERATE=1 cargo test -p rae-core --test engine generated
//!
//! Layout, as `kernels::pack_group` packs the weights: per input block, position p of the
//! transformed tile (p = N i + c for N x N positions), input lane l and output block j, one
//! vec4 at `((cb * N * N + p) * 4 + l) * OB + j`. A gather (`gather`, 16 vec4s, one per lane)
//! therefore holds 4 / OB positions' matrices, and `ob<OB>_<k>` takes one from the lanes
//! (conv3x3_gather16.wgsl, conv3x3_gather8.wgsl).

use std::fmt::Write;
use std::path::PathBuf;

/// Where a generated function starts and ends in its shader.
fn markers(name: &str) -> (String, &'static str) {
    (format!("// ---- generated: {name} ----\n"), "// ---- end generated ----\n")
}

/// The broadcast that takes block `j` of position `p` from its gather, for `ob` output blocks.
fn broadcast(ob: usize, p: usize, j: usize) -> String {
    match ob {
        1 => format!("ob1_{}", p % 4),
        2 => format!("ob2_{}{j}", p % 2),
        _ => format!("ob4_{j}"),
    }
}

/// Positions per gather of 16 vec4s with `ob` output blocks.
fn per_gather(ob: usize) -> usize {
    4 / ob
}

/// `wino_step` of conv3x3_wino.wgsl: F(2x2, 3x3) on two stacked 2x2 output tiles (4 rows) x
/// `OB` blocks; its 16 positions in two loops of two tile rows (8 positions) each.
fn wino_step() -> String {
    let mut s = String::new();
    let tiles: Vec<String> = (0..2).flat_map(|t| (0..4).map(move |j| format!("m{t}{j}: ptr<function, Wino>"))).collect();
    writeln!(s, "fn wino_step({}, cb: u32, w: u32, x: i32, y0: i32) {{", tiles.join(", ")).unwrap();
    s += "    let k = window4(cb, x, y0);\n";
    for c in 0..4 {
        writeln!(s, "    let k{c} = k.k{c};").unwrap();
    }
    for r in 0..6 {
        writeln!(s, "    let e{r} = wino_row_of(k0.v{r}, k1.v{r}, k2.v{r}, k3.v{r});").unwrap();
    }
    s += "    let v0 = wino_v(e0, e1, e2, e3);\n";
    s += "    let v1 = wino_v(e2, e3, e4, e5);\n";
    s += "    let g = wino_gather(w + cb * 64u * OB);\n";
    s += "    // Position p = 4 i + c of each tile (Wino's r<i>.c<c>), block by block; tile rows 0\n";
    s += "    // and 1, then 2 and 3, each pair in a loop that runs once: a basic block of its own\n";
    s += "    // for LLVM (conv_common.wgsl's `once`).\n";
    for (k, ob) in [1, 2, 4].into_iter().enumerate() {
        s += match k {
            0 => "    if OB == 1u {\n",
            1 => "    } else if OB == 2u {\n",
            _ => "    } else {\n",
        };
        for half in 0..2 {
            s += "        loop {\n";
            for p in 8 * half..8 * half + 8 {
                let (i, c) = (p / 4, p % 4);
                for j in 0..ob {
                    let u = broadcast(ob, p, j);
                    let gi = p / per_gather(ob);
                    let mac = |t: usize| format!("(*m{t}{j}).r{i}.c{c} = mac((*m{t}{j}).r{i}.c{c}, u, v{t}.r{i}.c{c});");
                    writeln!(s, "            {{ let u = {u}(g.g{gi});").unwrap();
                    writeln!(s, "              {} {} }}", mac(0), mac(1)).unwrap();
                }
            }
            s += "            continuing { break if once(); }\n";
            s += "        }\n";
        }
    }
    s += "    }\n}\n";
    s
}

/// `wino4_step` of conv3x3_wino4.wgsl: F(4x4, 3x3) on one 4x4 output tile (4 rows) x `OB`
/// blocks; its 36 positions in three loops of two tile rows (12 positions) each, each gather
/// loaded just before the positions it holds.
fn wino4_step() -> String {
    let mut s = String::new();
    let tiles: Vec<String> = (0..4).map(|j| format!("m0{j}: ptr<function, Wino6>")).collect();
    writeln!(s, "fn wino4_step({}, cb: u32, w: u32, x: i32, y0: i32) {{", tiles.join(", ")).unwrap();
    s += "    var k: Window6;\n";
    s += "    if !SOURCE_B || cb < params.cin4_a {\n";
    s += "        k = window6(src_a, MODE_A, cb, x, y0);\n";
    s += "    } else {\n";
    s += "        k = window6(src_b, MODE_B, cb - params.cin4_a, x, y0);\n";
    s += "    }\n";
    for c in 0..6 {
        writeln!(s, "    let k{c} = k.k{c};").unwrap();
    }
    for r in 0..6 {
        writeln!(s, "    let e{r} = hex_b(k0.v{r}, k1.v{r}, k2.v{r}, k3.v{r}, k4.v{r}, k5.v{r});").unwrap();
    }
    s += "    let v0 = wino6_v(e0, e1, e2, e3, e4, e5);\n";
    s += "    let base = w + cb * 144u * OB;\n";
    s += "    // Position p = 6 i + c of the tile (Wino6's r<i>.c<c>), block by block; tile rows 0 and\n";
    s += "    // 1, 2 and 3, 4 and 5, each pair in a loop that runs once: a basic block of its own for\n";
    s += "    // LLVM (conv_common.wgsl's `once`).\n";
    for (k, ob) in [1, 2, 4].into_iter().enumerate() {
        s += match k {
            0 => "    if OB == 1u {\n",
            1 => "    } else if OB == 2u {\n",
            _ => "    } else {\n",
        };
        let n = per_gather(ob);
        for third in 0..3 {
            s += "        loop {\n";
            for first in (12 * third..12 * third + 12).step_by(n) {
                s += "            {\n";
                writeln!(s, "            let g = gather(base + {}u);", 16 * (first / n)).unwrap();
                for p in first..first + n {
                    let (i, c) = (p / 6, p % 6);
                    for j in 0..ob {
                        let u = broadcast(ob, p, j);
                        writeln!(s, "            {{ let u = {u}(g); (*m0{j}).r{i}.c{c} = mac((*m0{j}).r{i}.c{c}, u, v0.r{i}.c{c}); }}")
                            .unwrap();
                    }
                }
                s += "            }\n";
            }
            s += "            continuing { break if once(); }\n";
            s += "        }\n";
        }
    }
    s += "    }\n}\n";
    s
}

/// The store of accumulator (`mt`, `nt`) through the subgroup's part of `stage`: `value` is
/// what goes in (the accumulator, or a split pair joined).
fn emit(s: &mut String, indent: &str, value: &str, mt: usize, nt: usize) {
    writeln!(s, "{indent}workgroupBarrier();").unwrap();
    writeln!(s, "{indent}coopStoreT({value}, &stage[sg * TILE], 16u);").unwrap();
    writeln!(s, "{indent}workgroupBarrier();").unwrap();
    writeln!(s, "{indent}emit(sg, lane, {mt}u, {nt}u, x0, y0, wg.z);").unwrap();
}

/// The opening of the two cooperative entry points, up to their accumulators.
fn coop_head(s: &mut String, name: &str) {
    s.push_str("@compute @workgroup_size(128, 1, 1)\n");
    writeln!(s, "fn {name}(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {{").unwrap();
    s.push_str("    let x0 = wg.x * pixels();\n    let y0 = wg.y * ROWS;\n    let w = wg.z * params.group_stride;\n");
    s.push_str("    let sg = li / 32u;\n    let lane = li % 32u;\n");
}

/// The accumulators `prefix<mt><nt>`, a row of four per `mt`.
fn accumulators(s: &mut String, prefix: char, mts: usize) {
    for mt in 0..mts {
        let row: Vec<String> = (0..4).map(|nt| format!("var {prefix}{mt}{nt} = Acc();")).collect();
        writeln!(s, "    {}", row.join(" ")).unwrap();
    }
}

/// The chunk loop's opening: the window staged by `stage` between two barriers, then the taps.
fn chunk_loop(s: &mut String, stage: &str) {
    s.push_str("    for (var c = 0u; c < chunks(); c++) {\n");
    s.push_str("        // The previous chunk's products are done before its window is overwritten.\n");
    writeln!(s, "        workgroupBarrier();\n        {stage}(li, c, x0, y0);\n        workgroupBarrier();").unwrap();
    s.push_str("        for (var t = 0u; t < 9u; t++) {\n            let ky = t / 3u;\n            let kx = t % 3u;\n");
}

/// `mma` of conv3x3_mma_coop.wgsl: 4 pixel tiles (MT) x up to 4 output tiles (NT) of 16 x 16
/// accumulators in the matrix units, the tiles past NT behind `if NT > n`.
fn mma() -> String {
    let mut s = String::new();
    coop_head(&mut s, "mma");
    s.push_str("    // Accumulator (mt, nt): pixels 16 mt .. 16 mt + 15 of row y0 + sg x output tile nt.\n");
    accumulators(&mut s, 'c', 4);
    chunk_loop(&mut s, "stage_chunk");
    for mt in 0..4 {
        writeln!(s, "            let a{mt} = coopLoadT<TileA>(&win[a_at(sg, {mt}u, ky, kx)], 16u);").unwrap();
    }
    for nt in 0..4 {
        let ind = if nt == 0 { "            " } else { "                " };
        if nt > 0 {
            writeln!(s, "            if NT > {nt}u {{").unwrap();
        }
        writeln!(s, "{ind}let b{nt} = coopLoadT<TileB>(&weights[b_at(w, c, t, {nt}u)], 16u);").unwrap();
        for mt in 0..4 {
            writeln!(s, "{ind}c{mt}{nt} = coopMultiplyAdd(a{mt}, b{nt}, c{mt}{nt});").unwrap();
        }
        if nt > 0 {
            s.push_str("            }\n");
        }
    }
    s.push_str("        }\n    }\n");
    s.push_str("    // Each accumulator through this subgroup's part of `stage` to the output.\n");
    for nt in 0..4 {
        let ind = if nt == 0 { "    " } else { "        " };
        if nt > 0 {
            writeln!(s, "    if NT > {nt}u {{").unwrap();
        }
        for mt in 0..4 {
            emit(&mut s, ind, &format!("c{mt}{nt}"), mt, nt);
        }
        if nt > 0 {
            s.push_str("    }\n");
        }
    }
    s.push_str("}\n");
    s
}

/// `mma_split` of conv3x3_mma_coop.wgsl: 2 pixel tiles x up to 4 output tiles, each a pair of
/// accumulators (c: hi products, d: the remainders'), joined at the store.
fn mma_split() -> String {
    let mut s = String::new();
    coop_head(&mut s, "mma_split");
    s.push_str("    // Accumulators (mt, nt): pixels 16 mt .. 16 mt + 15 of row y0 + sg x output tile nt.\n");
    accumulators(&mut s, 'c', 2);
    accumulators(&mut s, 'd', 2);
    chunk_loop(&mut s, "stage_chunk_split");
    for mt in 0..2 {
        writeln!(s, "            let a{mt} = coopLoadT<TileA>(&win[a_at(sg, {mt}u, ky, kx)], 16u);").unwrap();
    }
    s.push_str("            var l0 = TileA();\n            var l1 = TileA();\n            if SPLIT_A {\n");
    for mt in 0..2 {
        writeln!(s, "                l{mt} = coopLoadT<TileA>(&win[lo_at() + a_at(sg, {mt}u, ky, kx)], 16u);").unwrap();
    }
    s.push_str("            }\n");
    for nt in 0..4 {
        let ind = if nt == 0 { "            " } else { "                " };
        if nt > 0 {
            writeln!(s, "            if NT > {nt}u {{").unwrap();
        }
        writeln!(s, "{ind}let b{nt} = coopLoadT<TileB>(&weights[b_at(w, c, t, {nt}u)], 16u);").unwrap();
        writeln!(s, "{ind}let e{nt} = coopLoadT<TileB>(&weights[b_at(w, c, t, {nt}u) + lo_tiles()], 16u);").unwrap();
        for mt in 0..2 {
            writeln!(s, "{ind}c{mt}{nt} = coopMultiplyAdd(a{mt}, b{nt}, c{mt}{nt});").unwrap();
        }
        for mt in 0..2 {
            writeln!(s, "{ind}d{mt}{nt} = coopMultiplyAdd(a{mt}, e{nt}, d{mt}{nt});").unwrap();
        }
        writeln!(s, "{ind}if SPLIT_A {{").unwrap();
        for mt in 0..2 {
            writeln!(s, "{ind}    d{mt}{nt} = coopMultiplyAdd(l{mt}, b{nt}, d{mt}{nt});").unwrap();
        }
        writeln!(s, "{ind}}}").unwrap();
        if nt > 0 {
            s.push_str("            }\n");
        }
    }
    s.push_str("        }\n    }\n");
    s.push_str("    // Each pair of accumulators joined, through this subgroup's part of `stage` to the output.\n");
    for nt in 0..4 {
        let ind = if nt == 0 { "    " } else { "        " };
        if nt > 0 {
            writeln!(s, "    if NT > {nt}u {{").unwrap();
        }
        for mt in 0..2 {
            emit(&mut s, ind, &format!("c{mt}{nt} + d{mt}{nt} * (1.0 / LO_SCALE)"), mt, nt);
        }
        if nt > 0 {
            s.push_str("    }\n");
        }
    }
    s.push_str("}\n");
    s
}

/// Each generated function: its shader file (under `shaders/`), its name, its text.
fn generated() -> [(&'static str, &'static str, String); 4] {
    [
        ("conv3x3_wino.wgsl", "wino_step", wino_step()),
        ("conv3x3_wino4.wgsl", "wino4_step", wino4_step()),
        ("conv3x3_mma_coop.wgsl", "mma", mma()),
        ("conv3x3_mma_coop.wgsl", "mma_split", mma_split()),
    ]
}

/// `file`'s text with the region of `name` replaced by `body`.
fn with_region(file: &str, text: &str, name: &str, body: &str) -> String {
    let (begin, end) = markers(name);
    let start = text.find(&begin).unwrap_or_else(|| panic!("{file} has the marker {begin:?}")) + begin.len();
    let stop = start + text[start..].find(end).unwrap_or_else(|| panic!("{file} ends the region of {name}"));
    format!("{}{body}{}", &text[..start], &text[stop..])
}

#[test]
fn generated_wgsl_matches_its_generator() {
    let shaders = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shaders");
    let regenerate = std::env::var_os("RAE_REGENERATE").is_some();
    for (file, name, body) in generated() {
        let path = shaders.join(file);
        let text = std::fs::read_to_string(&path).unwrap();
        let want = with_region(file, &text, name, &body);
        if regenerate {
            std::fs::write(&path, &want).unwrap();
            continue;
        }
        assert!(
            text == want,
            "{file}: `{name}` differs from tests/engine/generated.rs's output; run RAE_REGENERATE=1 cargo test -p rae-core --test engine generated"
        );
        // The table the crate compiles in is the file as committed.
        assert_eq!(rae_core::kernels::shader_source(file.trim_end_matches(".wgsl")), want, "{file} as compiled in");
    }
}

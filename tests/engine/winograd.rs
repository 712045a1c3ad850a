//! The Winograd tiles (F(2x2) direct and across the subgroup, F(4x4) across the subgroup)
//! against the CPU implementation and each other, and their weight transforms.

use rae_core::graph::Read;
use rae_core::kernels::{self, ConvSpec, Kernels, Tile, WeightMemory};

use crate::gpu;
use crate::kernels::*;

#[test]
fn conv_winograd_tiles_match_cpu() {
    // Every Winograd tile (one or two stacked 2x2 output tiles, one or two output blocks), with
    // both weight memories and every read mode, on levels of odd width and height (partial tiles
    // on both edges); 11 outputs make a partial last group of 2-block tiles.
    let cases = [
        (2, 1, WeightMemory::Uniform, 8),
        (2, 2, WeightMemory::Storage, 32),
        (4, 1, WeightMemory::Storage, 16),
        (4, 2, WeightMemory::Uniform, 64),
    ];
    for (i, (rows, blocks, memory, group)) in cases.into_iter().enumerate() {
        let tile = Tile::winograd(rows, blocks).and_then(|t| t.with_group(group)).expect("a Winograd tile");
        assert_eq!((tile.cols, tile.taps()), (2, 16));
        check_conv_case(i, 200 + 3 * i as u64, tile, memory);
    }
    // One row: the level of a deep conv on a small frame.
    check_conv_tile((tensor(9, 1, 11, 230), Read::Direct), None, 8, true, 11, 1, 231, Tile::winograd(4, 2).unwrap(), WeightMemory::Storage);
    // The widest input a Winograd chunk holds (252 channels, 63 blocks, one output block).
    check_conv_tile(
        (tensor(128, 9, 13, 232), Read::Direct),
        Some((tensor(124, 9, 13, 233), Read::Direct)),
        5,
        true,
        13,
        9,
        234,
        Tile::winograd(2, 2).unwrap(),
        WeightMemory::Uniform,
    );
    assert_eq!(Tile::winograd(8, 1), None);
    assert_eq!(Tile::winograd(2, 3), None);
    assert_eq!(Tile::winograd(4, 1).unwrap().to_string(), "wino4x1");
}

#[test]
fn conv_winograd_lanes_tiles_match_cpu_and_the_winograd_tiles() {
    // Winograd with its weights across the subgroup: two stacked 2x2 tiles, one, two and four
    // blocks, both weight memories and every read mode, on levels 13 and 22 wide and 19
    // and 12 high (partial tiles on both edges, lanes past them loading for the others).
    let g = gpu();
    let wl = |rows, blocks| Tile::winograd_lanes(rows, blocks).expect("a Winograd lanes tile");
    if !kernels::winograd_lanes_supported(&g.device) {
        refused_without_8_lanes(wl(4, 2));
        return;
    }
    let cases = [
        (wl(4, 2), WeightMemory::Uniform),
        (wl(4, 1).with_group(32).unwrap(), WeightMemory::Storage),
        (wl(4, 4), WeightMemory::Storage),
        (wl(4, 2), WeightMemory::Storage),
        (wl(4, 4), WeightMemory::Uniform),
        (wl(4, 1), WeightMemory::Uniform),
    ];
    for (i, (tile, memory)) in cases.into_iter().enumerate() {
        assert_eq!((tile.cols, tile.taps()), (2, 16));
        check_conv_case(i, 800 + 3 * i as u64, tile, memory);
    }
    // One row: a deep level of a small frame.
    check_conv_tile((tensor(9, 1, 11, 830), Read::Direct), None, 8, true, 11, 1, 831, wl(4, 4), WeightMemory::Storage);
    // The same transforms and sums in the same order as `winograd`'s: bit-identical.
    let (a, b) = (tensor(6, 38, 26, 840), tensor(5, 19, 13, 841));
    let (weight, bias) = (noise(11 * 11 * 9, 842), noise(11, 843));
    let run = |tile| gpu_conv((&a, Read::Pool), Some((&b, Read::Direct)), &weight, &bias, true, 13, 19, tile, WeightMemory::Uniform).data;
    let wino = run(Tile::winograd(4, 2).unwrap());
    assert_eq!(run(wl(4, 2)), wino, "winolanes4x2 against wino4x2");
    assert_eq!(run(wl(4, 4)), wino, "winolanes4x4 against wino4x2");
    // Its pooled output is the 2x2 max of its output, bit for bit (the pool pass's).
    pools_as_the_pool_pass(wl(4, 4), 850);
    assert_eq!(wl(4, 2).to_string(), "winolanes4x2");
    assert_eq!(Tile::CPU_WINOGRAD, wl(4, 4), "the CPU drivers' Winograd tile is one the kernel has");
    assert_eq!(Tile::winograd_lanes(2, 1), None);
    assert_eq!(Tile::winograd_lanes(8, 1), None);
    assert_eq!(Tile::winograd_lanes(4, 3), None);
    assert_eq!(wl(4, 2).with_split(2), None);
}

#[test]
fn conv_winograd4_lanes_tiles_match_cpu_and_pool_their_output() {
    // Winograd F(4x4, 3x3) with its weights in the plan's weight texture, across the subgroup:
    // one 4x4 tile, one, two and four blocks, either weight memory (the texture serves both
    // layouts) and every read mode, on levels 13 and 22 wide (4-column tiles with 1
    // and 2 columns inside) and 19 and 12 high, against the float64 sum.
    let g = gpu();
    let w4 = |rows, blocks| Tile::winograd4_lanes(rows, blocks).expect("a Winograd F(4x4) lanes tile");
    if !kernels::winograd_lanes_supported(&g.device) {
        refused_without_8_lanes(w4(4, 4));
        return;
    }
    // Every output-block count (every broadcast of the gathers), each weight memory.
    let cases = [
        (w4(4, 4), WeightMemory::Storage),
        (w4(4, 1).with_group(32).unwrap(), WeightMemory::Uniform),
        (w4(4, 2), WeightMemory::Uniform),
        (w4(4, 4), WeightMemory::Uniform),
    ];
    for (i, (tile, memory)) in cases.into_iter().enumerate() {
        assert_eq!((tile.cols, tile.taps()), (4, 36));
        check_conv_case(i, 900 + 3 * i as u64, tile, memory);
    }
    // The CPU drivers' own F(4x4) tile (Tile::cpu_for) for the rest.
    let cpu = Tile::CPU_WINOGRAD4;
    // One row (a deep level of a small frame), and 30 input blocks with uniform weights, more
    // than a 64 KiB chunk holds of them: the texture has no chunk limit.
    check_conv_tile((tensor(9, 1, 11, 930), Read::Direct), None, 8, true, 11, 1, 931, cpu, WeightMemory::Storage);
    check_conv_tile(
        (tensor(60, 10, 9, 932), Read::Direct),
        Some((tensor(60, 10, 9, 933), Read::Direct)),
        13,
        false,
        9,
        10,
        934,
        cpu,
        WeightMemory::Uniform,
    );
    // Its pooled output is the 2x2 max of its output, bit for bit, with the last column of tiles
    // half outside the level.
    pools_as_the_pool_pass(cpu, 950);
    assert_eq!(w4(4, 2).to_string(), "wino4lanes4x2");
    assert_eq!(Tile::CPU_WINOGRAD4, w4(4, 4), "the CPU drivers' F(4x4) tile is one the kernel has");
    assert_eq!(Tile::winograd4_lanes(2, 1), None);
    assert_eq!(Tile::winograd4_lanes(8, 4), None);
    assert_eq!(Tile::winograd4_lanes(4, 3), None);
    assert_eq!(w4(4, 2).with_split(2), None);
}

#[test]
fn gathers_in_8_lanes_are_the_16_lane_ones_bit_for_bit() {
    // conv3x3_gather8.wgsl, the Winograd lanes kernels' gathers on 8-lane subgroups (lavapipe
    // without AVX-512), loads each gather of 16 vec4s in two loads of 8 and broadcasts every
    // vec4 from where it landed: the outputs are conv3x3_gather16.wgsl's bit for bit. Held where
    // the device's subgroups have 16 lanes or more and so run both (Kernels::gather_in_8_lanes);
    // on 8 lanes the sweeps above hold the 8-lane gathers to the CPU and to `winograd`. F(2x2)
    // with two and four blocks takes the ob2 and ob4 broadcasts, F(4x4) with one the ob1 ones.
    let g = gpu();
    let dev = &g.device;
    if kernels::narrow_gathers(dev) || !kernels::winograd_lanes_supported(dev) {
        return;
    }
    let (w, h, cout) = (22usize, 13usize, 11usize);
    let (a, b) = (tensor(7, h, w, 970), tensor(5, h, w, 971));
    let (weight, bias) = (noise(cout * 12 * 9, 972), noise(cout, 973));
    let (ta, tb) = (upload(&a), upload(&b));
    let tiles = [
        Tile::winograd_lanes(4, 2).expect("an F(2x2) tile"),
        Tile::winograd_lanes(4, 4).expect("an F(2x2) tile"),
        Tile::winograd4_lanes(4, 1).expect("an F(4x4) tile"),
    ];
    let spec = ConvSpec { cb: b.c, ..one_source_spec("gathers", w as u32, h as u32, a.c, &weight, &bias) };
    // Each tile's output texels, with the gathers in loads of 8 lanes or of 16.
    let run = |in_8_lanes: bool| -> Vec<Vec<u32>> {
        let mut k = Kernels::new(dev, kernels::Precision::F32, WeightMemory::Storage);
        if in_8_lanes {
            k.gather_in_8_lanes();
        }
        outputs_per_tile(&mut k, spec, &tiles, &ta, &tb)
    };
    let (wide, narrow) = (run(false), run(true));
    for ((tile, wide), narrow) in tiles.iter().zip(&wide).zip(&narrow) {
        assert!(wide.iter().any(|&v| v != 0), "{tile} wrote its output");
        assert_eq!(narrow, wide, "{tile}: 8-lane gathers against 16-lane ones");
    }
}

#[test]
fn winograd_weight_transform_reproduces_the_direct_convolution() {
    // G g G^T on the host: for a 4x4 input patch d, A^T [(G g G^T) * (B^T d B)] A
    // equals the 2x2 direct correlation of d with g.
    let g: Vec<f32> = noise(9, 300);
    let d: Vec<f64> = noise(16, 301).iter().map(|&v| v as f64).collect();
    let u = kernels::winograd_taps(&g);
    let bt = [[1.0, 0.0, -1.0, 0.0], [0.0, 1.0, 1.0, 0.0], [0.0, -1.0, 1.0, 0.0], [0.0, 1.0, 0.0, -1.0]];
    let at = [[1.0, 1.0, 1.0, 0.0], [0.0, 1.0, -1.0, -1.0]];
    let v = |i: usize, j: usize| -> f64 {
        (0..4).flat_map(|r| (0..4).map(move |c| (r, c))).map(|(r, c)| bt[i][r] * d[r * 4 + c] * bt[j][c]).sum()
    };
    for y in 0..2 {
        for x in 0..2 {
            let wino: f64 = (0..16).map(|p| at[y][p / 4] * u[p] as f64 * v(p / 4, p % 4) * at[x][p % 4]).sum();
            let direct: f64 = (0..9).map(|t| g[t] as f64 * d[(y + t / 3) * 4 + x + t % 3]).sum();
            assert!((wino - direct).abs() < 1e-6 * (1.0 + direct.abs()), "output ({x}, {y}): {wino} vs {direct}");
        }
    }
}

#[test]
fn winograd4_weight_transform_reproduces_the_direct_convolution() {
    // The same for F(4x4, 3x3): a 6x6 patch, the kernel's B^T and A^T (conv3x3_wino4.wgsl),
    // 4x4 outputs. The transformed weights are rounded to f32 and A^T has 8s, so it holds to 1e-5.
    let g: Vec<f32> = noise(9, 310);
    let d: Vec<f64> = noise(36, 311).iter().map(|&v| v as f64).collect();
    let u = kernels::winograd4_taps(&g);
    let bt = [
        [4.0, 0.0, -5.0, 0.0, 1.0, 0.0],
        [0.0, -4.0, -4.0, 1.0, 1.0, 0.0],
        [0.0, 4.0, -4.0, -1.0, 1.0, 0.0],
        [0.0, -2.0, -1.0, 2.0, 1.0, 0.0],
        [0.0, 2.0, -1.0, -2.0, 1.0, 0.0],
        [0.0, 4.0, 0.0, -5.0, 0.0, 1.0],
    ];
    let at = [
        [1.0, 1.0, 1.0, 1.0, 1.0, 0.0],
        [0.0, 1.0, -1.0, 2.0, -2.0, 0.0],
        [0.0, 1.0, 1.0, 4.0, 4.0, 0.0],
        [0.0, 1.0, -1.0, 8.0, -8.0, 1.0],
    ];
    let v = |i: usize, j: usize| -> f64 {
        (0..6).flat_map(|r| (0..6).map(move |c| (r, c))).map(|(r, c)| bt[i][r] * d[r * 6 + c] * bt[j][c]).sum()
    };
    for y in 0..4 {
        for x in 0..4 {
            let wino: f64 = (0..36).map(|p| at[y][p / 6] * u[p] as f64 * v(p / 6, p % 6) * at[x][p % 6]).sum();
            let direct: f64 = (0..9).map(|t| g[t] as f64 * d[(y + t / 3) * 6 + x + t % 3]).sum();
            assert!((wino - direct).abs() < 1e-5 * (1.0 + direct.abs()), "output ({x}, {y}): {wino} vs {direct}");
        }
    }
}

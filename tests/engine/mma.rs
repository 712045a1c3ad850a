//! The matrix-unit tiles (emulated where the device has no cooperative matrices) against the
//! CPU implementation, and their weight layout.

use rae_core::cpu::{self, Chw};
use rae_core::graph::Read;
use rae_core::kernels::{self, ConvPlan, ConvSpec, Kernels, Tile, WeightMemory};

use crate::kernels::*;
use crate::{Tolerance, gpu};

/// An Mma conv ([`Tile::mma`]) against the CPU convolution of f16-rounded inputs and weights:
/// the kernel multiplies f16 values (exactly, in f32) and sums in f32, so with the rounding of
/// its operands reproduced on the CPU it is held to the direct kernel's tolerance.
#[allow(clippy::too_many_arguments)]
fn check_conv_mma(a: (Chw, Read), b: Option<(Chw, Read)>, cout: usize, leaky: bool, w: usize, h: usize, seed: u64, tile: Tile) {
    let cin = a.0.c + b.as_ref().map_or(0, |b| b.0.c);
    let rel = 1e-5 * ((9 * cin) as f32 / 100.0).sqrt().max(1.0);
    let weight: Vec<f32> = noise(cout * cin * 9, seed).iter().map(|v| v * 0.3).collect();
    let bias = noise(cout, seed + 1);
    let got = gpu_conv((&a.0, a.1), b.as_ref().map(|b| (&b.0, b.1)), &weight, &bias, leaky, w, h, tile, WeightMemory::Storage);
    let f16 = |v: &f32| half::f16::from_f32(*v).to_f32();
    let ra = cpu::read(&a.0, a.1, h, w);
    let mut x = match &b {
        Some((t, m)) => cpu::concat(&ra, &cpu::read(t, *m, h, w)),
        None => ra,
    };
    x.data = x.data.iter().map(f16).collect();
    let weight16: Vec<f32> = weight.iter().map(f16).collect();
    let want = cpu::conv3x3(&x, &weight16, &bias, leaky.then_some(0.1));
    crate::assert_close(
        Tolerance { rel },
        &format!("mma conv {:?}/{:?} {w}x{h} tile {tile}", a.1, b.as_ref().map(|b| b.1)),
        &got.data,
        &want.data,
    );
    // And the products' rounding is what separates it from the f32 convolution.
    let exact = cpu::conv3x3(&x, &weight, &bias, leaky.then_some(0.1));
    assert!(got.data.iter().zip(&exact.data).any(|(g, e)| g != e), "f16 weights change some output");
}

#[test]
fn conv_mma_tiles_match_cpu() {
    // The matrix-unit kernel (emulated here unless the device has cooperative matrices), on
    // levels spanning partial 64-pixel and 4-row workgroups. 43 outputs: 3 tiles of 16, the
    // last partial, in groups of 2 (the second half empty) with mma32; a pooled source and a
    // direct one (11 + 6 blocks: 5 chunks of 16 channels, the last partial).
    check_conv_mma(
        (tensor(41, 18, 140, 300), Read::Pool),
        Some((tensor(22, 9, 70, 301), Read::Direct)),
        43,
        true,
        70,
        9,
        302,
        Tile::mma(32).unwrap(),
    );
    // Upsampled and pool-upsampled sources, a linear conv with 8 outputs (one tile of 16,
    // mma64 shrinks to it), a level 14 x 6.
    check_conv_mma(
        (tensor(6, 3, 7, 303), Read::Upsample),
        Some((tensor(5, 6, 14, 304), Read::PoolUpsample)),
        8,
        false,
        14,
        6,
        305,
        Tile::mma(64).unwrap(),
    );
    // One source, 20 outputs in tiles of 16 (two groups), one row.
    check_conv_mma((tensor(33, 1, 65, 306), Read::Direct), None, 20, true, 65, 1, 307, Tile::mma(16).unwrap());
    // 48 outputs in one group of 3 tiles.
    check_conv_mma(
        (tensor(12, 5, 19, 308), Read::Direct),
        Some((tensor(12, 5, 19, 309), Read::Direct)),
        48,
        true,
        19,
        5,
        310,
        Tile::mma(48).unwrap(),
    );
    assert_eq!(Tile::mma(32).unwrap().to_string(), "mma32");
    assert_eq!(Tile::mma(24), None);
}

/// A split Mma conv ([`Tile::mma_split`]) against the CPU convolution in f32, at the direct
/// kernel's tolerance of the output's largest value, on inputs and a bias scaled by `scale`:
/// the f16-rounded operands of the plain tiles must fail the same bound, so the test tells the
/// two apart.
#[allow(clippy::too_many_arguments)]
fn check_conv_mma_split(
    a: (Chw, Read),
    b: Option<(Chw, Read)>,
    cout: usize,
    leaky: bool,
    w: usize,
    h: usize,
    seed: u64,
    tile: Tile,
    scale: f32,
) {
    let scaled = |t: Chw| Chw { data: t.data.iter().map(|v| v * scale).collect(), ..t };
    let (a, b) = ((scaled(a.0), a.1), b.map(|b| (scaled(b.0), b.1)));
    let cin = a.0.c + b.as_ref().map_or(0, |b| b.0.c);
    let rel = 1e-5 * ((9 * cin) as f32 / 100.0).sqrt().max(1.0);
    let weight: Vec<f32> = noise(cout * cin * 9, seed).iter().map(|v| v * 0.3).collect();
    let bias: Vec<f32> = noise(cout, seed + 1).iter().map(|v| v * scale).collect();
    let got = gpu_conv((&a.0, a.1), b.as_ref().map(|b| (&b.0, b.1)), &weight, &bias, leaky, w, h, tile, WeightMemory::Storage);
    let ra = cpu::read(&a.0, a.1, h, w);
    let x = match &b {
        Some((t, m)) => cpu::concat(&ra, &cpu::read(t, *m, h, w)),
        None => ra,
    };
    let want = cpu::conv3x3(&x, &weight, &bias, leaky.then_some(0.1));
    // Errors over the output's largest value (Tolerance is absolute below 1).
    let top = want.data.iter().fold(0.0f32, |m, v| m.max(v.abs()));
    let unit = |d: &[f32]| d.iter().map(|v| v / top).collect::<Vec<f32>>();
    let what = format!("split mma conv {:?}/{:?} {w}x{h} tile {tile} scale {scale}", a.1, b.as_ref().map(|b| b.1));
    crate::assert_close(Tolerance { rel }, &what, &unit(&got.data), &unit(&want.data));
    // The plain tiles' operands, f16-rounded, miss that bound.
    let f16 = |v: &f32| half::f16::from_f32(*v).to_f32();
    let x16 = Chw { data: x.data.iter().map(f16).collect(), ..x };
    let plain = cpu::conv3x3(&x16, &weight.iter().map(f16).collect::<Vec<f32>>(), &bias, leaky.then_some(0.1));
    assert!(Tolerance { rel }.worst(&unit(&plain.data), &unit(&want.data)).0 > 1.0, "{what}: f16 operands would pass too");
}

#[test]
fn conv_mma_split_tiles_match_cpu_in_f32() {
    // The split matrix-unit kernel (emulated here unless the device has cooperative matrices)
    // holds f32 convolutions to the direct kernel's tolerance: mma32x3 over a pooled and a
    // direct source (5 chunks, the last partial) with 43 outputs in groups of two tiles on a
    // level spanning partial workgroups; mma64x3 (four tiles a group, one group short of its
    // last two) on the same; mma16x3 on upsampled sources at a thousandth of the scale, where
    // an unscaled remainder would be an f16 subnormal.
    check_conv_mma_split(
        (tensor(41, 18, 140, 320), Read::Pool),
        Some((tensor(22, 9, 70, 321), Read::Direct)),
        43,
        true,
        70,
        9,
        322,
        Tile::mma_split(32).unwrap(),
        1.0,
    );
    check_conv_mma_split(
        (tensor(41, 18, 140, 326), Read::Pool),
        Some((tensor(22, 9, 70, 327), Read::Direct)),
        43,
        true,
        70,
        9,
        328,
        Tile::mma_split(64).unwrap(),
        1.0,
    );
    check_conv_mma_split(
        (tensor(6, 3, 7, 323), Read::Upsample),
        Some((tensor(5, 6, 14, 324), Read::PoolUpsample)),
        20,
        false,
        14,
        6,
        325,
        Tile::mma_split(16).unwrap(),
        1e-3,
    );
    assert_eq!(Tile::mma_split(32).unwrap().to_string(), "mma32x3");
    assert_eq!(Tile::mma_split(80), None, "at most four 16-channel tiles");
}

#[test]
fn mma_tiles_need_storage_weights() {
    let g = gpu();
    let mut kernels = Kernels::new(&g.device, kernels::Precision::F32, WeightMemory::Uniform);
    let (weight, bias) = (vec![0.0; 4 * 8 * 9], vec![0.0; 4]);
    let spec = one_source_spec("d1.l1.0", 8, 8, 8, &weight, &bias);
    let err = ConvPlan::new(&g.device, &g.queue, &mut kernels, &[spec], &[Tile::mma(16).unwrap()])
        .err()
        .expect("uniform weights are refused")
        .to_string();
    assert!(err.contains("mma16") && err.contains("storage"), "{err}");
}

#[test]
fn mma_weights_are_laid_out_as_the_kernel_reads_them() {
    // pack_mma: chunk c, tap t, tile, row k (input channel of block 4c + k / 4, lane k % 4),
    // column n; source a's 5 channels pad to 8 (2 blocks), b's 3 channels follow at block 2.
    let (cout, ca, cb) = (20, 5, 3);
    let weight: Vec<f32> = (0..cout * (ca + cb) * 9).map(|i| i as f32).collect();
    let bias: Vec<f32> = (0..cout).map(|i| 1.0 + i as f32 / 3.0).collect();
    let spec = ConvSpec { cb, read_b: Read::Direct, ..one_source_spec("test", 8, 8, ca, &weight, &bias) };
    let packed = kernels::pack_mma(&spec, 16, 2, false);
    assert_eq!(packed.len(), 9 * 2 * 256 + 64, "one chunk of 3 blocks, 9 taps, 2 tiles, the bias");
    let at = |t: usize, tile: usize, k: usize, n: usize| packed[(t * 2 + tile) * 256 + k * 16 + n].to_f32();
    let w = |o: usize, i: usize, t: usize| half::f16::from_f32(weight[(o * (ca + cb) + i) * 9 + t]).to_f32();
    // Output 16 + n (n < 4 exist), input channel 4 (block 1, lane 0) at k = 4; b's channel 0
    // (input channel 5) at block 2, k = 8.
    assert_eq!(at(7, 0, 4, 3), w(19, 4, 7));
    assert_eq!(at(2, 0, 8, 0), w(16, 5, 2));
    assert_eq!(at(2, 0, 5, 0), 0.0, "a's padding lane");
    assert_eq!(at(0, 0, 12, 0), 0.0, "the chunk's padding block");
    assert_eq!(at(0, 0, 0, 4), 0.0, "output 20 is past the conv");
    assert!((0..16 * 9 * 2).all(|i| at(i / 32, 1, (i / 16) % 16, i % 16) == 0.0), "the second tile is all padding");
    // The bias in two halves whose sum is the f32 bias to ~22 bits.
    let hi = &packed[9 * 2 * 256..][..32];
    let lo = &packed[9 * 2 * 256 + 32..];
    for n in 0..4 {
        let b = bias[16 + n];
        assert!((hi[n].to_f32() + lo[n].to_f32() - b).abs() <= b.abs() * 2e-6, "bias {n}");
    }
    assert!(hi[4..].iter().chain(&lo[4..]).all(|v| v.to_f32() == 0.0));
    // Split: the same tiles, then each weight's remainder scaled by 2^11, then the same bias;
    // hi + lo / 2^11 is the f32 weight to 22 bits.
    let weight: Vec<f32> = weight.iter().map(|v| (v + 0.1) / 7.0).collect();
    let spec = ConvSpec { weight: &weight, ..spec };
    let (plain, split) = (kernels::pack_mma(&spec, 16, 2, false), kernels::pack_mma(&spec, 16, 2, true));
    let tiles = 9 * 2 * 256;
    assert_eq!(split.len(), 2 * tiles + 64);
    assert_eq!(split[..tiles], plain[..tiles], "the hi tiles");
    assert_eq!(split[2 * tiles..], plain[tiles..], "the bias");
    for (t, k, n) in [(7, 4, 3), (2, 8, 0), (0, 1, 2)] {
        let i = (t * 2) * 256 + k * 16 + n;
        let joined = split[i].to_f32() + split[tiles + i].to_f32() / kernels::MMA_LO_SCALE;
        // Rows 0-4: a's channels 0-4; rows 8-10: b's, input channels 5-7.
        let input = if k < 5 { k } else { 5 + (k - 8) };
        let w = weight[((16 + n) * (ca + cb) + input) * 9 + t];
        assert!((joined - w).abs() <= w.abs() * 2.5e-7, "tap {t} row {k} column {n}: {joined} against {w}");
    }
}

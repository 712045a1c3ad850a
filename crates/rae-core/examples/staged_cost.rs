//! What storing the staged outputs in 64-bit words saves one conv
//! ([`kernels::wide_staged_stores`]): the same staged F(4x4) conv planned twice, storing 32-bit
//! and 64-bit words, timed in one process, alternating a submit of one and of the other, as
//! `pad_cost` does. Prints, per conv, each plan's median time per dispatch and the median of
//! the per-round ratios. The copies into the textures are not timed: they are the same bytes.
//!
//! cargo run --release -p rae-core --example staged_cost -- [ROUNDS] [TILE]
//!
//! TILE as compile_cost takes it, an F(4x4) one (wino4lanesRxB; default wino4lanes8x4, the
//! CPU drivers' tile on the largest levels).
//!
//! The convs are the default network's L0 ones at 256x256: 64 -> 32 channels from two
//! 32-channel sources, 32 -> 32 from one with its pooled output, and 8 -> 32 from one.

use rae_core::Gpu;
use rae_core::kernels;

mod common;

/// Dispatches per timed submit.
const REPEAT: usize = 3;

fn main() {
    // SAFETY: first thing in main, before any thread starts.
    unsafe { rae_core::gpu::prefer_wide_cpu_vectors() };
    let rounds: usize = std::env::args().nth(1).map_or(15, |a| a.parse().expect("ROUNDS"));
    let tile = common::parse_tile(&std::env::args().nth(2).unwrap_or_else(|| "wino4lanes8x4".into()));
    let g = Gpu::new().expect("a device");
    println!("{}; 64-bit staged stores: {}", g.describe(), kernels::wide_staged_stores(&g.device));
    if !kernels::wide_staged_stores(&g.device) {
        return;
    }
    println!("{:>16} {:>9} {:>12} {:>12} {:>10}", "tile", "conv", "32-bit ms", "64-bit ms", "ratio");
    let (w, h) = (256u32, 256u32);
    let view = |w, h, c| common::activation_view(&g.device, w, h, c);
    let (a, b, out, pooled) = (view(w, h, 32), view(w, h, 32), view(w, h, 32), view(w / 2, h / 2, 32));
    for (label, ca, cb, pool) in [("64->32", 32usize, 32usize, false), ("32->32+pool", 32, 0, true), ("8->32", 8, 0, false)] {
        let weight: Vec<f32> = (0..32 * (ca + cb) * 9).map(|i| (i % 101) as f32 * 1e-3 - 0.05).collect();
        let bias = vec![0.01f32; 32];
        let spec = common::probe_spec(w, h, ca, cb, &weight, &bias, pool);
        // The two plans, staged as the Denoiser stages them: 32-bit words, and 64-bit ones.
        let plans = common::plan_pair(&g, spec, tile, [&a, &b, &out], pool.then_some(&pooled), |i, k| {
            k.pad_from_bounds();
            k.stage_outputs();
            if i == 0 {
                k.stage_in_32_bit_words();
            }
        });
        assert!(plans.iter().all(|p| p.1.staged(0)), "staged convs");
        let (narrow, wide, ratio) = common::time_pair(&g, &plans, rounds, REPEAT);
        println!("{:>16} {label:>11} {:>12.3} {:>12.3} {:>10.3}", tile.to_string(), narrow, wide, ratio);
    }
}

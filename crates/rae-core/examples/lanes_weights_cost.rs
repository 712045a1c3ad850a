//! What reading the two-column lanes tiles' weights from the weight texture saves
//! ([`rae_core::kernels::TEXEL_WEIGHTS`]): the same conv planned twice, its weights in the
//! storage buffer ([`rae_core::kernels::Kernels::lanes_weights_in_buffers`]) and in the weight
//! texture, timed in one process, alternating a submit of one and of the other, as `pad_cost`
//! does. Prints, per conv, each plan's median time per dispatch and the median of the
//! per-round ratios (texture / buffer).
//!
//! cargo run --release -p rae-core --example lanes_weights_cost -- [ROUNDS] [TILE]
//!
//! TILE as compile_cost takes it, a two-column lanes one (lanesRxB; default lanes4x2, the CPU
//! drivers' tile on levels of 8 x 8 and less where subgroups have 16 lanes). The convs are the
//! default network's deepest ones: on its 8 x 8, 4 x 4 and 2 x 2 levels (the levels of a
//! 256x256 frame's bottleneck and of a 64x64 frame's three deepest), with the weights in
//! storage as [`rae_core::kernels::WeightMemory::for_conv`] puts them there.

use rae_core::Gpu;

mod common;

/// Dispatches per timed submit.
const REPEAT: usize = 5;

fn main() {
    // SAFETY: first thing in main, before any thread starts.
    unsafe { rae_core::gpu::prefer_wide_cpu_vectors() };
    let rounds: usize = std::env::args().nth(1).map_or(15, |a| a.parse().expect("ROUNDS"));
    let tile = common::parse_tile(&std::env::args().nth(2).unwrap_or_else(|| "lanes4x2".into()));
    let g = Gpu::new().expect("a device");
    println!("{}", g.describe());
    println!("{:>12} {:>6} {:>12} {:>12} {:>12} {:>10}", "tile", "level", "conv", "buffer ms", "texture ms", "ratio");
    for size in [8u32, 4, 2] {
        let view = |w, h, c| common::activation_view(&g.device, w, h, c);
        let (a, b) = (view(size, size, 101), view(size, size, 101));
        let out = view(size, size, 101);
        for (label, ca, cb, cout) in [("101->101", 101usize, 0usize, 101usize), ("202->101", 101, 101, 101), ("152->76", 76, 76, 76)] {
            let weight: Vec<f32> = (0..cout * (ca + cb) * 9).map(|i| (i % 101) as f32 * 1e-3 - 0.05).collect();
            let bias = vec![0.01f32; cout];
            let spec = common::probe_spec(size, size, ca, cb, &weight, &bias, false);
            let plans = common::plan_pair(&g, spec, tile, [&a, &b, &out], None, |i, k| {
                k.pad_from_bounds();
                if i == 0 {
                    k.lanes_weights_in_buffers();
                }
            });
            let (buffer, texture, ratio) = common::time_pair(&g, &plans, rounds, REPEAT);
            println!("{:>12} {:>6} {label:>12} {buffer:>12.3} {texture:>12.3} {ratio:>10.3}", tile.to_string(), format!("{size}x{size}"));
        }
    }
}

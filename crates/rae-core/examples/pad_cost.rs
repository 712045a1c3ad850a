//! What reading the zero padding from outside the textures saves one conv
//! ([`Kernels::pad_from_bounds`]): the same conv planned twice, testing each fetched pixel and
//! not, timed in one process, alternating a submit of one and of the other, so that the
//! machine's drift between runs (a fifth and more on a 2-vCPU VM) falls on both alike. Prints,
//! per conv, each plan's median time per dispatch and the median of the per-round ratios.
//!
//! cargo run --release -p rae-core --example pad_cost -- [ROUNDS] [TILE ...]
//!
//! TILE as compile_cost takes it (common::parse_tile: wino4lanesRxB, lanesRxB, ...); the
//! convs are the default network's L0 ones at 256x256: 64 -> 32 channels from two 32-channel
//! sources, and 8 -> 32 from one.

use rae_core::Gpu;
use rae_core::kernels;

mod common;

/// Dispatches per timed submit.
const REPEAT: usize = 3;

fn main() {
    // SAFETY: first thing in main, before any thread starts.
    unsafe { rae_core::gpu::prefer_wide_cpu_vectors() };
    let mut args = std::env::args().skip(1).peekable();
    let rounds: usize = args.next_if(|a| a.parse::<usize>().is_ok()).map_or(15, |a| a.parse().unwrap());
    let tiles: Vec<String> = args.collect();
    let tiles = if tiles.is_empty() { vec!["wino4lanes8x4".to_string()] } else { tiles };
    let g = Gpu::new().expect("a device");
    println!("{}; reads zero outside: {}", g.describe(), kernels::out_of_bounds_reads_zero(&g.device));
    println!("{:>16} {:>9} {:>12} {:>12} {:>10}", "tile", "conv", "tested ms", "bounds ms", "ratio");
    let (w, h) = (256u32, 256u32);
    let view = |c| common::activation_view(&g.device, w, h, c);
    let (a, b, out) = (view(32), view(32), view(32));
    for name in &tiles {
        let tile = common::parse_tile(name);
        for (label, ca, cb) in [("64->32", 32usize, 32usize), ("8->32", 8, 0)] {
            let weight = vec![0.01f32; 32 * (ca + cb) * 9];
            let bias = vec![0.0f32; 32];
            let spec = common::probe_spec(w, h, ca, cb, &weight, &bias, false);
            // The two plans: the fetch tests each pixel, and it reads outside instead.
            let plans = common::plan_pair(&g, spec, tile, [&a, &b, &out], None, |i, k| {
                if i == 1 {
                    k.pad_from_bounds();
                }
            });
            let (tested, bounds, ratio) = common::time_pair(&g, &plans, rounds, REPEAT);
            println!("{name:>16} {label:>9} {:>12.3} {:>12.3} {:>10.3}", tested, bounds, ratio);
        }
    }
}

//! What one conv pipeline costs the driver to build: a single conv (two 32-channel sources,
//! 32 outputs, 32x32) with one tile, its plan made and its first dispatch waited on, each
//! timed. On lavapipe the first dispatch is where LLVM compiles the pipeline, so this is the
//! build time a plan pays per pipeline into an empty shader cache (docs/PERF.md, session 27,
//! where the F(4x4) 8x4 tile took 15.8 s and 7.6 s after its body was split into blocks).
//!
//! MESA_SHADER_CACHE_DISABLE=true cargo run --release -p rae-core --example compile_cost -- [TILE ...]
//!
//! TILE is wino4lanesRxB, winolanesRxB, lanesRxB (two columns), winoRxB, directRxB, mmaC or
//! mmasC (C channels); wino4lanes8x4 when none is named. Without the variable Mesa's shader
//! cache answers a second run.

use std::time::Instant;

use rae_core::Gpu;
use rae_core::kernels::{self, ConvPlan, Kernels, WeightMemory};

mod common;

fn main() {
    let tiles: Vec<String> = std::env::args().skip(1).collect();
    let tiles = if tiles.is_empty() { vec!["wino4lanes8x4".to_string()] } else { tiles };
    let g = Gpu::new().expect("a device");
    eprintln!("{}", g.describe());
    let (w, h, c) = (32u32, 32u32, 32usize);
    let weight = vec![0.01f32; 2 * c * c * 9];
    let bias = vec![0.0f32; c];
    let view = |c| common::activation_view(&g.device, w, h, c);
    let (a, b, out) = (view(c), view(c), view(c));
    for name in tiles {
        let tile = common::parse_tile(&name);
        let mut k = Kernels::new(&g.device, kernels::Precision::F32, WeightMemory::Storage);
        // As a Denoiser's plan does (its sources are the level's size).
        k.pad_from_bounds();
        let spec = common::probe_spec(w, h, c, c, &weight, &bias, false);
        let t0 = Instant::now();
        let plan = ConvPlan::new(&g.device, &g.queue, &mut k, &[spec], &[tile]).expect("plan");
        let group = plan.bind_group(&g.device, &k, 0, &a, &b, &out, None);
        let made = t0.elapsed();
        let t1 = Instant::now();
        let mut enc = g.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            plan.record(&mut pass, 0, false, &group);
        }
        g.queue.submit(Some(enc.finish()));
        g.device.poll(wgpu::PollType::wait_indefinitely()).expect("poll");
        let first = t1.elapsed();
        println!("{name:>16}  plan {:8.2} s  first dispatch {:8.2} s", made.as_secs_f64(), first.as_secs_f64());
    }
}

//! What one conv pipeline costs the driver to build: a single conv (two 32-channel sources,
//! 32 outputs, 32x32) with one tile, its plan made and its first dispatch waited on, each
//! timed. On lavapipe the first dispatch is where LLVM compiles the pipeline, so this is the
//! build time a plan pays per pipeline into an empty shader cache, and most of the test
//! suite's time.
//!
//! MESA_SHADER_CACHE_DISABLE=true cargo run --release -p rae-core --example compile_cost -- [TILE ...]
//!
//! TILE is a tile as `rae-cli bench --tile` names it (`wino4lanes4x4`, `lanes8x2w2`, `16x2`,
//! `mma32x3`, ...); wino4lanes4x4 when none is named. Without the variable Mesa's shader cache
//! answers a second run.

use std::time::Instant;

use rae_core::Gpu;
use rae_core::graph::Read;
use rae_core::kernels::{self, Carve, ConvPlan, ConvSpec, Kernels, Tile, WeightMemory, blocks};

/// A `w` x `h` activation texture of `channels`, viewed as the array a conv binds.
fn activation_view(device: &wgpu::Device, w: u32, h: u32, channels: usize) -> wgpu::TextureView {
    let t = device.create_texture(&wgpu::TextureDescriptor {
        label: None,
        size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: blocks(channels) },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: kernels::ACTIVATION_FORMAT,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::STORAGE_BINDING,
        view_formats: &[],
    });
    t.create_view(&wgpu::TextureViewDescriptor { dimension: Some(wgpu::TextureViewDimension::D2Array), ..Default::default() })
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let names: Vec<String> = std::env::args().skip(1).collect();
    let names = if names.is_empty() { vec!["wino4lanes4x4".to_string()] } else { names };
    let g = Gpu::new()?;
    eprintln!("{}", g.describe());
    let (w, h, c) = (32u32, 32u32, 32usize);
    let weight = vec![0.01f32; 2 * c * c * 9];
    let bias = vec![0.0f32; c];
    let view = |c| activation_view(&g.device, w, h, c);
    let (a, b, out) = (view(c), view(c), view(c));
    for name in names {
        let tile: Tile = name.parse()?;
        let mut k = Kernels::new(&g.device, kernels::Precision::F32, WeightMemory::Storage);
        // As a Denoiser's plan does (its sources are the level's size).
        k.pad_from_bounds();
        let spec = ConvSpec {
            name: "probe",
            width: w,
            height: h,
            ca: c,
            cb: c,
            cout: c,
            weight: &weight,
            bias: &bias,
            read_a: Read::Direct,
            read_b: Read::Direct,
            leaky: true,
            slope: 0.1,
            b_is_hidden: false,
            pooled: false,
            carves: [Carve::NONE; 4],
        };
        let t0 = Instant::now();
        let plan = ConvPlan::new(&g.device, &g.queue, &mut k, &[spec], &[tile])?;
        let group = plan.bind_group(&g.device, &k, 0, &a, &b, &out, None);
        let made = t0.elapsed();
        let t1 = Instant::now();
        let mut enc = g.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            plan.record(&mut pass, 0, false, &group);
        }
        g.queue.submit(Some(enc.finish()));
        g.device.poll(wgpu::PollType::wait_indefinitely())?;
        let first = t1.elapsed();
        println!("{name:>16}  plan {:8.2} s  first dispatch {:8.2} s", made.as_secs_f64(), first.as_secs_f64());
    }
    Ok(())
}

//! Frames submitted back to back on GPU buffers, with a timestamp before and after each: each
//! frame's span and the time between one frame's closing timestamp and the next one's opening
//! timestamp. With `--no-spare` the opening timestamp is written alone, as before session 19;
//! on lavapipe that moves the frame's first dispatches (prep) out of its span and into the gap.
//!
//! cargo run --release -p rae-core --example frame_gaps -- [SIZE] [--no-spare]

use rae_core::denoiser::{GpuFrameIo, read_timestamps, write_opening_timestamp};
use rae_core::{Denoiser, Gpu, Weights};
use wgpu::util::DeviceExt;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // SAFETY: first thing in main, before any thread starts.
    unsafe { rae_core::gpu::prefer_wide_cpu_vectors() };
    let args: Vec<String> = std::env::args().skip(1).collect();
    let spare = !args.iter().any(|a| a == "--no-spare");
    let size: u32 = args.iter().find(|a| !a.starts_with("--")).map_or(Ok(256), |s| s.parse())?;
    let weights = Weights::load(concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/rae-default.safetensors"))?;
    let gpu = Gpu::new()?;
    let dev = &gpu.device;
    let n = (size * size) as usize;
    // The bench's input pattern: a smooth wave in every channel.
    let wave: Vec<f32> = (0..3 * n).map(|i| 0.5 + 0.5 * ((i as f32) * 0.37).sin()).collect();
    let storage = |data: &[f32]| {
        dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: None,
            contents: bytemuck::cast_slice(data),
            usage: wgpu::BufferUsages::STORAGE,
        })
    };
    let (color, one) = (storage(&wave), storage(&wave[..n]));
    let output = dev.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: (3 * n * 4) as u64,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    let mut d = Denoiser::new(dev, &gpu.queue, &weights, size, size)?;
    let io = d.bind_io(&GpuFrameIo {
        color: &color,
        albedo: Some(&color),
        normal: Some(&color),
        depth: Some(&one),
        roughness: Some(&one),
        output: &output,
    })?;
    // Per frame: opening timestamp, its spare, closing timestamp; 2 warm-up frames first.
    let frames = 12u32;
    let queries = dev.create_query_set(&wgpu::QuerySetDescriptor { label: None, ty: wgpu::QueryType::Timestamp, count: 3 * frames });
    for i in 0..frames {
        let mut enc = dev.create_command_encoder(&Default::default());
        if spare {
            write_opening_timestamp(&mut enc, &queries, 3 * i, 3 * i + 1);
        } else {
            enc.write_timestamp(&queries, 3 * i);
        }
        d.record(&mut enc, &io)?;
        enc.write_timestamp(&queries, 3 * i + 2);
        gpu.queue.submit(Some(enc.finish()));
    }
    let ticks = read_timestamps(dev, &gpu.queue, &queries, 3 * frames)?;
    let ms = |a: u64, b: u64| b.saturating_sub(a) as f64 * gpu.queue.get_timestamp_period() as f64 * 1e-6;
    println!("{} at {size}x{size}, opening timestamps {}", gpu.describe(), if spare { "with a spare" } else { "alone" });
    let (mut spans, mut gaps) = (vec![], vec![]);
    for i in 3..frames as usize {
        let (span, gap) = (ms(ticks[3 * i], ticks[3 * i + 2]), ms(ticks[3 * i - 1], ticks[3 * i]));
        println!("frame {i:2}: span {span:8.2} ms, gap before {gap:6.2} ms");
        spans.push(span);
        gaps.push(gap);
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    println!("median span {:.2} ms, median gap {:.2} ms", median(&mut spans), median(&mut gaps));
    Ok(())
}

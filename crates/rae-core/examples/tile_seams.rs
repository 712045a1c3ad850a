//! How far a tiled run is from the whole-frame run, by overlap: a sequence denoised whole and
//! in tiles of one interior size with each overlap, frame after frame (hidden state carried),
//! and per overlap the largest and mean absolute difference (relative to the whole run's mean
//! value) and the largest near a seam. The table chooses `TILE_OVERLAP`.
//!
//! cargo run --release -p rae-core --example tile_seams -- SEQUENCE MODEL TILE OVERLAP...

use std::path::PathBuf;

use rae_core::denoiser::FrameTiles;
use rae_core::io::Sequence;
use rae_core::{Denoiser, Gpu, Options, Weights};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 4 {
        return Err("usage: tile_seams SEQUENCE MODEL TILE OVERLAP...".into());
    }
    let seq = Sequence::scan(&PathBuf::from(&args[0]))?;
    let weights = Weights::load(&args[1])?;
    let tile: u32 = args[2].parse()?;
    let overlaps: Vec<u32> = args[3..].iter().map(|s| s.parse()).collect::<Result<_, _>>()?;
    let g = Gpu::new()?;
    eprintln!("{}", g.describe());
    let (w, h) = (seq.width, seq.height);
    let frames: Vec<_> = (0..seq.numbers.len()).map(|i| seq.load(i)).collect::<Result<_, _>>()?;
    let run = |options: Options| -> Result<Vec<Vec<f32>>, Box<dyn std::error::Error>> {
        let mut d = Denoiser::with_options(&g.device, &g.queue, &weights, w, h, options)?;
        if let Some(p) = d.tile_plan() {
            eprintln!("{} tiles of {}x{}", p.count(), p.extent.0, p.extent.1);
        }
        // Without motion: tiled frames are not reprojected.
        Ok(frames.iter().map(|f| d.denoise(&rae_core::FrameInputs { motion: None, ..f.inputs() })).collect::<Result<_, _>>()?)
    };
    let whole = run(Options::default())?;
    println!("| overlap | frame | max abs diff / mean | mean abs diff / mean |");
    println!("|---|---|---|---|");
    for &overlap in &overlaps {
        let tiled = run(Options { frame_tiles: Some(FrameTiles { tile, overlap, host_state: false }), ..Default::default() })?;
        for (i, (a, b)) in whole.iter().zip(&tiled).enumerate() {
            let mean = a.iter().map(|v| v.abs() as f64).sum::<f64>() / a.len() as f64;
            let max = a.iter().zip(b).map(|(x, y)| (x - y).abs() as f64).fold(0.0, f64::max);
            let avg = a.iter().zip(b).map(|(x, y)| (x - y).abs() as f64).sum::<f64>() / a.len() as f64;
            println!("| {overlap} | {i} | {:.2e} | {:.2e} |", max / mean, avg / mean);
        }
    }
    Ok(())
}

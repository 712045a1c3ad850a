//! rae-cli: the command-line face of rae-core.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand};
use rae_core::golden::{Golden, Tolerance};
use rae_core::graph::Graph;
use rae_core::{Denoiser, Gpu, Weights};

#[derive(Parser)]
#[command(name = "rae-cli", version, about = "Recurrent denoising autoencoder for path-traced sequences, on wgpu")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Print a weights file's architecture, inputs, parameter count and cost per pixel.
    Info {
        /// A .safetensors weights file written by weights-tool.
        file: PathBuf,
    },
    /// List the adapters wgpu sees (WGPU_BACKEND filters; WGPU_ADAPTER_NAME picks one).
    Devices,
    /// Run golden sequences (written by weights-tool) on the GPU and report the error against
    /// PyTorch and the time per frame; fails if any value is outside 1e-4 * max(1, |torch|).
    Verify {
        /// Golden .safetensors files; their weights file is looked up beside them.
        #[arg(required = true)]
        golden: Vec<PathBuf>,
    },
}

fn info(path: &Path) -> Result<()> {
    let w = Weights::load(path)?;
    let a = &w.arch;
    let macs = Graph::new(a).macs_per_pixel();
    let names = |v: &[rae_core::InputBuffer]| v.iter().map(|b| b.name()).collect::<Vec<_>>().join(", ");
    println!("file:            {}", path.display());
    println!("network inputs:  {} ({} channels)", names(&a.inputs), a.in_channels());
    println!("buffers needed:  {}", names(&a.required_buffers()));
    println!("demodulate:      {} (albedo eps {})", a.demodulate, a.albedo_eps);
    println!("transfer:        {:?}", a.transfer);
    println!("encoder widths:  {:?}, bottleneck {}", a.encoder, a.bottleneck);
    println!("skip variant:    {:?}", a.skip);
    println!("output:          {:?}", a.output_activation);
    println!("frame multiple:  {} (frames are padded to it)", 1 << a.levels());
    println!("parameters:      {}", a.parameter_count());
    println!("cost per pixel:  {:.0} multiply-adds, {:.1} kFLOP", macs, 2.0 * macs / 1e3);
    Ok(())
}

fn devices() -> Result<()> {
    let adapters = rae_core::gpu::adapters();
    if adapters.is_empty() {
        bail!("wgpu sees no adapter; for a CPU Vulkan driver install lavapipe (apt-get install mesa-vulkan-drivers)");
    }
    for a in adapters {
        let i = a.get_info();
        let f16 = a.features().contains(wgpu::Features::SHADER_F16);
        let ts = a.features().contains(wgpu::Features::TIMESTAMP_QUERY);
        println!("{} | {:?} | {:?} | driver {} {} | f16 {f16} | timestamps {ts}", i.name, i.backend, i.device_type, i.driver, i.driver_info);
    }
    Ok(())
}

fn verify(files: &[PathBuf]) -> Result<()> {
    let gpu = Gpu::new()?;
    println!("adapter: {}", gpu.describe());
    println!("{:<40} {:>5} {:>9} {:>12} {:>10} {:>10}", "sequence", "frame", "size", "max |err|", "of tol", "ms");
    let mut failed = 0;
    for path in files {
        let golden = Golden::load(path)?;
        let wpath = path.with_file_name(&golden.weights);
        let weights = Weights::load(&wpath).with_context(|| format!("weights of {}", path.display()))?;
        let mut d = Denoiser::new(&gpu.device, &gpu.queue, &weights, golden.width, golden.height)?;
        let name = path.file_name().unwrap_or_default().to_string_lossy();
        for i in 0..golden.frames.len() {
            let t = Instant::now();
            let out = d.denoise(&golden.inputs(i)).with_context(|| format!("{name} frame {i}"))?;
            let ms = t.elapsed().as_secs_f64() * 1e3;
            let (ratio, _, max_abs) = Tolerance::GOLDEN.worst(&out, golden.expected(i));
            failed += (ratio > 1.0) as usize;
            let size = format!("{}x{}", golden.width, golden.height);
            println!("{name:<40} {i:>5} {size:>9} {max_abs:>12.3e} {ratio:>10.4} {ms:>10.1}");
        }
    }
    println!("(frame 0 includes shader compilation; \"of tol\" is the worst error over 1e-4 * max(1, |torch|))");
    if failed > 0 {
        bail!("{failed} frame(s) outside the tolerance");
    }
    Ok(())
}

fn main() -> Result<()> {
    match Cli::parse().command {
        Command::Info { file } => info(&file),
        Command::Devices => devices(),
        Command::Verify { golden } => verify(&golden),
    }
}

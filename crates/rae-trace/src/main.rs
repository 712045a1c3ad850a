//! rae-trace: render sequences for rae, or trace and denoise live with rae-core embedded.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::{Args, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use rae_core::frame::parse_size;
use rae_trace::{Aux, Scene, Settings, output, render_frame, scenes};

#[derive(Parser)]
#[command(name = "rae-trace", version, about = "Path tracer that renders training and test sequences for rae")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Args)]
struct SceneChoice {
    /// A fixed scene: cornell, glossy, firefly, cornell-moving or glossy-moving.
    #[arg(long, conflicts_with_all = ["random", "varied"])]
    scene: Option<String>,
    /// A procedural scene from this seed.
    #[arg(long, conflicts_with = "varied")]
    random: Option<u64>,
    /// A procedural scene from this seed, from the wider generator the training set at scale
    /// uses (moving objects, thin geometry, rooms, many lights, still to fast cameras).
    #[arg(long)]
    varied: Option<u64>,
}

impl SceneChoice {
    fn build(&self) -> Result<(Scene, String)> {
        match (&self.scene, self.random, self.varied) {
            (Some(name), _, _) => {
                let scene =
                    scenes::by_name(name).with_context(|| format!("unknown scene `{name}` (known: {})", scenes::NAMES.join(", ")))?;
                Ok((scene, name.clone()))
            }
            (None, Some(seed), _) => Ok((scenes::random(seed), format!("random {seed}"))),
            (None, None, Some(seed)) => Ok((scenes::varied(seed), format!("varied {seed}"))),
            (None, None, None) => bail!("choose --scene NAME, --random SEED or --varied SEED"),
        }
    }
}

#[derive(Subcommand)]
enum Command {
    /// Render a sequence: noisy color at --spp, albedo, normal, depth, roughness, motion and a
    /// reference at --ref-spp, one EXR per buffer per frame (color_0000.exr, ...).
    Render {
        #[command(flatten)]
        scene: SceneChoice,
        /// Frames in the sequence.
        #[arg(long, default_value_t = 8)]
        frames: u32,
        /// Samples per pixel of the noisy color.
        #[arg(long, default_value_t = 1)]
        spp: u32,
        /// Samples per pixel of the reference (0: none).
        #[arg(long, default_value_t = 1024)]
        ref_spp: u32,
        /// Image size, WxH.
        #[arg(long, default_value = "256x256", value_parser = parse_size)]
        size: (u32, u32),
        /// Seed of the noise (the scene's own seed is --random).
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Longest path in bounces.
        #[arg(long, default_value_t = 8)]
        max_depth: u32,
        /// Write half-float EXR (smaller) instead of float.
        #[arg(long)]
        half: bool,
        /// Auxiliary buffers from the pixel centre's ray (`centre`: noise-free, as a
        /// rasteriser's G-buffer) or averaged over the color's samples through mirrors and glass
        /// (`samples`: as Cycles and other offline renderers write them).
        #[arg(long, default_value = "centre", value_parser = parse_aux)]
        aux: Aux,
        /// Output folder (created).
        out: PathBuf,
    },
    /// Render a training set: --count sequences of `--varied` scenes (seeds from --first-seed),
    /// their sample counts cycling through 1, 2, 4 and 8 spp, references at --ref-spp, each in
    /// OUT/vSEED-Nspp (OUT/vSEED-Nspp-aux-samples where the auxiliary buffers are the samples').
    /// Sequences already there are kept, so an interrupted run continues.
    Dataset {
        /// Sequences to render.
        #[arg(long, default_value_t = 300)]
        count: u64,
        /// Seed of the first scene.
        #[arg(long, default_value_t = 1)]
        first_seed: u64,
        /// Frames per sequence.
        #[arg(long, default_value_t = 8)]
        frames: u32,
        /// Samples per pixel of the references.
        #[arg(long, default_value_t = 256)]
        ref_spp: u32,
        /// Image size, WxH.
        #[arg(long, default_value = "128x128", value_parser = parse_size)]
        size: (u32, u32),
        /// Auxiliary buffers: `mixed` alternates `centre` and `samples` (see `render --aux`)
        /// every four seeds, so each sample count has both.
        #[arg(long, default_value = "mixed", value_parser = parse_dataset_aux)]
        aux: DatasetAux,
        /// Output folder (created).
        out: PathBuf,
    },
    /// Trace 1 spp per frame and denoise each with rae-core, hidden state carried: prints trace
    /// and denoise times per frame and writes color and denoised EXRs. The code to copy.
    Live {
        #[command(flatten)]
        scene: SceneChoice,
        /// rae weights file (.safetensors).
        #[arg(long)]
        weights: PathBuf,
        /// Frames.
        #[arg(long, default_value_t = 8)]
        frames: u32,
        /// Image size, WxH.
        #[arg(long, default_value = "256x256", value_parser = parse_size)]
        size: (u32, u32),
        /// Do not pass the tracer's motion to the denoiser (its hidden state is then not
        /// reprojected).
        #[arg(long)]
        no_motion: bool,
        /// Output folder (created).
        out: PathBuf,
    },
}

fn progress(frames: u64) -> ProgressBar {
    let bar = ProgressBar::new(frames);
    bar.set_style(ProgressStyle::with_template("{bar:40} {pos}/{len} frames  {per_sec}  ETA {eta}  {msg}").expect("valid template"));
    bar
}

/// Renders every frame of `scene` into `out`, a step of `bar` per frame.
fn render_frames(
    scene: &Scene,
    frames: u32,
    settings: &Settings,
    precision: output::Precision,
    out: &Path,
    bar: &ProgressBar,
) -> Result<()> {
    create_dir(out)?;
    for f in 0..frames {
        let fb = render_frame(scene, f, frames, settings);
        output::write_frame(out, f, settings.width as usize, settings.height as usize, &fb, precision)?;
        bar.inc(1);
    }
    Ok(())
}

/// Sample counts a training set cycles through, so one model serves them all.
const DATASET_SPP: [u32; 4] = [1, 2, 4, 8];

fn parse_aux(s: &str) -> Result<Aux, String> {
    match s {
        "centre" => Ok(Aux::Centre),
        "samples" => Ok(Aux::Samples),
        _ => Err(format!("`{s}`: expected centre or samples")),
    }
}

/// `dataset --aux`: both conventions, alternating by seed, or one.
#[derive(Clone, Copy)]
enum DatasetAux {
    Mixed,
    Only(Aux),
}

fn parse_dataset_aux(s: &str) -> Result<DatasetAux, String> {
    if s == "mixed" { Ok(DatasetAux::Mixed) } else { parse_aux(s).map(DatasetAux::Only).map_err(|e| format!("{e} or mixed")) }
}

fn dataset(count: u64, first_seed: u64, frames: u32, ref_spp: u32, (width, height): (u32, u32), aux: DatasetAux, out: &Path) -> Result<()> {
    create_dir(out)?;
    let bar = progress(count * frames as u64);
    let start = Instant::now();
    let mut rendered = 0;
    for seed in first_seed..first_seed + count {
        let spp = DATASET_SPP[(seed % DATASET_SPP.len() as u64) as usize];
        let aux = match aux {
            DatasetAux::Only(aux) => aux,
            DatasetAux::Mixed if (seed / DATASET_SPP.len() as u64) % 2 == 1 => Aux::Samples,
            DatasetAux::Mixed => Aux::Centre,
        };
        let name = format!("v{seed:05}-{spp}spp{}", if aux == Aux::Samples { "-aux-samples" } else { "" });
        let dir = out.join(&name);
        if dir.is_dir() {
            bar.inc(frames as u64);
            continue;
        }
        bar.set_message(name.clone());
        // Written under a hidden name, then renamed: readers never see half a sequence.
        let partial = out.join(format!(".{name}.partial"));
        if partial.exists() {
            std::fs::remove_dir_all(&partial).with_context(|| format!("removing {}", partial.display()))?;
        }
        let settings = Settings { width, height, spp, ref_spp, seed, max_depth: 8, aux };
        render_frames(&scenes::varied(seed), frames, &settings, output::Precision::F32, &partial, &bar)?;
        std::fs::rename(&partial, &dir).with_context(|| format!("renaming {} to {}", partial.display(), dir.display()))?;
        rendered += 1;
    }
    bar.finish_and_clear();
    println!(
        "{count} sequences in {} ({rendered} rendered now, {} already there) in {:.1} s",
        out.display(),
        count - rendered,
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

fn create_dir(out: &Path) -> Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("creating output folder {}", out.display()))
}

fn render(choice: &SceneChoice, frames: u32, settings: Settings, precision: output::Precision, out: &Path) -> Result<()> {
    let (scene, name) = choice.build()?;
    let bar = progress(frames as u64);
    let start = Instant::now();
    render_frames(&scene, frames, &settings, precision, out, &bar)?;
    bar.finish_and_clear();
    let secs = start.elapsed().as_secs_f64();
    let paths = frames as f64 * (settings.width * settings.height) as f64 * (settings.spp + settings.ref_spp) as f64;
    println!(
        "{name}: {frames} frames of {}x{} at {} spp (reference {} spp) into {} in {secs:.1} s: {:.2} M paths/s on {} threads",
        settings.width,
        settings.height,
        settings.spp,
        settings.ref_spp,
        out.display(),
        paths / secs / 1e6,
        rayon::current_num_threads()
    );
    Ok(())
}

fn live(choice: &SceneChoice, weights: &Path, frames: u32, size: (u32, u32), motion: bool, out: &Path) -> Result<()> {
    let (scene, name) = choice.build()?;
    create_dir(out)?;
    // Embedding rae-core: load the weights, open a GPU, build one Denoiser for the frame size.
    let weights = rae_core::Weights::load(weights)?;
    let gpu = rae_core::Gpu::new()?;
    let (w, h) = size;
    // With motion, the denoiser reprojects its hidden state with the tracer's motion vectors and
    // accumulates its output along them.
    let options = rae_core::Options { motion, accumulate: motion, ..Default::default() };
    let mut denoiser = rae_core::Denoiser::with_options(&gpu.device, &gpu.queue, &weights, w, h, options)?;
    println!("{name} at {w}x{h}, denoising on {}", gpu.describe());
    println!("{:>5} {:>10} {:>12}", "frame", "trace ms", "denoise ms");
    let settings = Settings { width: w, height: h, spp: 1, ref_spp: 0, seed: 0, max_depth: 8, aux: Aux::Centre };
    let mut helper = None;
    for f in 0..frames {
        let t0 = Instant::now();
        let fb = render_frame(&scene, f, frames, &settings);
        let t1 = Instant::now();
        // The tracer's buffers are already in the layout rae-core reads; the hidden state
        // carries from frame to frame inside the Denoiser (call reset() on a scene cut).
        let frame = rae_core::FrameInputs {
            color: &fb.color,
            albedo: Some(&fb.albedo),
            normal: Some(&fb.normal),
            depth: Some(&fb.depth),
            roughness: Some(&fb.roughness),
            motion: motion.then_some(fb.motion.as_slice()),
        };
        // On a CPU driver a first frame into an empty shader cache compiles on one core; a
        // second device compiles from the other end if it is slow to come.
        if f == 0 {
            let note = || {
                eprintln!(
                    "the first frame is slow to come: compiling kernels on a second device too (lavapipe compiles at first use, into Mesa's shader cache)"
                )
            };
            helper = rae_core::gpu::CompileHelper::start(&gpu, &weights, w, h, options, note);
        }
        let denoised = denoiser.denoise(&frame)?;
        if let Some(h) = &mut helper {
            h.first_frame_done();
        }
        let t2 = Instant::now();
        println!("{f:>5} {:>10.1} {:>12.1}", (t1 - t0).as_secs_f64() * 1e3, (t2 - t1).as_secs_f64() * 1e3);
        rae_core::io::write_exr(&output::frame_path(out, "color", f), w, h, &fb.color, false)?;
        rae_core::io::write_exr(&output::frame_path(out, "denoised", f), w, h, &denoised, false)?;
    }
    if let Some(h) = helper {
        h.finish();
    }
    Ok(())
}

fn main() -> Result<()> {
    // SAFETY: first thing in main, before any thread (the renderer's, wgpu's) exists.
    unsafe { rae_core::gpu::prefer_wide_cpu_vectors() };
    match Cli::parse().command {
        Command::Render { scene, frames, spp, ref_spp, size, seed, max_depth, half, aux, out } => {
            let (width, height) = size;
            let precision = if half { output::Precision::F16 } else { output::Precision::F32 };
            render(&scene, frames, Settings { width, height, spp, ref_spp, seed, max_depth, aux }, precision, &out)
        }
        Command::Dataset { count, first_seed, frames, ref_spp, size, aux, out } => {
            dataset(count, first_seed, frames, ref_spp, size, aux, &out)
        }
        Command::Live { scene, weights, frames, size, no_motion, out } => live(&scene, &weights, frames, size, !no_motion, &out),
    }
}

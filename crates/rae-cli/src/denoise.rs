//! `rae-cli denoise SEQ/`: a folder of frames in, denoised frames out, error against run time.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use rae_core::denoiser::MemoryPlan;
use rae_core::gpu::CompileHelper;
use rae_core::io::{self, Sequence, Slot};
use rae_core::metrics::median;
use rae_core::{Denoiser, Gpu, InputBuffer, Precision, TileChoice, Weights, metrics};

/// What `denoise` was asked to do.
pub struct Options {
    /// The sequence folder.
    pub input: PathBuf,
    /// Output folder (None: a new folder beside the input).
    pub output: Option<PathBuf>,
    /// Weights file (None: the best shipped model for the buffers present).
    pub weights: Option<PathBuf>,
    /// Folder of shipped models (`None`: [`models_dir`] finds it).
    pub models: Option<PathBuf>,
    /// Frame numbers to denoise, inclusive.
    pub frames: Option<(Option<u32>, Option<u32>)>,
    /// Frame numbers before which the hidden state is reset (scene cuts).
    pub reset_at: Vec<u32>,
    /// Also write tonemapped sRGB PNG previews.
    pub png: bool,
    /// Write half-float EXR.
    pub half: bool,
    /// Sanitize NaN/Inf input values instead of refusing the frame.
    pub allow_nonfinite: bool,
    /// Storage precision of activations on the GPU (`None`: f32, or f16 where `max_memory` is
    /// too small for f32).
    pub precision: Option<Precision>,
    /// Cap in bytes on the denoiser's GPU memory ([`rae_core::Options::max_memory`]).
    pub max_memory: Option<u64>,
    /// Write per-frame times (and errors, where a reference exists) as CSV to this file.
    pub csv: Option<PathBuf>,
    /// The conv tile (`--tile`).
    pub tiles: TileChoice,
    /// No second device compiling kernels for a slow first frame ([`CompileHelper`]).
    pub no_helper: bool,
    /// Reproject the hidden state with the sequence's motion, read in this convention (`None`:
    /// `--no-motion`).
    pub motion: Option<MotionConvention>,
    /// Blend each output with the previous one along the motion where the hidden state is
    /// reprojected ([`rae_core::Options::accumulate`]; `--no-accumulate` turns it off).
    pub accumulate: bool,
}

/// What a sequence's motion files mean.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum MotionConvention {
    /// rae's: previous position minus current, in pixels, x right, y down.
    Rae,
    /// OptiX's flow: current minus previous (the negative of rae's).
    Optix,
}

/// Parse `A..B`, `A..`, `..B` or `A` (inclusive frame numbers).
pub fn parse_range(s: &str) -> Result<(Option<u32>, Option<u32>)> {
    let num = |t: &str| -> Result<Option<u32>> {
        if t.is_empty() { Ok(None) } else { Ok(Some(t.parse().with_context(|| format!("`{t}` in --frames {s} is not a frame number"))?)) }
    };
    match s.split_once("..") {
        Some((a, b)) => Ok((num(a)?, num(b)?)),
        None => {
            let n = num(s)?;
            Ok((n, n))
        }
    }
}

/// The folder of shipped models: `explicit` (`--models`), else `$RAE_MODELS`, else the first
/// of `models/` beside the executable, `../share/rae/models/` from it (an installed tree) and
/// the source tree's `models/` that holds a `.safetensors` file.
pub fn models_dir(explicit: Option<&Path>) -> Result<PathBuf> {
    if let Some(dir) = explicit {
        return Ok(dir.to_path_buf());
    }
    if let Some(dir) = std::env::var_os("RAE_MODELS") {
        return Ok(PathBuf::from(dir));
    }
    let exe_dir = std::env::current_exe().ok().and_then(|e| e.parent().map(Path::to_path_buf));
    let mut places: Vec<PathBuf> = exe_dir.iter().flat_map(|d| [d.join("models"), d.join("../share/rae/models")]).collect();
    places.push(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models"));
    let has_models = |d: &Path| {
        std::fs::read_dir(d).is_ok_and(|mut it| it.any(|e| e.is_ok_and(|e| e.path().extension().is_some_and(|x| x == "safetensors"))))
    };
    places.iter().find(|d| has_models(d)).cloned().with_context(|| {
        let looked: Vec<String> = places.iter().map(|p| p.display().to_string()).collect();
        format!("no shipped models found (looked in {}); set RAE_MODELS=DIR, pass --models DIR or --weights FILE", looked.join(", "))
    })
}

/// The shipped model with the most inputs among those whose buffers the sequence has.
fn pick_model(models: &Path, present: &BTreeSet<InputBuffer>) -> Result<PathBuf> {
    let mut candidates = Vec::new();
    let entries = std::fs::read_dir(models)
        .with_context(|| format!("reading the shipped models in {} (or pass --weights FILE)", models.display()))?;
    for e in entries {
        let p = e?.path();
        if p.extension().is_some_and(|x| x == "safetensors") {
            let w = Weights::load(&p)?;
            let need = w.arch.required_buffers();
            if need.iter().all(|b| present.contains(b)) {
                candidates.push((need.len(), p));
            }
        }
    }
    candidates.sort();
    candidates.pop().map(|(_, p)| p).with_context(|| {
        format!(
            "no shipped model in {} fits the buffers present {:?}; pass --weights FILE",
            models.display(),
            present.iter().map(|b| b.name()).collect::<Vec<_>>()
        )
    })
}

/// A new folder beside `input`: `NAME-denoised`, or `-denoised-2`, ... if taken.
fn default_output(input: &Path) -> PathBuf {
    let name = input.file_name().map(|n| n.to_string_lossy().to_string()).unwrap_or_else(|| "sequence".into());
    let parent = input.parent().unwrap_or(Path::new("."));
    (1..)
        .map(|k| parent.join(if k == 1 { format!("{name}-denoised") } else { format!("{name}-denoised-{k}") }))
        .find(|p| !p.exists())
        .expect("some name is free")
}

fn prepare_output(input: &Path, out: &Path) -> Result<()> {
    if out.exists() && std::fs::canonicalize(out)? == std::fs::canonicalize(input)? {
        bail!("{}: the output folder is the input folder; choose another with -o (inputs are never overwritten)", out.display());
    }
    std::fs::create_dir_all(out).with_context(|| format!("{}: cannot create the output folder", out.display()))?;
    let probe = out.join(".rae-write-test");
    std::fs::write(&probe, b"").with_context(|| format!("{}: the output folder is not writable", out.display()))?;
    std::fs::remove_file(&probe).ok();
    Ok(())
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

struct FrameReport {
    number: u32,
    ms: f64,
    times: [f64; 3],
    noisy: Option<(f64, f64, f64)>,
    rae: Option<(f64, f64, f64)>,
}

/// The per-frame CSV of `--csv`: frame, upload/GPU/download ms, then relMSE, PSNR and SSIM of the
/// input and of the result (empty where the sequence has no reference).
fn csv_text(reports: &[FrameReport]) -> String {
    let mut s = String::from("frame,upload_ms,gpu_ms,download_ms,relmse_input,relmse_rae,psnr_input,psnr_rae,ssim_input,ssim_rae\n");
    for r in reports {
        let m = |x: Option<(f64, f64, f64)>, k: usize| x.map_or(String::new(), |v| format!("{}", [v.0, v.1, v.2][k]));
        let [u, g, d] = r.times;
        s += &format!("{},{u:.4},{g:.4},{d:.4}", r.number);
        for k in 0..3 {
            s += &format!(",{},{}", m(r.noisy, k), m(r.rae, k));
        }
        s.push('\n');
    }
    s
}

/// The storage precision and the memory plan: the one asked for, else f32, or f16 where the
/// cap is too small for f32 tiles with the frame's state on the GPU (and large enough for f16
/// ones); f32 with the state in host memory only where neither fits.
fn memory_plan(o: &Options, weights: &Weights, seq: &Sequence, gpu: &Gpu, motion: bool) -> Result<(Precision, MemoryPlan)> {
    let limits = gpu.device.limits();
    let plan = |p: Precision| MemoryPlan::new(&weights.arch, seq.width, seq.height, p, o.max_memory, None, motion, &limits);
    if let Some(p) = o.precision {
        let hint = if p == Precision::F32 && plan(Precision::F16).is_ok() { " (f16 activations fit: --precision f16)" } else { "" };
        return Ok((p, plan(p).with_context(|| format!("--max-memory{hint}"))?));
    }
    let (f32, f16) = (plan(Precision::F32), plan(Precision::F16));
    Ok(match (f32, f16) {
        (Ok(p), _) if p.host_state == 0 => (Precision::F32, p),
        (_, Ok(p)) if p.host_state == 0 => (Precision::F16, p),
        (Ok(p), _) => (Precision::F32, p),
        (Err(_), f16) => (Precision::F16, f16.context("--max-memory: too small for f32 or f16 activations")?),
    })
}

/// Run `denoise`.
pub fn run(o: &Options) -> Result<()> {
    let seq = Sequence::scan(&o.input)?;
    let present: BTreeSet<InputBuffer> = seq.inputs().into_iter().collect();
    let weights_path = match &o.weights {
        Some(p) => p.clone(),
        None => pick_model(&models_dir(o.models.as_deref())?, &present)?,
    };
    let weights = Weights::load(&weights_path)?;
    for b in weights.arch.required_buffers() {
        if !present.contains(&b) {
            bail!(
                "{}: the model {} needs the `{}` buffer, which the sequence lacks ({}_{:04}.exr or a `{}` layer); it has {:?}",
                o.input.display(),
                weights_path.display(),
                b.name(),
                b.name(),
                seq.numbers[0],
                b.name(),
                present.iter().map(|b| b.name()).collect::<Vec<_>>()
            );
        }
    }
    let indices: Vec<usize> = (0..seq.numbers.len())
        .filter(|&i| {
            let n = seq.numbers[i];
            o.frames.is_none_or(|(a, b)| a.is_none_or(|a| n >= a) && b.is_none_or(|b| n <= b))
        })
        .collect();
    if indices.is_empty() {
        bail!("{}: --frames selects none of frames {}..{}", o.input.display(), seq.numbers[0], seq.numbers[seq.numbers.len() - 1]);
    }
    let out_dir = o.output.clone().unwrap_or_else(|| default_output(&o.input));
    prepare_output(&o.input, &out_dir)?;

    let gpu = Gpu::new()?;
    let motion_source = seq.motion_source();
    let (precision, plan) = memory_plan(o, &weights, &seq, &gpu, motion_source.is_some() && o.motion.is_some())?;
    // Frames in tiles are not reprojected: their motion is left unread.
    let motion = o.motion.filter(|_| motion_source.is_some() && plan.tiles.is_none());
    // Blender's Vector pass is converted as it is read; other motion is negated for OptiX's.
    let negate = motion == Some(MotionConvention::Optix) && motion_source != Some(io::MotionSource::BlenderVector);
    let accumulate = motion.is_some() && o.accumulate;
    let options = rae_core::Options {
        precision,
        tiles: o.tiles,
        motion: motion.is_some(),
        accumulate,
        max_memory: o.max_memory,
        ..Default::default()
    };
    let mut d = Denoiser::with_options(&gpu.device, &gpu.queue, &weights, seq.width, seq.height, options)?;
    let used: Vec<&str> = weights.arch.required_buffers().iter().map(|b| b.name()).collect();
    println!(
        "input:   {} ({}, {} frames {}..{}, {}x{})",
        o.input.display(),
        seq.layout,
        seq.numbers.len(),
        seq.numbers[0],
        seq.numbers[seq.numbers.len() - 1],
        seq.width,
        seq.height
    );
    println!(
        "buffers: {:?}{}",
        seq.slots.iter().map(|s| s.name()).collect::<Vec<_>>(),
        if seq.has_reference() { " (reference used for error only)" } else { "" }
    );
    if !seq.ignored.is_empty() {
        println!("ignored: {:?} (layers rae does not read)", seq.ignored);
    }
    println!("model:   {} (uses {used:?})", weights_path.display());
    match weights.arch.miss_by() {
        (false, false) => println!("misses:  not told (the model reads neither depth nor normal)"),
        by => println!(
            "misses:  told by {}: albedo 1 there, the input color kept",
            match by {
                (true, true) => "depth and normal",
                (true, false) => "depth",
                _ => "normal",
            }
        ),
    }
    match (motion_source, o.motion) {
        (None, _) => println!("motion:  none (the hidden state is not reprojected)"),
        (Some(_), None) => println!("motion:  not used (--no-motion)"),
        (Some(source), Some(_)) if plan.tiles.is_some() => println!("motion:  {source} not used (frames in tiles are not reprojected)"),
        (Some(source @ io::MotionSource::BlenderVector), Some(_)) => println!("motion:  {source}"),
        (Some(source), Some(MotionConvention::Rae)) => println!("motion:  {source}, rae convention"),
        (Some(source), Some(MotionConvention::Optix)) => println!("motion:  {source}, OptiX convention (negated)"),
    }
    if motion.is_some() {
        println!(
            "blend:   {}",
            if accumulate { "the output accumulated along the motion (--no-accumulate turns it off)" } else { "none (--no-accumulate)" }
        );
    }
    println!("device:  {}", gpu.describe());
    println!(
        "tile:    {} at full resolution, {} sources ({})",
        d.conv_tiles()[0],
        d.sources_name(),
        match o.tiles {
            TileChoice::Auto => "auto",
            TileChoice::Tuned | TileChoice::TunedAmong(_) => "tuned",
            TileChoice::TunedMma => "tuned-mma",
            TileChoice::Fixed(_) => "--tile",
        }
    );
    let mib = |b: u64| b.div_ceil(1 << 20);
    let cap = o.max_memory.map_or(String::new(), |c| format!(" under a cap of {} MiB", mib(c)));
    match d.tile_plan() {
        None => println!("memory:  at most {} MiB, {} activations, the frame whole{cap}", mib(plan.total()), precision.name()),
        Some(t) => println!(
            "memory:  at most {} MiB, {} activations{cap}: {} tiles of {}x{} ({} pixels of overlap; {:.2}x the whole frame's pixels){}",
            mib(plan.total()),
            precision.name(),
            t.count(),
            t.extent.0,
            t.extent.1,
            t.overlap,
            t.work_ratio(),
            if d.state_on_host() { format!("; the frame's state in host memory, {} MiB", mib(plan.host_state)) } else { String::new() }
        ),
    }
    println!("output:  {}", out_dir.display());

    let n = (seq.width * seq.height * 3) as usize;
    let mut out = vec![0f32; n];
    let (mut up, mut gpu_t, mut down) = (Vec::new(), Vec::new(), Vec::new());
    let mut reports = Vec::new();
    let mut prev: Option<(Vec<f32>, Vec<f32>, Vec<f32>)> = None; // (noisy, rae, reference)
    let (mut temporal_noisy, mut temporal_rae) = (Vec::new(), Vec::new());
    let bar = ProgressBar::new(indices.len() as u64);
    bar.set_style(ProgressStyle::with_template("{bar:40} {pos}/{len} frames  {per_sec}  ETA {eta}").expect("valid template"));
    // On lavapipe a first frame into an empty shader cache compiles on one core: a second device
    // compiles from the other end if the frame is slow to come.
    let said = bar.clone();
    let note = move || {
        said.suspend(|| eprintln!("the first frame is slow to come: compiling kernels on a second device too (lavapipe compiles at first use, into Mesa's shader cache)"))
    };
    // Tiles run one network at their extent: the helper compiles it whole at that size (the
    // same pipelines, without a second copy of the frame's state).
    let (hw, hh, helper_options) = match d.tile_plan() {
        Some(t) => (t.extent.0, t.extent.1, rae_core::Options { max_memory: None, ..options }),
        None => (seq.width, seq.height, options),
    };
    let mut helper = if o.no_helper { None } else { CompileHelper::start(&gpu, &weights, hw, hh, helper_options, note) };
    for &i in &indices {
        let mut frame = seq.load(i)?;
        if let Some((buffer, path, count)) = frame.nonfinite.first()
            && !o.allow_nonfinite
        {
            bail!(
                "{}: {count} NaN/Inf values in `{buffer}` (frame {}); fix the renderer or pass --allow-nonfinite to have rae replace them (see rae-core's input policy)",
                path.display(),
                frame.number
            );
        }
        if o.reset_at.contains(&frame.number) {
            d.reset();
            prev = None;
        }
        if negate && let Some(m) = frame.buffers.get_mut(&Slot::Motion) {
            m.iter_mut().for_each(|v| *v = -*v);
        }
        let mut inputs = frame.inputs();
        if motion.is_none() {
            inputs.motion = None;
        }
        let t = d.denoise_into(&inputs, &mut out).with_context(|| match gpu.lost() {
            Some(reason) => format!("frame {}: the GPU device was lost ({reason})", frame.number),
            None => format!("frame {}", frame.number),
        })?;
        if let Some(h) = &mut helper {
            h.first_frame_done();
        }
        up.push(ms(t.upload));
        gpu_t.push(ms(t.gpu));
        down.push(ms(t.download));
        let path = out_dir.join(format!("denoised_{:04}.exr", frame.number));
        io::write_exr(&path, seq.width, seq.height, &out, o.half)?;
        if o.png {
            io::write_png(&path.with_extension("png"), seq.width, seq.height, &out)?;
        }
        let color = frame.buffers.get(&Slot::from(InputBuffer::Color)).expect("color is required");
        let mut report = FrameReport {
            number: frame.number,
            ms: ms(t.upload + t.gpu + t.download),
            times: [ms(t.upload), ms(t.gpu), ms(t.download)],
            noisy: None,
            rae: None,
        };
        if let Some(r) = frame.reference() {
            let m = |x: &[f32]| (metrics::relmse(x, r), metrics::psnr(x, r), metrics::ssim(x, r, seq.width, seq.height));
            report.noisy = Some(m(color));
            report.rae = Some(m(&out));
            if let Some((pn, po, pr)) = &prev {
                temporal_noisy.push(metrics::temporal_error(pn, color, pr, r));
                temporal_rae.push(metrics::temporal_error(po, &out, pr, r));
            }
            // Keep this frame for the next temporal error: move the buffers, copy only the result.
            let color = frame.buffers.remove(&Slot::from(InputBuffer::Color)).expect("color is required");
            let reference = frame.buffers.remove(&Slot::Reference).expect("reference present");
            let rae = match prev.take() {
                Some((_, mut old, _)) => {
                    old.copy_from_slice(&out);
                    old
                }
                None => out.clone(),
            };
            prev = Some((color, rae, reference));
        }
        reports.push(report);
        bar.inc(1);
    }
    bar.finish_and_clear();
    if let Some(h) = helper {
        h.finish();
    }

    println!();
    println!(
        "time per frame (median of {}, frame 0 includes shader compilation): upload {:.2} ms, GPU {:.1} ms, download {:.2} ms",
        reports.len(),
        median(&mut up),
        median(&mut gpu_t),
        median(&mut down)
    );
    if reports.iter().any(|r| r.rae.is_some()) {
        println!();
        println!(
            "{:>6} {:>11} {:>11} {:>9} {:>9} {:>8} {:>8} {:>9}",
            "frame", "relMSE in", "relMSE rae", "PSNR in", "PSNR rae", "SSIM in", "SSIM rae", "ms"
        );
        for r in &reports {
            if let (Some(a), Some(b)) = (r.noisy, r.rae) {
                println!("{:>6} {:>11.4} {:>11.4} {:>9.2} {:>9.2} {:>8.4} {:>8.4} {:>9.1}", r.number, a.0, b.0, a.1, b.1, a.2, b.2, r.ms);
            }
        }
        let mean = |f: &dyn Fn(&FrameReport) -> Option<f64>| {
            let v: Vec<f64> = reports.iter().filter_map(f).collect();
            v.iter().sum::<f64>() / v.len().max(1) as f64
        };
        println!(
            "{:>6} {:>11.4} {:>11.4} {:>9.2} {:>9.2} {:>8.4} {:>8.4} {:>9.1}",
            "mean",
            mean(&|r| r.noisy.map(|m| m.0)),
            mean(&|r| r.rae.map(|m| m.0)),
            mean(&|r| r.noisy.map(|m| m.1)),
            mean(&|r| r.rae.map(|m| m.1)),
            mean(&|r| r.noisy.map(|m| m.2)),
            mean(&|r| r.rae.map(|m| m.2)),
            mean(&|r| Some(r.ms)),
        );
        if !temporal_rae.is_empty() {
            let avg = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
            println!(
                "temporal error (mean |d out - d ref| between frames, tonemapped): input {:.5}, rae {:.5}",
                avg(&temporal_noisy),
                avg(&temporal_rae)
            );
        }
    } else {
        println!("(no reference in the sequence: no error reported)");
    }
    if let Some(path) = &o.csv {
        io::write_text(path, &csv_text(&reports))?;
        println!("wrote per-frame times and errors to {}", path.display());
    }
    println!("wrote {} frames to {}", reports.len(), out_dir.display());
    Ok(())
}

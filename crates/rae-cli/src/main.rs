//! rae-cli: the command-line face of rae-core.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::Parser;
use rae_cli::args::{Cli, Command, PrecisionArg, parse_cap, parse_memory, parse_motion, parse_sources, parse_tile};
use rae_cli::denoise;
use rae_core::golden::{Golden, Tolerance};
use rae_core::graph::Graph;
use rae_core::metrics::median;
use rae_core::{Denoiser, Gpu, GpuFrameIo, Options, Precision, SourceAccess, Tile, TileChoice, WeightMemory, Weights};

fn bench(path: &Path, sizes: &[(u32, u32)], frames: usize, warmup: usize, layers: bool, sweep: &Sweep, peak: Option<f64>) -> Result<()> {
    let weights = Weights::load(path)?;
    let gpu = Gpu::new()?;
    let flop_px = 2.0 * Graph::new(&weights.arch).macs_per_pixel();
    let resident = gpu.device.features().contains(wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS);
    println!("adapter: {}; weights: {}; {frames} timed frames after {warmup} warm-up", gpu.describe(), path.display());
    // Both precisions run everywhere: f16 is rgba16float storage (core WebGPU), arithmetic f32.
    println!(
        "total = upload + gpu + download: a frame from host slices to host slices (gpu: submit to done, the host<->device copies included)"
    );
    println!(
        "resident: GPU timestamps around a frame on GPU buffers (the path of a renderer that records rae into its own encoder), frames submitted back to back; pipelined: wall time per frame of that run; GFLOP/s from resident where the device has encoder timestamps, else from gpu"
    );
    println!(
        "peak MiB: the buffers and textures the denoiser holds (frames allocate nothing); alloc MiB: the device allocator's live total, wgpu's own included, where the backend reports it"
    );
    println!(
        "precisions: f32, f16 (f16 = rgba16float activations, f32 arithmetic; SHADER_F16 {})",
        gpu.device.features().contains(wgpu::Features::SHADER_F16)
    );
    println!(
        "tile: the conv tile (rows x output blocks per invocation), `tuned` per conv on this device; weights: uniform chunks or one storage buffer (the lanes and Winograd lanes tiles read a weight texture whatever it says); sources: the convs' inputs as sampled or storage textures (`mixed`: tuned per conv); build: seconds to build the denoiser (compiling, tuning)"
    );
    println!(
        "err: the last timed frame's largest difference from the same frames in f32 with the {} tile, over that frame's largest value",
        reference_tile(&gpu.device)
    );
    println!(
        "matrix units (mma tiles on tensor cores): {}",
        if rae_core::kernels::matrix_units_supported(&gpu.device) { "yes" } else { "no (mma tiles emulated)" }
    );
    println!(
        "{:>10} {:>9} {:>12} {:>7} {:>7} {:>6} {:>6} {:>6} {:>10} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>7} {:>9} {:>9} {:>8}",
        "size",
        "precision",
        "tile",
        "weights",
        "sources",
        "motion",
        "tiles",
        "build",
        "total ms",
        "upload",
        "gpu",
        "download",
        "resident",
        "pipelined",
        "GFLOP/s",
        "of peak",
        "peak MiB",
        "alloc MiB",
        "err"
    );
    for &(w, h) in sizes {
        let s = format!("{w}x{h}");
        let n = (w * h) as usize;
        let (wave, one, pan) = bench_buffers(w, h);
        // The frames every combination's error is taken against: as many, in f32, with the
        // reference tile, with motion where the combination has it.
        let mut references: Vec<((bool, bool), Vec<f32>)> = Vec::new();
        for &(motion, accumulate) in &sweep.motions {
            let options = Options { tiles: TileChoice::Fixed(reference_tile(&gpu.device)), motion, accumulate, ..Default::default() };
            let mut d = Denoiser::with_options(&gpu.device, &gpu.queue, &weights, w, h, options)
                .with_context(|| format!("building the reference denoiser at {s}"))?;
            let mut out = vec![0.0; 3 * n];
            for _ in 0..warmup + frames.max(1) {
                d.denoise_into(&bench_frame(&wave, &one, &pan, motion), &mut out)?;
            }
            references.push(((motion, accumulate), out));
        }
        for options in sweep.combinations() {
            let frame = bench_frame(&wave, &one, &pan, options.motion);
            let reference = &references.iter().find(|(m, _)| *m == (options.motion, options.accumulate)).expect("one per motion").1;
            let (precision, tiles) = (options.precision, options.tiles);
            let built = Instant::now();
            let mut d = match Denoiser::with_options(&gpu.device, &gpu.queue, &weights, w, h, options) {
                Ok(d) => d,
                // A tile this combination cannot run (e.g. mma with uniform weights): say so and go on.
                Err(e @ rae_core::Error::UnsupportedTile { .. }) => {
                    println!(
                        "{s:>10} {:>9} {:>12} {:>7} {:>7} {:>6} unsupported: {e}",
                        precision.name(),
                        tiles.to_string(),
                        options.weights.map_or("auto", |m| m.name()),
                        options.sources.map_or("auto", |m| m.name()),
                        motion_name(&options)
                    );
                    continue;
                }
                Err(e) => return Err(e).with_context(|| format!("building the {} denoiser at {s}", precision.name())),
            };
            let build_s = built.elapsed().as_secs_f64();
            let mut out = vec![0.0; 3 * n];
            for _ in 0..warmup {
                d.denoise_into(&frame, &mut out)?;
            }
            let (mut total, mut up, mut gpu_t, mut down) = (vec![], vec![], vec![], vec![]);
            for _ in 0..frames.max(1) {
                let t = Instant::now();
                let f = d.denoise_into(&frame, &mut out)?;
                total.push(t.elapsed().as_secs_f64() * 1e3);
                up.push(f.upload.as_secs_f64() * 1e3);
                gpu_t.push(f.gpu.as_secs_f64() * 1e3);
                down.push(f.download.as_secs_f64() * 1e3);
            }
            // The frame's padded size (a tiled denoiser's network runs at its tiles' extent).
            let (pw, ph) = d.tile_plan().map_or(d.padded_size(), |t| (t.pwidth, t.pheight));
            let g = median(&mut gpu_t);
            let err = relative_difference(&out, reference);
            // Tiled frames take host slices only: no resident run.
            let timed = if resident && d.tile_plan().is_none() {
                Some(resident_frames(&gpu, &mut d, &frame, frames.max(1), warmup)?)
            } else {
                None
            };
            let rate_ms = timed.map_or(g, |(r, _)| r);
            let gflops = flop_px * (pw * ph) as f64 / (rate_ms * 1e-3) / 1e9;
            // What the denoiser holds (frames allocate nothing, so it is the peak); where the
            // backend keeps an allocator report, the driver-side reservation of the whole
            // device as well.
            let mib = d.gpu_bytes() as f64 / (1 << 20) as f64;
            let alloc = gpu
                .device
                .generate_allocator_report()
                .map_or("-".to_string(), |r| format!("{:.1}", r.total_allocated_bytes as f64 / (1 << 20) as f64));
            let share = peak.map_or("-".to_string(), |p| format!("{:.1}%", 100.0 * gflops / p));
            let (res, pipe) = timed.map_or(("-".to_string(), "-".to_string()), |(r, p)| (format!("{r:.2}"), format!("{p:.2}")));
            println!(
                "{s:>10} {:>9} {:>12} {:>7} {:>7} {:>6} {:>6} {build_s:>6.1} {:>10.2} {:>9.2} {g:>9.2} {:>9.2} {res:>9} {pipe:>9} {gflops:>9.1} {share:>7} {mib:>9.1} {alloc:>9} {err:>8.1e}",
                precision.name(),
                tiles.to_string(),
                d.weights_name(),
                d.sources_name(),
                motion_name(&options),
                tiles_name(&d),
                median(&mut total),
                median(&mut up),
                median(&mut down)
            );
            if layers {
                stage_table(&mut d, &frame, &mut out, frames.max(1))?;
            }
        }
    }
    Ok(())
}

/// The tile of `bench`'s reference frames: the CPU drivers' default there (no tuning, no
/// compiling past what `auto` does), the plain direct tile on GPUs.
fn reference_tile(device: &wgpu::Device) -> Tile {
    if device.adapter_info().device_type == wgpu::DeviceType::Cpu { Tile::cpu(device) } else { Tile::default() }
}

/// Largest |a - b| over the largest |b| (at least 1): how far a frame is from a reference, on
/// the image's scale.
fn relative_difference(a: &[f32], b: &[f32]) -> f64 {
    let scale = b.iter().fold(1.0f32, |m, v| m.max(v.abs()));
    let worst = a.iter().zip(b).fold(0.0f32, |m, (x, y)| if (x - y).is_nan() { f32::INFINITY } else { m.max((x - y).abs()) });
    (worst / scale) as f64
}

/// What `bench` times: every precision x weight memory x source access x tile.
struct Sweep {
    precisions: Vec<PrecisionArg>,
    memories: Vec<Option<WeightMemory>>,
    sources: Vec<Option<SourceAccess>>,
    tiles: Vec<TileChoice>,
    /// (reproject, accumulate) per `--motion` value.
    motions: Vec<(bool, bool)>,
    /// `--max-memory` caps in bytes (`None`: the whole frame where the device takes it).
    caps: Vec<Option<u64>>,
}

impl Sweep {
    /// The denoiser options of every combination, in the table's order.
    fn combinations(&self) -> impl Iterator<Item = Options> + '_ {
        self.motions.iter().flat_map(move |&(motion, accumulate)| {
            self.precisions.iter().flat_map(move |&p| {
                self.memories.iter().flat_map(move |&weights| {
                    self.sources.iter().flat_map(move |&sources| {
                        self.tiles.iter().flat_map(move |&tiles| {
                            self.caps.iter().map(move |&max_memory| Options {
                                precision: p.into(),
                                tiles,
                                weights,
                                sources,
                                motion,
                                accumulate,
                                max_memory,
                                ..Default::default()
                            })
                        })
                    })
                })
            })
        })
    }
}

/// The motion column of `bench`: `off`, `warp` (reprojected) or `on` (and accumulated).
fn motion_name(o: &Options) -> &'static str {
    match (o.motion, o.accumulate) {
        (false, _) => "off",
        (true, false) => "warp",
        (true, true) => "on",
    }
}

/// The tiles column of `bench`: `whole`, or columns x rows.
fn tiles_name(d: &Denoiser) -> String {
    d.tile_plan().map_or("whole".into(), |t| format!("{}x{}", t.columns.len(), t.rows.len()))
}

/// Deterministic, smooth-but-noisy host buffers of a `w` x `h` frame (color, then the one-channel
/// depth and roughness, then motion: a pan of (1.5, -0.75) pixels): timing does not depend on
/// values.
fn bench_buffers(w: u32, h: u32) -> (Vec<f32>, Vec<f32>, Vec<f32>) {
    let n = (w * h) as usize;
    let wave: Vec<f32> = (0..3 * n).map(|i| 0.5 + 0.5 * ((i as f32) * 0.37).sin()).collect();
    let one = wave[..n].to_vec();
    let pan = [1.5f32, -0.75].repeat(n);
    (wave, one, pan)
}

/// The frame `bench` times, with the pan as its motion where `motion`.
fn bench_frame<'a>(wave: &'a [f32], one: &'a [f32], pan: &'a [f32], motion: bool) -> rae_core::FrameInputs<'a> {
    rae_core::FrameInputs {
        color: wave,
        albedo: Some(wave),
        normal: Some(wave),
        depth: Some(one),
        roughness: Some(one),
        motion: motion.then_some(pan),
    }
}

/// `bench --interleave`: every combination of precision, weight memory and tile built at once
/// and timed round-robin, one frame each per round, so that slow and fast spells of a shared
/// machine fall on all of them alike; the ratio column is the median over rounds of each
/// round's time over the first combination's in that round.
fn bench_interleaved(path: &Path, sizes: &[(u32, u32)], rounds: usize, warmup: usize, sweep: &Sweep) -> Result<()> {
    let weights = Weights::load(path)?;
    let gpu = Gpu::new()?;
    let rounds = rounds.max(1);
    println!(
        "adapter: {}; weights: {}; interleaved: {rounds} rounds of one frame per combination, after {warmup} warm-up frames each",
        gpu.describe(),
        path.display()
    );
    println!(
        "ms: a frame from host slices to host slices (the `total` of bench); vs first: median over rounds of the ratio to the first combination in the same round"
    );
    println!(
        "{:>10} {:>9} {:>12} {:>7} {:>7} {:>6} {:>6} {:>9} {:>10} {:>10} {:>9}",
        "size", "precision", "tile", "weights", "sources", "motion", "tiles", "held MiB", "median ms", "fastest", "vs first"
    );
    for &(w, h) in sizes {
        let s = format!("{w}x{h}");
        let (wave, one, pan) = bench_buffers(w, h);
        let mut out = vec![0.0; wave.len()];
        // Build (and warm up) every combination before timing any.
        let mut runs = Vec::new();
        for options in sweep.combinations() {
            let (precision, tiles) = (options.precision, options.tiles);
            let mut d = Denoiser::with_options(&gpu.device, &gpu.queue, &weights, w, h, options)
                .with_context(|| format!("building the {} denoiser at {s}", precision.name()))?;
            for _ in 0..warmup {
                d.denoise_into(&bench_frame(&wave, &one, &pan, options.motion), &mut out)?;
            }
            runs.push((precision, tiles, options, d, Vec::with_capacity(rounds)));
        }
        for _ in 0..rounds {
            for (_, _, options, d, ms) in runs.iter_mut() {
                let t = Instant::now();
                d.denoise_into(&bench_frame(&wave, &one, &pan, options.motion), &mut out)?;
                ms.push(t.elapsed().as_secs_f64() * 1e3);
            }
        }
        let first = runs[0].4.clone();
        for (precision, tiles, options, d, ms) in runs.iter_mut() {
            let mut ratio: Vec<f64> = ms.iter().zip(&first).map(|(a, b)| a / b).collect();
            let fastest = ms.iter().copied().fold(f64::INFINITY, f64::min);
            println!(
                "{s:>10} {:>9} {:>12} {:>7} {:>7} {:>6} {:>6} {:>9.1} {:>10.2} {fastest:>10.2} {:>9.3}",
                precision.name(),
                tiles.to_string(),
                d.weights_name(),
                d.sources_name(),
                motion_name(options),
                tiles_name(d),
                d.gpu_bytes() as f64 / (1 << 20) as f64,
                median(ms),
                median(&mut ratio)
            );
        }
    }
    Ok(())
}

/// Time `frames` frames on GPU-resident buffers (after `warmup` untimed ones), each in its own encoder
/// and submit, back to back: the median GPU time between timestamps written before and after
/// each frame, and the wall time per frame of the whole run (what a renderer feeding rae every
/// frame would see, CPU encoding included).
fn resident_frames(gpu: &Gpu, d: &mut Denoiser, frame: &rae_core::FrameInputs, frames: usize, warmup: usize) -> Result<(f64, f64)> {
    use wgpu::util::DeviceExt;
    let dev = &gpu.device;
    let storage = |label, data: &[f32]| {
        dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytemuck::cast_slice(data),
            usage: wgpu::BufferUsages::STORAGE,
        })
    };
    let buf = |data: Option<&[f32]>, label| data.map(|v| storage(label, v));
    let (color, albedo, normal, depth, roughness, motion) = (
        storage("color", frame.color),
        buf(frame.albedo, "albedo"),
        buf(frame.normal, "normal"),
        buf(frame.depth, "depth"),
        buf(frame.roughness, "roughness"),
        buf(frame.motion, "motion"),
    );
    let output = dev.create_buffer(&wgpu::BufferDescriptor {
        label: Some("output"),
        size: (frame.color.len() * 4) as u64,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    let io = d.bind_io(&GpuFrameIo {
        color: &color,
        albedo: albedo.as_ref(),
        normal: normal.as_ref(),
        depth: depth.as_ref(),
        roughness: roughness.as_ref(),
        motion: motion.as_ref(),
        output: &output,
    })?;
    let total = frames + warmup;
    // Per frame: the opening timestamp, its spare, the closing one.
    let count = 3 * total as u32;
    let queries = dev.create_query_set(&wgpu::QuerySetDescriptor { label: Some("frames"), ty: wgpu::QueryType::Timestamp, count });
    let mut start = Instant::now();
    for i in 0..total as u32 {
        if i == warmup as u32 {
            dev.poll(wgpu::PollType::wait_indefinitely()).context("waiting for warm-up frames")?;
            start = Instant::now();
        }
        let mut enc = dev.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("resident frame") });
        rae_core::denoiser::write_opening_timestamp(&mut enc, &queries, 3 * i, 3 * i + 1);
        d.record(&mut enc, &io)?;
        enc.write_timestamp(&queries, 3 * i + 2);
        gpu.queue.submit(Some(enc.finish()));
    }
    dev.poll(wgpu::PollType::wait_indefinitely()).context("waiting for timed frames")?;
    let pipelined = start.elapsed().as_secs_f64() * 1e3 / frames as f64;
    let ticks = rae_core::denoiser::read_timestamps(dev, &gpu.queue, &queries, count).context("reading timestamps")?;
    let period = gpu.queue.get_timestamp_period() as f64 * 1e-6;
    let mut ms: Vec<f64> = ticks.chunks(3).skip(warmup).map(|p| p[2].saturating_sub(p[0]) as f64 * period).collect();
    Ok((median(&mut ms), pipelined))
}

/// Median GPU time of every stage over `frames` profiled frames, with its share and GFLOP/s.
fn stage_table(d: &mut Denoiser, frame: &rae_core::FrameInputs, out: &mut [f32], frames: usize) -> Result<()> {
    let runs: Vec<Vec<(String, f64)>> = (0..frames).map(|_| d.denoise_profiled(frame, out)).collect::<rae_core::Result<_>>()?;
    let (pw, ph) = d.padded_size();
    let nodes = &d.graph().nodes;
    let (tiles, sources, tuning) = (d.conv_tiles(), d.conv_sources(), d.tuning());
    let mut rows: Vec<(String, f64, String, f64, String, &str, String)> = Vec::new();
    for (k, (name, _)) in runs[0].iter().enumerate() {
        let mut t: Vec<f64> = runs.iter().map(|r| r[k].1).collect();
        let ms = median(&mut t);
        let node = k.checked_sub(1).and_then(|i| nodes.get(i));
        let (shape, flop) = node.map_or((String::new(), 0.0), |n| {
            let px = (pw >> n.level) as f64 * (ph >> n.level) as f64;
            (format!("L{} {}->{}", n.level, n.cin(), n.cout), 2.0 * 9.0 * (n.cin() * n.cout) as f64 * px)
        });
        let tile = k.checked_sub(1).and_then(|i| tiles.get(i)).map_or(String::new(), |t| t.to_string());
        let source = k.checked_sub(1).and_then(|i| sources.get(i)).map_or("", |s| s.name());
        // The second-fastest finalist of tuning, and how much slower it was there.
        let next = match k.checked_sub(1).and_then(|i| tuning.get(i)).map(|f| f.as_slice()) {
            Some([first, second, ..]) if first.ns > 0.0 => {
                format!("{} {} +{:.1}%", second.tile, second.sources.name(), 100.0 * (second.ns / first.ns - 1.0))
            }
            _ => String::new(),
        };
        rows.push((name.clone(), ms, shape, flop, tile, source, next));
    }
    let total: f64 = rows.iter().map(|r| r.1).sum();
    println!(
        "    {:<16} {:<16} {:>10} {:>7} {:>9} {:>7} {:>9}  {}",
        "stage",
        "level cin->cout",
        "tile",
        "sources",
        "GPU ms",
        "share",
        "GFLOP/s",
        if tuning.is_empty() { "" } else { "tuning's runner-up" }
    );
    for (name, ms, shape, flop, tile, source, next) in &rows {
        let rate = if *flop > 0.0 { format!("{:.2}", flop / (ms * 1e-3) / 1e9) } else { String::new() };
        println!("    {name:<16} {shape:<16} {tile:>10} {source:>7} {ms:>9.2} {:>6.1}% {rate:>9}  {next}", 100.0 * ms / total);
    }
    println!("    {:<16} {:<16} {:>10} {:>7} {total:>9.2}", "sum", "", "", "");
    Ok(())
}

fn info(path: &Path, sizes: &[(u32, u32)], max_memory: Option<u64>) -> Result<()> {
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
    let graph = Graph::new(a);
    let m = 1u32 << a.levels();
    for &(w, h) in sizes {
        let s = format!("{w}x{h}");
        let (pw, ph) = (w.next_multiple_of(m), h.next_multiple_of(m));
        let mib = |p: Precision| rae_core::denoiser::activation_bytes(&graph, pw, ph, p, false) as f64 / (1u64 << 20) as f64;
        println!(
            "memory {s}:  activations and hidden state {:.1} MiB f32, {:.1} MiB f16 (padded to {pw}x{ph}; weights {:.1} MiB more)",
            mib(Precision::F32),
            mib(Precision::F16),
            (a.parameter_count() * 4) as f64 / (1u64 << 20) as f64,
        );
        let (least, at) = graph.least_live_bytes(pw, ph, Precision::F32.texel_bytes());
        println!(
            "least {s}:   {:.1} MiB f32, {:.1} MiB f16 live at once while {} runs: the floor of any sharing of one texture per value",
            least as f64 / (1u64 << 20) as f64,
            graph.least_live_bytes(pw, ph, Precision::F16.texel_bytes()).0 as f64 / (1u64 << 20) as f64,
            graph.nodes[at].name,
        );
        let guided = a.inputs.iter().any(|b| matches!(b, rae_core::InputBuffer::Normal | rae_core::InputBuffer::Depth));
        let second_state = rae_core::denoiser::activation_bytes(&graph, pw, ph, Precision::F32, true)
            - rae_core::denoiser::activation_bytes(&graph, pw, ph, Precision::F32, false);
        println!(
            "motion {s}:  the reprojection's motion pyramid{} {:.1} MiB more, and a second copy of the hidden state {:.1} MiB f32 (frames with motion, Options::motion)",
            if guided { " and previous normal and depth" } else { "" },
            rae_core::denoiser::motion_bytes(pw, ph, a.levels(), guided) as f64 / (1u64 << 20) as f64,
            second_state as f64 / (1u64 << 20) as f64
        );
        println!(
            "accumulate {s}:  the output's accumulation along the motion {:.1} MiB more (the network's radiance and two frames of history, RGB f32; Options::accumulate)",
            rae_core::denoiser::accumulate_bytes(w, h) as f64 / (1u64 << 20) as f64
        );
        if let Some(cap) = max_memory {
            for p in [Precision::F32, Precision::F16] {
                println!("plan {s} {} under {} MiB:  {}", p.name(), cap >> 20, plan_text(a, w, h, p, cap));
            }
        }
    }
    Ok(())
}

/// What `info --max-memory` says of one plan: whole or tiles, and what it holds.
fn plan_text(arch: &rae_core::Arch, w: u32, h: u32, precision: Precision, cap: u64) -> String {
    let limits = wgpu::Limits::default();
    let mib = |b: u64| b as f64 / (1u64 << 20) as f64;
    match rae_core::denoiser::MemoryPlan::new(arch, w, h, precision, Some(cap), None, false, &limits) {
        Err(e) => format!("{e}"),
        Ok(p) => {
            let state = if p.host_state > 0 {
                format!("staging of a tile's state {:.0} (the frame's state in host memory: {:.0} MiB)", mib(p.state), mib(p.host_state))
            } else {
                format!("state between tiles {:.0}", mib(p.state))
            };
            let parts = format!(
                "{:.0} MiB at most: activations {:.0}, {state}, convs {:.0}, transfer buffers {:.0}",
                mib(p.total()),
                mib(p.activations),
                mib(p.convs),
                mib(p.io)
            );
            match &p.tiles {
                None => format!("the frame whole, {parts}"),
                Some(t) => format!(
                    "{} tiles of {}x{} ({}x{} interiors, {} pixels of overlap, {:.2}x the frame's pixels), {parts}",
                    t.count(),
                    t.extent.0,
                    t.extent.1,
                    t.max_interior().0,
                    t.max_interior().1,
                    t.overlap,
                    t.work_ratio()
                ),
            }
        }
    }
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
        println!(
            "{} | {:?} | {:?} | driver {} {} | f16 {f16} | timestamps {ts}",
            i.name, i.backend, i.device_type, i.driver, i.driver_info
        );
        // Matrix units the adapter exposes to shaders (wgpu's experimental cooperative matrices).
        for m in a.cooperative_matrix_properties() {
            println!("    cooperative matrix {}x{}x{} {:?} -> {:?}", m.m_size, m.n_size, m.k_size, m.ab_type, m.cr_type);
        }
        if rae_core::gpu::has_matrix_units(&a) {
            println!("    matrix units: mma tiles run on them (--tile mma32, mma32x3, tuned-mma)");
        }
    }
    Ok(())
}

fn verify(files: &[PathBuf], tiles: TileChoice) -> Result<()> {
    let gpu = Gpu::new()?;
    println!("adapter: {}", gpu.describe());
    println!("tile: {tiles}");
    println!("{:<40} {:>5} {:>9} {:>12} {:>10} {:>10}", "sequence", "frame", "size", "max |err|", "of tol", "ms");
    let mut failed = 0;
    for path in files {
        let golden = Golden::load(path)?;
        let wpath = path.with_file_name(&golden.weights);
        let weights = Weights::load(&wpath).with_context(|| format!("weights of {}", path.display()))?;
        // A golden sequence with motion is verified with its hidden state reprojected.
        let motion = golden.frames.first().is_some_and(|f| f.contains_key("motion"));
        let options = Options { tiles, motion, ..Default::default() };
        let mut d = Denoiser::with_options(&gpu.device, &gpu.queue, &weights, golden.width, golden.height, options)
            .with_context(|| format!("denoiser for {}", path.display()))?;
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
    // SAFETY: first thing in main, before any thread (clap's, wgpu's, rayon's) exists.
    unsafe { rae_core::gpu::prefer_wide_cpu_vectors() };
    match Cli::parse().command {
        Command::Denoise {
            input,
            output,
            weights,
            models,
            frames,
            reset_at,
            png,
            half,
            allow_nonfinite,
            precision,
            max_memory,
            csv,
            tile,
            no_compile_helper,
            no_motion,
            no_accumulate,
            motion_convention,
        } => {
            let frames = frames.as_deref().map(denoise::parse_range).transpose()?;
            let tiles = parse_tile(&tile)?;
            denoise::run(&denoise::Options {
                input,
                output,
                weights,
                models,
                frames,
                reset_at,
                png,
                half,
                allow_nonfinite,
                precision: precision.map(Into::into),
                max_memory: max_memory.map(|m| m.saturating_mul(1 << 20)),
                csv,
                tiles,
                no_helper: no_compile_helper,
                motion: (!no_motion).then_some(motion_convention),
                accumulate: !no_accumulate,
            })
        }
        Command::Info { file, size, max_memory } => info(&file, &size, max_memory.map(|m| m.saturating_mul(1 << 20))),
        Command::Devices => devices(),
        Command::Verify { golden, tile } => verify(&golden, parse_tile(&tile)?),
        Command::Bench {
            weights,
            sizes,
            frames,
            warmup,
            layers,
            precision,
            peak_gflops,
            tile,
            weights_memory,
            sources,
            interleave,
            motion,
            max_memory,
        } => {
            let sweep = Sweep {
                precisions: precision,
                memories: weights_memory.iter().map(|m| parse_memory(m)).collect::<Result<_>>()?,
                sources: sources.iter().map(|s| parse_sources(s)).collect::<Result<_>>()?,
                tiles: tile.iter().map(|t| parse_tile(t)).collect::<Result<_>>()?,
                motions: motion.iter().map(|m| parse_motion(m)).collect::<Result<_>>()?,
                caps: max_memory.iter().map(|m| parse_cap(m)).collect::<Result<_>>()?,
            };
            if interleave {
                bench_interleaved(&weights, &sizes, frames, warmup, &sweep)
            } else {
                bench(&weights, &sizes, frames, warmup, layers, &sweep, peak_gflops)
            }
        }
    }
}

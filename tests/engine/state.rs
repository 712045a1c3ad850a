//! Recurrence, reset, determinism, odd sizes, the caller-buffer path and input errors.

use rae_core::denoiser::TUNE_TILES;
use rae_core::kernels::{
    self, CPU_SHORT_TILE_MAX_PIXELS, CPU_WINOGRAD_MIN_BLOCKS, CPU_WINOGRAD4_MIN_PIXELS, TileList, blocks, rows_per_invocation,
};
use rae_core::{Denoiser, Error, FrameInputs, GpuFrameIo, Method, Options, SourceAccess, Tile, TileChoice, WeightMemory, Weights};
use wgpu::util::DeviceExt;

use crate::{Golden, fixture, gpu};

fn setup() -> (Golden, Weights) {
    let golden = crate::golden("golden_full_64x64.safetensors");
    let weights = Weights::load(fixture(&golden.weights)).unwrap();
    (golden, weights)
}

fn denoiser(w: &Weights, golden: &Golden) -> Denoiser {
    let g = gpu();
    Denoiser::new(&g.device, &g.queue, w, golden.width, golden.height).unwrap()
}

fn bits(v: &[f32]) -> Vec<u32> {
    v.iter().map(|x| x.to_bits()).collect()
}

#[test]
fn hidden_state_carries_over_and_reset_restores_frame_zero() {
    let (golden, weights) = setup();
    let mut d = denoiser(&weights, &golden);
    let first = d.denoise(&golden.inputs(0)).unwrap();
    for i in 1..3 {
        d.denoise(&golden.inputs(i)).unwrap();
    }
    let third_in_sequence = d.denoise(&golden.inputs(3)).unwrap();
    let mut alone = denoiser(&weights, &golden);
    let third_alone = alone.denoise(&golden.inputs(3)).unwrap();
    let diff = third_in_sequence.iter().zip(&third_alone).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
    assert!(diff > 1e-2, "frame 3 after frames 0-2 must differ from frame 3 alone (max diff {diff})");

    d.reset();
    let again = d.denoise(&golden.inputs(0)).unwrap();
    assert_eq!(bits(&again), bits(&first), "after reset() frame 0 is bit-identical");
}

#[test]
fn two_runs_are_bit_identical() {
    let (golden, weights) = setup();
    let run = || {
        let mut d = denoiser(&weights, &golden);
        (0..golden.frames.len()).flat_map(|i| bits(&d.denoise(&golden.inputs(i)).unwrap())).collect::<Vec<_>>()
    };
    assert_eq!(run(), run());
}

#[test]
fn weights_chosen_by_level_give_the_frames_of_uniform_chunks() {
    // Left open, each conv reads its weights as its level suits the adapter (on CPU drivers
    // storage on the 32x32 and smaller levels, uniform chunks on the 64x64 one: one plan, one
    // weight buffer, both layouts), and the frames are those of every conv in uniform chunks.
    // Held with the CPU drivers' one-column tile, which reads the buffer (and compiles in a
    // fraction of a direct 16-row tile's time): the lanes module's tiles read the weight
    // texture and take storage on every level (kernels::TEXEL_WEIGHTS), so that a conv's
    // pipeline is the same on either side of the 32x32 line.
    let (golden, weights) = setup();
    let g = gpu();
    let device_type = g.device.adapter_info().device_type;
    if kernels::lanes_supported(&g.device) {
        let options = Options { tiles: TileChoice::Fixed(Tile::lanes(8, 2, 2).unwrap()), ..Default::default() };
        let d = Denoiser::with_options(&g.device, &g.queue, &weights, golden.width, golden.height, options).unwrap();
        assert!(d.weight_memories().iter().all(|&m| m == WeightMemory::Storage), "{:?}", d.weight_memories());
    }
    let tiles = TileChoice::Fixed(Tile::cpu(&g.device));
    let run = |memory: Option<WeightMemory>| {
        let options = Options { tiles, weights: memory, ..Default::default() };
        let mut d = Denoiser::with_options(&g.device, &g.queue, &weights, golden.width, golden.height, options).unwrap();
        let frames = (0..2).flat_map(|i| bits(&d.denoise(&golden.inputs(i)).unwrap())).collect::<Vec<_>>();
        (d, frames)
    };
    let (by_level, frames) = run(None);
    let want: Vec<WeightMemory> = (by_level.graph().nodes.iter())
        .map(|n| WeightMemory::for_conv(device_type, golden.width >> n.level, golden.height >> n.level))
        .collect();
    assert_eq!(by_level.weight_memories(), want);
    if device_type == wgpu::DeviceType::Cpu {
        assert!(want.contains(&WeightMemory::Uniform) && want.contains(&WeightMemory::Storage), "{want:?}");
        assert_eq!(by_level.weights_name(), "mixed");
    }
    let (uniform, uniform_frames) = run(Some(WeightMemory::Uniform));
    assert_eq!(uniform.weight_memory(), Some(WeightMemory::Uniform));
    assert!(frames == uniform_frames, "weights by level change the frames");
}

#[test]
fn cpu_tiles_by_level_and_width_follow_the_rule() {
    // Left to choose, a CPU driver with subgroups runs 4-row lanes tiles on levels of at most
    // 8x8 pixels (the 64x64 golden's L3); where 8-lane subgroups allow, 4-row Winograd F(4x4)
    // lanes tiles on levels of 64x64 and more (L0) and 4-row F(2x2) ones between for convs
    // of 32 channels and more (L1, L2); and 8-row lanes tiles for the others. On 8 lanes the F(2x2)
    // one takes every conv of 32 channels and more below 64x64 (L1 and deeper).
    // The 4- and 8-row direct tiles take the same sums in the same order, so with Winograd
    // only where it is chosen the frames stay bit for bit those of the rule's tiles; against
    // the 8-row tile everywhere they differ by Winograd's rounding alone.
    let (golden, weights) = setup();
    let g = gpu();
    let run = |tiles: TileChoice| {
        let options = Options { tiles, ..Default::default() };
        let mut d = Denoiser::with_options(&g.device, &g.queue, &weights, golden.width, golden.height, options).unwrap();
        let frames = (0..2).flat_map(|i| d.denoise(&golden.inputs(i)).unwrap()).collect::<Vec<_>>();
        (d, frames)
    };
    let (auto, frames) = run(TileChoice::Auto);
    let (lanes, one_tile) = run(TileChoice::Fixed(Tile::cpu(&g.device)));
    // Staged outputs (Options::staging, left open: CPU drivers): the F(4x4) convs on levels a
    // multiple of 16 wide write a buffer the frame copies into their textures; no other tile.
    let cpu = g.device.adapter_info().device_type == wgpu::DeviceType::Cpu;
    for (d, what) in [(&auto, "auto"), (&lanes, "one tile")] {
        let staged = d.staged_convs();
        for ((n, t), s) in d.graph().nodes.iter().zip(d.conv_tiles()).zip(&staged) {
            let w = d.padded_size().0 >> n.level;
            assert_eq!(*s, cpu && t.method == Method::Winograd4Lanes && w % 16 == 0, "{what}: {} ({t}, {w} wide) staged", n.name);
        }
    }
    if g.device.adapter_info().device_type != wgpu::DeviceType::Cpu || Tile::cpu(&g.device) != Tile::CPU_LANES {
        assert!(frames.iter().zip(&one_tile).all(|(a, b)| a.to_bits() == b.to_bits()), "one tile everywhere");
        return;
    }
    let wino = kernels::winograd_lanes_supported(&g.device);
    let narrow = kernels::narrow_gathers(&g.device);
    for (n, t) in auto.graph().nodes.iter().zip(auto.conv_tiles()) {
        let (w, h) = (golden.width >> n.level, golden.height >> n.level);
        let in_blocks = blocks(n.a.channels) + n.b.map_or(0, |b| blocks(b.channels));
        let small = w * h <= CPU_SHORT_TILE_MAX_PIXELS;
        let want = if wino && w * h >= CPU_WINOGRAD4_MIN_PIXELS {
            (Method::Winograd4Lanes, 4)
        } else if wino && in_blocks >= CPU_WINOGRAD_MIN_BLOCKS && (narrow || !small) {
            (Method::WinogradLanes, rows_per_invocation(h, 4))
        } else if small {
            (Method::Lanes, rows_per_invocation(h, 4))
        } else {
            (Method::Lanes, rows_per_invocation(h, 8))
        };
        assert_eq!((t.method, t.rows), want, "{} on {w}x{h} reading {in_blocks} blocks", n.name);
    }
    let methods: Vec<Method> = auto.conv_tiles().iter().map(|t| t.method).collect();
    // On 8 lanes every conv of the 64x64 golden is Winograd's (its L0 F(4x4), its
    // deeper convs all of 32 channels and more).
    assert_eq!(methods.contains(&Method::Lanes), !(wino && narrow));
    assert_eq!(methods.contains(&Method::WinogradLanes), wino);
    assert_eq!(methods.contains(&Method::Winograd4Lanes), wino);
    // The 64x64 golden's L0 (64 wide) stages where F(4x4) runs: the goldens and
    // the frames here go through the copies.
    assert_eq!(auto.staged_convs().contains(&true), wino);
    // Winograd's rounding only: the frames within 1e-5 of the largest value.
    let scale = one_tile.iter().fold(1f32, |m, v| m.max(v.abs()));
    let worst = frames.iter().zip(&one_tile).fold(0f32, |m, (a, b)| m.max((a - b).abs()));
    assert!(worst <= 1e-5 * scale, "largest difference {worst} (scale {scale})");
    if !wino {
        assert!(frames.iter().zip(&one_tile).all(|(a, b)| a.to_bits() == b.to_bits()), "the direct tiles by level change the frames");
    }
}

#[test]
fn compiling_backwards_leaves_the_frames_of_a_fresh_denoiser() {
    // CompileHelper's pass (every stage once, last first, on whatever the buffers hold) leaves
    // garbage in the hidden state; the reset after it makes the next frame a first frame again,
    // also after frames that left a state of their own.
    let (golden, weights) = setup();
    let run = |warm: bool| {
        let mut d = denoiser(&weights, &golden);
        if warm {
            d.denoise(&golden.inputs(1)).unwrap();
            d.compile_backwards().unwrap();
        }
        (0..golden.frames.len()).flat_map(|i| bits(&d.denoise(&golden.inputs(i)).unwrap())).collect::<Vec<_>>()
    };
    assert_eq!(run(true), run(false));
}

#[test]
fn size_not_multiple_of_32_runs_and_is_cropped() {
    let (golden, weights) = setup();
    let (w, h) = (50usize, 35usize);
    let crop = |name: &str, ch: usize| -> Vec<f32> {
        let src = &golden.frames[0][name];
        (0..h).flat_map(|y| src[(y * 64) * ch..(y * 64 + w) * ch].to_vec()).collect()
    };
    let (c, a, n, dp, r) = (crop("color", 3), crop("albedo", 3), crop("normal", 3), crop("depth", 1), crop("roughness", 1));
    let g = gpu();
    let mut d = Denoiser::new(&g.device, &g.queue, &weights, w as u32, h as u32).unwrap();
    assert_eq!(d.padded_size(), (64, 64));
    let frame = FrameInputs { color: &c, albedo: Some(&a), normal: Some(&n), depth: Some(&dp), roughness: Some(&r), motion: None };
    let out = d.denoise(&frame).unwrap();
    assert_eq!(out.len(), w * h * 3);
    assert!(out.iter().all(|v| v.is_finite() && *v >= 0.0));
    // Far from the padded border the result matches the uncropped 64x64 run closely.
    let full = denoiser(&weights, &golden).denoise(&golden.inputs(0)).unwrap();
    let (x, y) = (10, 10);
    for k in 0..3 {
        let (got, want) = (out[(y * w + x) * 3 + k], full[(y * 64 + x) * 3 + k]);
        assert!((got - want).abs() < 0.05 * want.abs().max(1.0), "pixel ({x},{y}) channel {k}: {got} vs {want}");
    }
}

#[test]
fn caller_buffers_in_caller_encoder_match_host_path() {
    let (golden, weights) = setup();
    let g = gpu();
    let mut host = denoiser(&weights, &golden);
    let mut embedded = denoiser(&weights, &golden);
    let storage = |data: &[f32]| {
        g.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: None,
            contents: bytemuck::cast_slice(data),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        })
    };
    let f = &golden.frames[0];
    let (c, a, n, dp, r) =
        (storage(&f["color"]), storage(&f["albedo"]), storage(&f["normal"]), storage(&f["depth"]), storage(&f["roughness"]));
    let bytes = (golden.width * golden.height * 12) as u64;
    let out = g.device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let read = g.device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let io = embedded
        .bind_io(&GpuFrameIo {
            color: &c,
            albedo: Some(&a),
            normal: Some(&n),
            depth: Some(&dp),
            roughness: Some(&r),
            motion: None,
            output: &out,
        })
        .unwrap();
    for i in 0..2 {
        // The renderer updates its buffers, then records the denoiser into its own encoder.
        for (buf, name) in [(&c, "color"), (&a, "albedo"), (&n, "normal"), (&dp, "depth"), (&r, "roughness")] {
            g.queue.write_buffer(buf, 0, bytemuck::cast_slice(&golden.frames[i][name]));
        }
        let mut enc = g.device.create_command_encoder(&Default::default());
        embedded.record(&mut enc, &io).unwrap();
        enc.copy_buffer_to_buffer(&out, 0, &read, 0, bytes);
        g.queue.submit(Some(enc.finish()));
        let (tx, rx) = std::sync::mpsc::channel();
        read.map_async(wgpu::MapMode::Read, .., move |r| tx.send(r).unwrap());
        g.device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
        rx.recv().unwrap().unwrap();
        let got: Vec<f32> = bytemuck::cast_slice(&read.get_mapped_range(..).unwrap()).to_vec();
        read.unmap();
        let want = host.denoise(&golden.inputs(i)).unwrap();
        assert_eq!(bits(&got), bits(&want), "frame {i}: embedded path equals host path");
    }
    // A binding belongs to the denoiser that made it.
    let mut enc = g.device.create_command_encoder(&Default::default());
    assert!(host.record(&mut enc, &io).is_err());
}

#[test]
fn missing_or_wrong_sized_buffers_are_named() {
    let (golden, weights) = setup();
    let mut d = denoiser(&weights, &golden);
    let mut frame = golden.inputs(0);
    frame.roughness = None;
    let err = d.denoise(&frame).unwrap_err();
    assert!(matches!(err, Error::MissingInput { buffer: "roughness", .. }), "{err}");
    let mut frame = golden.inputs(0);
    let short = &golden.frames[0]["normal"][..100];
    frame.normal = Some(short);
    let err = d.denoise(&frame).unwrap_err();
    assert!(matches!(err, Error::InputSize { buffer: "normal", found: 100, .. }), "{err}");
    let g = gpu();
    assert!(matches!(Denoiser::new(&g.device, &g.queue, &weights, 0, 10), Err(Error::FrameSize { .. })));
}

#[test]
fn tuned_tiles_and_storage_weights_give_the_frames_of_the_default_plan() {
    // The GPU path (weights in one storage buffer, each conv's tile and source kind timed on the
    // device, so the plan may mix sampled and storage-texture sources) against the default tile (uniform chunks, storage-texture sources on
    // this CPU driver, 16 x 2 everywhere): every tile sums each output's products in the same
    // order (input block, kx, ky, lane) and both source kinds read the same texels, so frames
    // are bit-identical.
    let golden = crate::golden("golden_paper_tiny_40x24.safetensors");
    let weights = Weights::load(fixture(&golden.weights)).unwrap();
    let g = gpu();
    let fixed = Options { tiles: TileChoice::Fixed(Tile::default()), weights: Some(WeightMemory::Uniform), ..Default::default() };
    // Three candidates of TUNE_TILES (a tall, a 2-column and a short one): each is compiled on
    // lavapipe, which takes seconds per pipeline.
    const CANDIDATES: [Tile; 3] = [TUNE_TILES[0], TUNE_TILES[10], TUNE_TILES[6]];
    let tuned = Options {
        tiles: TileChoice::TunedAmong(TileList::new(&CANDIDATES)),
        weights: Some(WeightMemory::Storage),
        sources: None,
        ..Default::default()
    };
    let mut a = Denoiser::with_options(&g.device, &g.queue, &weights, golden.width, golden.height, fixed).unwrap();
    let mut b = Denoiser::with_options(&g.device, &g.queue, &weights, golden.width, golden.height, tuned).unwrap();
    assert_eq!(b.weight_memory(), Some(WeightMemory::Storage));
    let default = SourceAccess::for_device_type(g.device.adapter_info().device_type);
    assert!(a.conv_sources().iter().all(|&s| s == default), "an untuned plan reads as the device type suits");
    assert_eq!((a.sources_name(), b.conv_sources().len()), (default.name(), b.graph().nodes.len()));
    // Tuning's report: per conv, every finalist with both kinds, timed, fastest first, the
    // first being what the conv runs.
    assert!(a.tuning().is_empty());
    assert_eq!(b.tuning().len(), b.graph().nodes.len());
    for (i, f) in b.tuning().iter().enumerate() {
        assert!(f.len() >= 2 && f.len() % 2 == 0, "conv {i}: each finalist tile with both kinds");
        assert!(f.windows(2).all(|w| w[0].ns <= w[1].ns) && f[0].ns > 0.0 && f.iter().all(|x| x.ns.is_finite()), "conv {i}: {f:?}");
        assert_eq!(f[0].sources, b.conv_sources()[i]);
        assert!(CANDIDATES.contains(&f[0].tile) && f[0].tile.rows >= b.conv_tiles()[i].rows, "conv {i}: {f:?}");
        for kind in [SourceAccess::Sampled, SourceAccess::Storage] {
            assert_eq!(f.iter().filter(|x| x.sources == kind).count(), f.len() / 2);
        }
    }
    assert_eq!(b.conv_tiles().len(), b.graph().nodes.len());
    for t in b.conv_tiles() {
        assert!(CANDIDATES.iter().any(|c| c.rows >= t.rows && c.blocks >= t.blocks && c.cols >= t.cols), "tile {t} comes from a candidate");
    }
    for i in 0..golden.frames.len() {
        let (x, y) = (a.denoise(&golden.inputs(i)).unwrap(), b.denoise(&golden.inputs(i)).unwrap());
        assert_eq!(bits(&x), bits(&y), "frame {i}: tuned/storage differs from fixed/uniform");
    }
}

/// The profiled frame's first stage holds its dispatch. Lavapipe reads an opening timestamp
/// alone only at the first barrier, after prep ([`rae_core::denoiser::write_opening_timestamp`]
/// writes a spare after it): without the spare prep comes out at 0.02 ms of a 64x64 frame beside
/// the output kernel's 1.3 ms, with it 0.36 ms. The bound is the ratio of two kernels of one frame, not a speed; the best of
/// five frames, after one that compiles the pipelines, so that a kernel slowed by the tests
/// running beside it does not decide (one full run failed with the median of three).
#[test]
fn the_profiled_frame_times_its_first_stage() {
    let (golden, weights) = setup();
    let mut d = denoiser(&weights, &golden);
    let mut out = vec![0.0; (golden.width * golden.height * 3) as usize];
    d.denoise_into(&golden.inputs(0), &mut out).unwrap();
    let ratios: Vec<f64> = (0..5)
        .map(|i| {
            let stages = d.denoise_profiled(&golden.inputs(i % golden.frames.len()), &mut out).unwrap();
            let (first, last) = (&stages[0], &stages[stages.len() - 1]);
            assert_eq!((first.0.as_str(), last.0.as_str()), ("prep", "output"));
            first.1 / last.1
        })
        .collect();
    let best = ratios.iter().copied().fold(0.0, f64::max);
    assert!(best > 0.05, "prep took {ratios:.3?} of the output kernel's time: the opening timestamp came after it");
}

#[test]
fn motion_is_a_choice_of_the_denoiser_and_zero_motion_changes_nothing() {
    // Zero motion over a still scene (normal and depth those of frame 0 throughout) fetches
    // every state at its own pixel with weight 1 and passes every history test: the frames of
    // a denoiser built with motion are those of one without, bit for bit; a frame without
    // motion runs as without it. A denoiser built without motion refuses frames and GPU
    // buffers with it.
    let (golden, weights) = setup();
    let g = gpu();
    let (w, h) = (golden.width, golden.height);
    let zero = vec![0.0f32; (w * h * 2) as usize];
    let mut plain = denoiser(&weights, &golden);
    let mut moving = Denoiser::with_options(&g.device, &g.queue, &weights, w, h, Options { motion: true, ..Default::default() }).unwrap();
    let still = golden.inputs(0);
    for i in 0..3 {
        let frame = FrameInputs { normal: still.normal, depth: still.depth, ..golden.inputs(i) };
        let with_zero = FrameInputs { motion: Some(&zero), ..frame };
        let input = if i == 1 { frame } else { with_zero };
        assert_eq!(bits(&moving.denoise(&input).unwrap()), bits(&plain.denoise(&frame).unwrap()), "frame {i}");
    }
    assert!(moving.gpu_bytes() > plain.gpu_bytes(), "the motion pyramid is counted");
    let err = plain.denoise(&FrameInputs { motion: Some(&zero), ..golden.inputs(0) }).unwrap_err().to_string();
    assert!(err.contains("built without"), "{err}");
    let short = vec![0.0f32; 10];
    let err = moving.denoise(&FrameInputs { motion: Some(&short), ..golden.inputs(0) }).unwrap_err().to_string();
    assert!(err.contains("motion") && err.contains("10"), "{err}");
    let buf = |n: u64| {
        g.device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: n,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        })
    };
    let (c, m, out) = (buf(w as u64 * h as u64 * 12), buf(w as u64 * h as u64 * 8), buf(w as u64 * h as u64 * 12));
    let io = |d: &Denoiser| {
        let need = |b| weights.arch.required_buffers().contains(&b).then_some(&c);
        d.bind_io(&GpuFrameIo {
            color: &c,
            albedo: need(rae_core::InputBuffer::Albedo),
            normal: need(rae_core::InputBuffer::Normal),
            depth: need(rae_core::InputBuffer::Depth),
            roughness: need(rae_core::InputBuffer::Roughness),
            motion: Some(&m),
            output: &out,
        })
    };
    assert!(matches!(io(&plain), Err(Error::Motion(_))));
    assert!(io(&moving).is_ok());
}

#[test]
fn history_that_fails_the_test_is_dropped_as_on_a_first_frame() {
    // A frame whose depth differs from the previous frame's everywhere by more than twice the
    // tolerance fails every pixel's history test: its hidden state starts from zero, and its
    // output is that of the same frame denoised first. Depth off by half the tolerance passes:
    // history is kept and the output differs.
    let (golden, weights) = setup();
    let g = gpu();
    let (w, h) = (golden.width, golden.height);
    let zero = vec![0.0f32; (w * h * 2) as usize];
    let build = || Denoiser::with_options(&g.device, &g.queue, &weights, w, h, Options { motion: true, ..Default::default() }).unwrap();
    // Prepared depth is log1p(depth): scaling 1 + depth by e^d moves it by d. The fixture's
    // misses (depth +inf or 0) are given a surface at depth 50 first, so that every pixel moves.
    let hits: Vec<f32> = golden.inputs(1).depth.unwrap().iter().map(|&z| if z.is_finite() && z > 0.0 { z } else { 50.0 }).collect();
    let moved = |d: f32| -> Vec<f32> { hits.iter().map(|z| (1.0 + z) * d.exp() - 1.0).collect() };
    let run = |depth: &[f32], history: bool| {
        let mut den = build();
        if history {
            den.denoise(&FrameInputs { depth: Some(&hits), ..golden.inputs(1) }).unwrap();
        }
        den.denoise(&FrameInputs { depth: Some(depth), motion: Some(&zero), ..golden.inputs(1) }).unwrap()
    };
    let (far, near) = (moved(0.25), moved(0.025));
    let first = run(&far, false);
    let dropped = run(&far, true);
    let worst = first.iter().zip(&dropped).map(|(a, b)| (a - b).abs() / a.abs().max(1.0)).fold(0.0f32, f32::max);
    assert!(worst <= 1e-5, "history that fails the test: {worst} from a first frame");
    let kept = run(&near, true);
    let first_near = run(&near, false);
    let moved_by = first_near.iter().zip(&kept).map(|(a, b)| (a - b).abs() / a.abs().max(1.0)).fold(0.0f32, f32::max);
    assert!(moved_by > 1e-3, "history that passes the test changes the frame: {moved_by}");
}

#[test]
fn reprojection_runs_in_f16_storage_close_to_f32() {
    // The warped state is written in the activations' format (kernels::WARP_F16): with f16
    // storage the frames of the motion golden stay within f16's rounding of the f32 ones.
    let golden = crate::golden("golden_color_tiny_motion_96x32.safetensors");
    let weights = Weights::load(fixture(&golden.weights)).unwrap();
    let g = gpu();
    let build = |precision| {
        let options = Options { motion: true, precision, ..Default::default() };
        Denoiser::with_options(&g.device, &g.queue, &weights, golden.width, golden.height, options).unwrap()
    };
    let (mut f32s, mut f16s) = (build(rae_core::Precision::F32), build(rae_core::Precision::F16));
    for i in 0..golden.frames.len() {
        let (a, b) = (f32s.denoise(&golden.inputs(i)).unwrap(), f16s.denoise(&golden.inputs(i)).unwrap());
        let max = a.iter().fold(0.0f32, |m, v| m.max(v.abs()));
        let worst = a.iter().zip(&b).map(|(x, y)| (x - y).abs()).fold(0.0f32, f32::max);
        assert!(b.iter().all(|v| v.is_finite()) && worst <= 1e-2 * max.max(1.0), "frame {i}: {worst} of {max}");
    }
}

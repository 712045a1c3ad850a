//! rae-cli as a user runs it.

use std::process::Command;

fn rae() -> Command {
    Command::new(env!("CARGO_BIN_EXE_rae-cli"))
}

/// `bench`'s reference tile on lavapipe (rae-cli's `reference_tile`: `Tile::CPU_LANES` on CPU
/// drivers with subgroups of 8 or more lanes, as lavapipe has with AVX2 or AVX-512). Its
/// pipelines are compiled by every bench run for the error's reference frames, so tests that
/// need a fixed tile take it and add no compiling (bench_reports checks the name).
const REFERENCE_TILE: &str = "lanes8x2";

fn fixture(name: &str) -> String {
    format!("{}/../../tests/fixtures/{name}", env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn info_describes_the_reference_network() {
    let out = rae().args(["info", &fixture("weights_full.safetensors")]).output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("1504301"), "{text}");
    assert!(text.contains("73661 multiply-adds"), "{text}");
    assert!(text.contains("color, normal, depth, roughness"), "{text}");
}

#[test]
fn info_on_a_bad_file_names_it_and_fails() {
    let golden = fixture("golden_full_64x64.safetensors");
    let out = rae().args(["info", &golden]).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(err.contains("golden_full_64x64.safetensors") && err.contains("rae.arch"), "{err}");
}

#[test]
fn no_matching_adapter_says_how_to_install_lavapipe() {
    let out = rae()
        .args(["verify", &fixture("golden_paper_tiny_40x24.safetensors")])
        .env("WGPU_ADAPTER_NAME", "no-such-adapter-anywhere")
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(err.contains("mesa-vulkan-drivers") && err.contains("no-such-adapter-anywhere"), "{err}");
}

#[test]
fn verify_holds_the_chosen_tile_to_pytorch() {
    // `--tile` picks what is verified: the split matrix-unit tile (emulated here) holds the
    // golden tolerance, the plain one (f16 operands) does not, and says so with a failing exit.
    let golden = fixture("golden_paper_tiny_40x24.safetensors");
    let split = rae().args(["verify", &golden, "--tile", "mma16x3"]).output().unwrap();
    let text = String::from_utf8_lossy(&split.stdout);
    assert!(split.status.success(), "{text}{}", String::from_utf8_lossy(&split.stderr));
    assert!(text.contains("tile: mma16x3"), "{text}");
    let plain = rae().args(["verify", &golden, "--tile", "mma16"]).output().unwrap();
    assert!(!plain.status.success(), "{}", String::from_utf8_lossy(&plain.stdout));
    assert!(String::from_utf8_lossy(&plain.stderr).contains("outside the tolerance"), "{}", String::from_utf8_lossy(&plain.stderr));
    // A golden sequence with motion is verified with the hidden state reprojected.
    let motion = rae().args(["verify", &fixture("golden_color_tiny_motion_96x32.safetensors"), "--tile", REFERENCE_TILE]).output().unwrap();
    assert!(motion.status.success(), "{}{}", String::from_utf8_lossy(&motion.stdout), String::from_utf8_lossy(&motion.stderr));
}

// ---- denoise: layouts, options, and every kind of bad input ------------------------------

use std::path::{Path, PathBuf};

use exr::prelude::*;

const W: usize = 32;
const H: usize = 32;

fn wave(n: usize, k: f32) -> Vec<f32> {
    (0..n).map(|i| 0.5 + 0.4 * (i as f32 * k).sin()).collect()
}

fn write_rgb(path: &Path, w: usize, h: usize, data: &[f32]) {
    write_rgb_file(path, w, h, |x, y| {
        let i = 3 * (y * w + x);
        (data[i], data[i + 1], data[i + 2])
    })
    .unwrap();
}

fn write_y(path: &Path, w: usize, h: usize, data: &[f32]) {
    let ch = SpecificChannels::build().with_channel("Y").with_pixel_fn(|p: Vec2<usize>| (data[p.y() * w + p.x()],));
    Image::from_channels((w, h), ch).write().to_file(path).unwrap();
}

/// A per-buffer sequence of `frames` frames with every buffer and a reference.
fn per_buffer_sequence(dir: &Path, frames: u32) {
    for f in 0..frames {
        let k = 0.01 * (f + 1) as f32;
        let color = wave(W * H * 3, k);
        write_rgb(&dir.join(format!("color_{f:04}.exr")), W, H, &color);
        write_rgb(&dir.join(format!("reference_{f:04}.exr")), W, H, &wave(W * H * 3, 0.01));
        write_rgb(&dir.join(format!("albedo_{f:04}.exr")), W, H, &vec![0.5; W * H * 3]);
        write_rgb(&dir.join(format!("normal_{f:04}.exr")), W, H, &[0.0, 1.0, 0.0].repeat(W * H));
        write_y(&dir.join(format!("depth_{f:04}.exr")), W, H, &vec![3.0; W * H]);
        write_y(&dir.join(format!("roughness_{f:04}.exr")), W, H, &vec![0.5; W * H]);
    }
}

/// `rae-cli denoise` on `input` with the fixture weights. Without the compile helper: the tests
/// run two at a time on two cores, where a helper finds no idle core and only adds compiling
/// (a_cold_first_frame_gets_a_compile_helper_and_the_same_frames tests it). With
/// [`REFERENCE_TILE`] unless `extra` names a tile: these tests are about files, and `auto`'s
/// F(4x4) pipelines, which per_buffer_sequence_is_denoised_with_error_report and the bench
/// tests run, take 10-20 s each to compile; two tests that miss the shader cache at
/// once both compile.
fn denoise(input: &Path, extra: &[&str]) -> (bool, String, String) {
    let mut cmd = rae();
    cmd.arg("denoise").arg(input).args(["--weights", &fixture("weights_full.safetensors"), "--no-compile-helper"]).args(extra);
    if !extra.contains(&"--tile") {
        cmd.args(["--tile", REFERENCE_TILE]);
    }
    let out = cmd.output().unwrap();
    (out.status.success(), String::from_utf8_lossy(&out.stdout).into(), String::from_utf8_lossy(&out.stderr).into())
}

fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> =
        std::fs::read_dir(dir).map(|r| r.map(|e| e.unwrap().file_name().to_string_lossy().into()).collect()).unwrap_or_default();
    v.sort();
    v
}

fn seq_dir(tmp: &tempfile::TempDir) -> PathBuf {
    let d = tmp.path().join("seq");
    std::fs::create_dir(&d).unwrap();
    d
}

fn write_rg(path: &Path, w: usize, h: usize, data: &[f32]) {
    let ch = SpecificChannels::build()
        .with_channel("R")
        .with_channel("G")
        .with_pixel_fn(|p: Vec2<usize>| (data[2 * (p.y() * w + p.x())], data[2 * (p.y() * w + p.x()) + 1]));
    Image::from_channels((w, h), ch).write().to_file(path).unwrap();
}

/// The denoised frames of `dir`'s sequence, frame by frame, after a run into `out`.
fn denoised_frames(out: &Path) -> Vec<Vec<f32>> {
    let mut names: Vec<_> = listing(out).into_iter().filter(|n| n.starts_with("denoised_") && n.ends_with(".exr")).collect();
    names.sort();
    names
        .iter()
        .map(|n| {
            let img = read_first_rgba_layer_from_file(
                out.join(n),
                |r, _| vec![0f32; r.width() * r.height() * 3],
                |v: &mut Vec<f32>, p: Vec2<usize>, (r, g, b, _): (f32, f32, f32, f32)| {
                    let i = 3 * (p.y() * W + p.x());
                    v[i..i + 3].copy_from_slice(&[r, g, b]);
                },
            )
            .unwrap();
            img.layer_data.channel_data.pixels
        })
        .collect()
}

#[test]
fn motion_files_reproject_the_hidden_state_and_say_so() {
    // motion_NNNN.exr (R, G) beside the buffers: `denoise` reprojects with it and says where it
    // came from; --no-motion and the OptiX convention (the negated field) give other frames.
    // A sequence whose motion is missing in one frame, or of another size, is refused, naming
    // the file.
    let tmp = tempfile::tempdir().unwrap();
    let seq = seq_dir(&tmp);
    per_buffer_sequence(&seq, 3);
    let motion: Vec<f32> = (0..W * H).flat_map(|i| [1.5 + 0.1 * (i % 7) as f32, -0.75]).collect();
    for f in 0..3 {
        write_rg(&seq.join(format!("motion_{f:04}.exr")), W, H, &motion);
    }
    let run = |name: &str, extra: &[&str]| {
        let out = tmp.path().join(name);
        let mut args = vec!["-o", out.to_str().unwrap()];
        args.extend(extra);
        let (ok, text, err) = denoise(&seq, &args);
        assert!(ok, "{text}{err}");
        (text, denoised_frames(&out))
    };
    let (text, with) = run("with", &[]);
    assert!(text.contains("motion:  motion_NNNN.exr, rae convention"), "{text}");
    assert!(text.contains("blend:   the output accumulated along the motion"), "{text}");
    assert!(text.contains("misses:  told by depth and normal"), "{text}");
    let (text, without) = run("without", &["--no-motion"]);
    assert!(text.contains("motion:  not used (--no-motion)") && !text.contains("blend:"), "{text}");
    let (text, optix) = run("optix", &["--motion-convention", "optix"]);
    assert!(text.contains("OptiX convention (negated)"), "{text}");
    let (text, unblended) = run("unblended", &["--no-accumulate"]);
    assert!(text.contains("blend:   none (--no-accumulate)"), "{text}");
    assert_eq!(with[0], without[0], "frame 0 has no history to reproject");
    assert_eq!(with[0], unblended[0], "nor any output to accumulate");
    assert_ne!(with[2], without[2], "reprojected history changes later frames");
    assert_ne!(with[2], unblended[2], "accumulation changes later frames");
    assert_ne!(unblended[2], without[2], "reprojection without accumulation changes them too");
    assert_ne!(with[2], optix[2], "the other convention is the other field");
    // Motion in some frames only.
    std::fs::remove_file(seq.join("motion_0001.exr")).unwrap();
    let (ok, _, err) = denoise(&seq, &["-o", tmp.path().join("gap").to_str().unwrap()]);
    assert!(!ok && err.contains("motion") && err.contains("frame 1"), "{err}");
    // Motion of another size.
    write_rg(&seq.join("motion_0001.exr"), W / 2, H, &motion[..W * H]);
    let (ok, _, err) = denoise(&seq, &["-o", tmp.path().join("size").to_str().unwrap()]);
    assert!(!ok && err.contains("motion_0001.exr"), "{err}");
}

#[test]
fn per_buffer_sequence_is_denoised_with_error_report() {
    let tmp = tempfile::tempdir().unwrap();
    let seq = seq_dir(&tmp);
    per_buffer_sequence(&seq, 3);
    let before = listing(&seq);
    let (ok, out, err) = denoise(&seq, &["--png", "--tile", "auto"]);
    assert!(ok, "{out}{err}");
    assert!(out.contains("per-buffer files") && out.contains("relMSE") && out.contains("temporal error"), "{out}");
    let written = listing(&tmp.path().join("seq-denoised"));
    assert_eq!(
        written,
        ["denoised_0000.exr", "denoised_0000.png", "denoised_0001.exr", "denoised_0001.png", "denoised_0002.exr", "denoised_0002.png"]
    );
    assert_eq!(listing(&seq), before, "inputs untouched");
    assert!(pixels(&tmp.path().join("seq-denoised/denoised_0001.exr")).iter().flatten().all(|v| v.is_finite() && *v >= 0.0));
    // A second run goes to a new folder beside the input; --csv writes one row per frame whose
    // errors are the ones printed.
    let csv = tmp.path().join("times.csv");
    let (ok, out2, err) = denoise(&seq, &["--csv", csv.to_str().unwrap(), "--tile", "auto"]);
    assert!(ok, "{out2}{err}");
    assert!(tmp.path().join("seq-denoised-2/denoised_0002.exr").exists());
    let text = std::fs::read_to_string(&csv).unwrap();
    let rows: Vec<Vec<&str>> = text.lines().map(|l| l.split(',').collect()).collect();
    assert_eq!(rows[0][..3], ["frame", "upload_ms", "gpu_ms"]);
    assert_eq!(rows.len(), 4, "{text}");
    for (i, r) in rows[1..].iter().enumerate() {
        assert_eq!(r[0], i.to_string());
        assert!(r[2].parse::<f64>().unwrap() > 0.0, "GPU time {text}");
        let (rel_in, rel_rae): (f64, f64) = (r[4].parse().unwrap(), r[5].parse().unwrap());
        assert!(out2.contains(&format!("{rel_in:>11.4} {rel_rae:>11.4}")), "row {i} matches the printed table: {text}\n{out2}");
    }
}

/// The RGB pixels of a W x H EXR written by `denoise`.
fn pixels(path: &Path) -> Vec<[f32; 3]> {
    let img = read_first_rgba_layer_from_file(
        path,
        |res, _| vec![[0f32; 3]; res.width() * res.height()],
        |px: &mut Vec<[f32; 3]>, pos, (r, g, b, _a): (f32, f32, f32, f32)| px[pos.y() * W + pos.x()] = [r, g, b],
    )
    .unwrap();
    assert_eq!(img.layer_data.size, Vec2(W, H), "{}", path.display());
    img.layer_data.channel_data.pixels
}

#[test]
fn a_cold_first_frame_gets_a_compile_helper_and_the_same_frames() {
    // Into an empty shader cache the first frame compiles for seconds (lavapipe compiles at a
    // pipeline's first dispatch), so a second device starts compiling from the other end and
    // says so; its dispatches must not touch the frames. A run without it, on the cache the
    // first one filled, gives the same pixels. One fixed tile, bench's reference tile on CPU
    // drivers: into this test's own empty cache the test took 39 s with it and 103 s with
    // `auto`, whose F(4x4) pipelines take 10-20 s each (`docs/perf/lavapipe-2026-12-01-s26.log`).
    let tmp = tempfile::tempdir().unwrap();
    let seq = seq_dir(&tmp);
    per_buffer_sequence(&seq, 2);
    let cache = tmp.path().join("cache");
    let run = |out: &str, extra: &[&str]| {
        let o = rae()
            .env("MESA_SHADER_CACHE_DIR", &cache)
            .arg("denoise")
            .arg(&seq)
            .args(["--weights", &fixture("weights_full.safetensors"), "--tile", REFERENCE_TILE, "-o"])
            .arg(tmp.path().join(out))
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let cold = run("cold", &[]);
    assert!(cold.contains("on a second device"), "the helper started: {cold}");
    let plain = run("plain", &["--no-compile-helper"]);
    assert!(!plain.contains("on a second device"), "{plain}");
    for f in ["denoised_0000.exr", "denoised_0001.exr"] {
        let (a, b) = (pixels(&tmp.path().join("cold").join(f)), pixels(&tmp.path().join("plain").join(f)));
        assert!(a.iter().zip(&b).all(|(x, y)| x.map(f32::to_bits) == y.map(f32::to_bits)), "{f}: the helper changed the output");
    }
}

#[test]
fn a_memory_cap_runs_the_frames_in_tiles_and_too_small_a_cap_names_the_smallest() {
    // 640x448 frames: the whole plan of the full network exceeds a cap that tiles of 320
    // pixels fit, so the frames run in tiles, close to the whole run.
    let (w, h) = (640, 448);
    let tmp = tempfile::tempdir().unwrap();
    let dir = seq_dir(&tmp);
    for f in 0..2 {
        let k = 0.003 * (f + 1) as f32;
        write_rgb(&dir.join(format!("color_{f:04}.exr")), w, h, &wave(w * h * 3, k));
        write_rgb(&dir.join(format!("albedo_{f:04}.exr")), w, h, &vec![0.5; w * h * 3]);
        write_rgb(&dir.join(format!("normal_{f:04}.exr")), w, h, &[0.0, 1.0, 0.0].repeat(w * h));
        write_y(&dir.join(format!("depth_{f:04}.exr")), w, h, &wave(w * h, 0.001));
        write_y(&dir.join(format!("roughness_{f:04}.exr")), w, h, &vec![0.5; w * h]);
    }
    let arch = rae_core::Weights::load(fixture("weights_full.safetensors")).unwrap().arch;
    let limits = wgpu::Limits::default();
    let plan =
        |tiles| rae_core::denoiser::MemoryPlan::new(&arch, w as u32, h as u32, rae_core::Precision::F32, None, tiles, false, &limits);
    let whole = plan(None).unwrap().total();
    let tiled = plan(Some(rae_core::denoiser::FrameTiles { tile: 320, overlap: rae_core::denoiser::TILE_OVERLAP, host_state: false }))
        .unwrap()
        .total();
    let cap = tiled.div_ceil(1 << 20);
    assert!(cap << 20 < whole);
    let cap = cap.to_string();
    let (ok, stdout, stderr) = denoise(&dir, &["--max-memory", &cap, "-o", tmp.path().join("tiled").to_str().unwrap()]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("tiles of") && stdout.contains(&format!("under a cap of {cap} MiB")), "{stdout}");
    let (ok, _, stderr) = denoise(&dir, &["-o", tmp.path().join("whole").to_str().unwrap()]);
    assert!(ok, "{stderr}");
    let read = |d: &str| -> Vec<Vec<f32>> {
        (0..2)
            .map(|f| {
                let img = read_first_rgba_layer_from_file(
                    tmp.path().join(d).join(format!("denoised_{f:04}.exr")),
                    |res, _| vec![0f32; res.width() * res.height() * 3],
                    move |px: &mut Vec<f32>, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                        px[3 * (pos.y() * w + pos.x())..][..3].copy_from_slice(&[r, g, b])
                    },
                )
                .unwrap();
                img.layer_data.channel_data.pixels
            })
            .collect()
    };
    for (a, b) in read("whole").iter().zip(&read("tiled")) {
        let mean = a.iter().map(|v| v.abs()).sum::<f32>() / a.len() as f32;
        let diff = a.iter().zip(b).map(|(x, y)| (x - y).abs()).sum::<f32>() / a.len() as f32;
        assert!(diff < 1e-2 * mean, "tiled frames {diff} from the whole run on average (mean value {mean})");
    }
    // A cap below the smallest tiles: an error that names what they need, and nothing written.
    let out = tmp.path().join("small");
    let (ok, _, stderr) = denoise(&dir, &["--max-memory", "1", "-o", out.to_str().unwrap()]);
    assert!(!ok && stderr.contains("the smallest tiles need"), "{stderr}");
    assert!(listing(&out).iter().all(|n| !n.starts_with("denoised_")), "{:?}", listing(&out));
}

#[test]
fn frame_range_selects_frames() {
    let tmp = tempfile::tempdir().unwrap();
    let seq = seq_dir(&tmp);
    per_buffer_sequence(&seq, 3);
    let out = tmp.path().join("o");
    let (ok, so, se) = denoise(&seq, &["-o", out.to_str().unwrap(), "--frames", "1..1", "--reset-at", "1", "--tile", "2x1"]);
    assert!(ok, "{so}{se}");
    assert_eq!(listing(&out), ["denoised_0001.exr"]);
    assert!(so.contains("tile:    2x1 at full resolution, storage sources (--tile)"), "{so}");
    // A tile the kernel does not have is refused before anything is written.
    let out = tmp.path().join("o2");
    expect_error(&seq, &["-o", out.to_str().unwrap(), "--tile", "lanes16x2w2"], &["tile `lanes16x2w2`", "at most 8 rows"]);
    assert!(!out.exists(), "no output folder for a refused tile");
}

#[test]
fn blender_multilayer_exr_is_read_and_a_missing_buffer_is_named() {
    let tmp = tempfile::tempdir().unwrap();
    let seq = seq_dir(&tmp);
    for f in 0..2 {
        let mut ch = Vec::new();
        let n = W * H;
        let plane = |name: &str, v: Vec<f32>| AnyChannel::new(name, FlatSamples::F32(v));
        for (c, k) in ["R", "G", "B"].iter().zip([0.01, 0.02, 0.03]) {
            ch.push(plane(&format!("ViewLayer.Combined.{c}"), wave(n, k)));
            ch.push(plane(&format!("ViewLayer.Denoising Albedo.{c}"), vec![0.5; n]));
        }
        ch.push(plane("ViewLayer.Combined.A", vec![1.0; n]));
        for (c, v) in ["X", "Y", "Z"].iter().zip([0.0, 1.0, 0.0]) {
            ch.push(plane(&format!("ViewLayer.Denoising Normal.{c}"), vec![v; n]));
        }
        ch.push(plane("ViewLayer.Denoising Depth.Z", vec![2.0; n]));
        // The Vector pass: to the previous frame in X, Y (y up), to the next in Z, W.
        for (c, v) in ["X", "Y", "Z", "W"].iter().zip([1.5, 0.75, -1.5, -0.75]) {
            ch.push(plane(&format!("ViewLayer.Vector.{c}"), vec![v; n]));
        }
        let layer = Layer::new((W, H), LayerAttributes::default(), Encoding::FAST_LOSSLESS, AnyChannels::sort(ch.into_iter().collect()));
        Image::from_layer(layer).write().to_file(seq.join(format!("shot_{f:04}.exr"))).unwrap();
    }
    // The full model also needs roughness, which Blender does not write.
    let (ok, _, err) = denoise(&seq, &[]);
    assert!(!ok && err.contains("`roughness`"), "{err}");
    // The paper-variant fixture uses color, albedo and normal.
    let out = rae()
        .arg("denoise")
        .arg(&seq)
        .args(["--weights", &fixture("weights_paper_tiny.safetensors"), "--no-compile-helper"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}{}", String::from_utf8_lossy(&out.stderr));
    assert!(text.contains("multi-layer EXR"), "{text}");
    assert!(text.contains("motion:  the Vector pass, converted from Blender's convention (X, -Y)"), "{text}");
    assert!(text.contains("misses:  told by normal:"), "{text}");
    assert_eq!(listing(&tmp.path().join("seq-denoised")).len(), 2);
}

#[test]
fn reference_code_mosaic_png_is_read() {
    let tmp = tempfile::tempdir().unwrap();
    let seq = seq_dir(&tmp);
    for f in 0..2u32 {
        let img = image::RgbImage::from_fn(2 * W as u32, 3 * H as u32, |x, y| image::Rgb([(x * 3 + f) as u8, (y * 2) as u8, 128]));
        img.save(seq.join(format!("{f:05}.png"))).unwrap();
    }
    let (ok, out, err) = denoise(&seq, &[]);
    assert!(ok, "{out}{err}");
    assert!(out.contains("mosaic") && out.contains("relMSE"), "{out}");
}

fn expect_error(seq: &Path, extra: &[&str], needles: &[&str]) {
    let (ok, out, err) = denoise(seq, extra);
    assert!(!ok, "should fail: {out}");
    for n in needles {
        assert!(err.contains(n), "error should mention {n:?}: {err}");
    }
}

#[test]
fn empty_folder_is_an_error() {
    let tmp = tempfile::tempdir().unwrap();
    let seq = seq_dir(&tmp);
    expect_error(&seq, &[], &["seq", "no frames"]);
    assert!(!tmp.path().join("seq-denoised").exists(), "no output folder for a failed run");
}

#[test]
fn missing_color_is_an_error() {
    let tmp = tempfile::tempdir().unwrap();
    let seq = seq_dir(&tmp);
    per_buffer_sequence(&seq, 2);
    std::fs::remove_file(seq.join("color_0001.exr")).unwrap();
    expect_error(&seq, &[], &["frame 1 has no color"]);
}

#[test]
fn frames_of_different_sizes_are_an_error() {
    let tmp = tempfile::tempdir().unwrap();
    let seq = seq_dir(&tmp);
    per_buffer_sequence(&seq, 2);
    write_rgb(&seq.join("normal_0001.exr"), 16, 16, &vec![0.0; 16 * 16 * 3]);
    expect_error(&seq, &[], &["normal_0001.exr", "16x16"]);
}

#[test]
fn a_missing_frame_in_the_middle_is_an_error() {
    let tmp = tempfile::tempdir().unwrap();
    let seq = seq_dir(&tmp);
    per_buffer_sequence(&seq, 4);
    for b in ["color", "reference", "albedo", "normal", "depth", "roughness"] {
        std::fs::remove_file(seq.join(format!("{b}_0002.exr"))).unwrap();
    }
    expect_error(&seq, &[], &["frame 2 is missing"]);
}

#[test]
fn truncated_exr_fails_that_frame_and_leaves_no_partial_output() {
    let tmp = tempfile::tempdir().unwrap();
    let seq = seq_dir(&tmp);
    per_buffer_sequence(&seq, 3);
    let p = seq.join("color_0002.exr");
    let bytes = std::fs::read(&p).unwrap();
    std::fs::write(&p, &bytes[..bytes.len() * 2 / 3]).unwrap();
    let out = tmp.path().join("out");
    expect_error(&seq, &["-o", out.to_str().unwrap()], &["color_0002.exr"]);
    assert_eq!(listing(&out), ["denoised_0000.exr", "denoised_0001.exr"], "frames before the failure are complete; nothing partial");
}

#[test]
fn layers_rae_does_not_read_are_listed_and_ignored() {
    let tmp = tempfile::tempdir().unwrap();
    let seq = seq_dir(&tmp);
    let n = W * H;
    let ch: Vec<_> = ["R", "G", "B"]
        .iter()
        .flat_map(|c| {
            [
                AnyChannel::new(format!("Combined.{c}").as_str(), FlatSamples::F32(vec![0.5; n])),
                AnyChannel::new(format!("Sparkle.{c}").as_str(), FlatSamples::F32(vec![0.5; n])),
            ]
        })
        .collect();
    let layer = Layer::new((W, H), LayerAttributes::default(), Encoding::FAST_LOSSLESS, AnyChannels::sort(ch.into_iter().collect()));
    Image::from_layer(layer).write().to_file(seq.join("frame_0000.exr")).unwrap();
    let out = tmp.path().join("o");
    let run = rae()
        .arg("denoise")
        .arg(&seq)
        .args([
            "-o",
            out.to_str().unwrap(),
            "--weights",
            &fixture("weights_color_tiny.safetensors"),
            "--no-compile-helper",
            "--tile",
            REFERENCE_TILE,
        ])
        .output()
        .unwrap();
    let so = String::from_utf8_lossy(&run.stdout);
    assert!(run.status.success(), "{so}\n{}", String::from_utf8_lossy(&run.stderr));
    assert!(so.lines().any(|l| l.starts_with("ignored:") && l.contains("Sparkle")), "the header lists the layer: {so}");
    assert_eq!(listing(&out), ["denoised_0000.exr"]);
    // A file with no color layer among its layers is still an error that names them.
    let only: Vec<_> =
        ["R", "G", "B"].iter().map(|c| AnyChannel::new(format!("Sparkle.{c}").as_str(), FlatSamples::F32(vec![0.5; n]))).collect();
    let layer = Layer::new((W, H), LayerAttributes::default(), Encoding::FAST_LOSSLESS, AnyChannels::sort(only.into_iter().collect()));
    Image::from_layer(layer).write().to_file(seq.join("frame_0000.exr")).unwrap();
    expect_error(&seq, &[], &["frame_0000.exr", "no color layer", "Sparkle"]);
}

#[test]
fn nan_and_inf_pixels_are_named_unless_allowed() {
    let tmp = tempfile::tempdir().unwrap();
    let seq = seq_dir(&tmp);
    per_buffer_sequence(&seq, 2);
    let mut color = wave(W * H * 3, 0.02);
    color[5] = f32::NAN;
    color[77] = f32::INFINITY;
    write_rgb(&seq.join("color_0001.exr"), W, H, &color);
    let out = tmp.path().join("o");
    expect_error(&seq, &["-o", out.to_str().unwrap()], &["color_0001.exr", "2 NaN/Inf", "--allow-nonfinite"]);
    assert_eq!(listing(&out), ["denoised_0000.exr"], "no output for the failed frame");
    let (ok, so, se) = denoise(&seq, &["-o", tmp.path().join("p").to_str().unwrap(), "--allow-nonfinite"]);
    assert!(ok, "{so}{se}");
}

#[test]
fn output_folder_equal_to_input_or_unwritable_is_an_error() {
    let tmp = tempfile::tempdir().unwrap();
    let seq = seq_dir(&tmp);
    per_buffer_sequence(&seq, 1);
    let before = listing(&seq);
    expect_error(&seq, &["-o", seq.to_str().unwrap()], &["is the input folder"]);
    assert_eq!(listing(&seq), before);
    let file = tmp.path().join("a-file");
    std::fs::write(&file, b"x").unwrap();
    let under_file = file.join("out");
    expect_error(&seq, &["-o", under_file.to_str().unwrap()], &["a-file/out", "cannot create the output folder"]);
}

#[test]
fn weights_that_do_not_fit_are_an_error() {
    let tmp = tempfile::tempdir().unwrap();
    let seq = seq_dir(&tmp);
    for f in 0..2 {
        write_rgb(&seq.join(format!("color_{f:04}.exr")), W, H, &wave(W * H * 3, 0.01));
    }
    expect_error(&seq, &[], &["needs the `normal` buffer"]);
    let bad = tmp.path().join("bad.safetensors");
    std::fs::write(&bad, b"not weights").unwrap();
    let out = rae().arg("denoise").arg(&seq).args(["--weights", bad.to_str().unwrap()]).output().unwrap();
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("bad.safetensors"));
    // The color-only fixture fits.
    let out = rae()
        .arg("denoise")
        .arg(&seq)
        .args(["--weights", &fixture("weights_color_tiny.safetensors"), "--no-compile-helper", "--tile", REFERENCE_TILE])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
}

#[test]
fn an_installed_binary_finds_the_models_beside_it_or_in_rae_models() {
    // A copy of the binary with a `models/` folder beside it (as `cargo install` plus a copy of
    // the models leaves it) takes its models from there, before the source tree's; RAE_MODELS
    // takes precedence over both, and a folder without a fitting model is named in the error.
    let tmp = tempfile::tempdir().unwrap();
    let bin = tmp.path().join("bin");
    std::fs::create_dir_all(bin.join("models")).unwrap();
    let exe = bin.join("rae-cli");
    std::fs::copy(env!("CARGO_BIN_EXE_rae-cli"), &exe).unwrap();
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/rae-color.safetensors");
    std::fs::copy(shipped, bin.join("models/rae-color.safetensors")).unwrap();
    let seq = seq_dir(&tmp);
    per_buffer_sequence(&seq, 2);
    let run = |models_env: Option<&Path>| {
        let mut c = Command::new(&exe);
        c.arg("denoise").arg(&seq).args(["--no-compile-helper", "--tile", REFERENCE_TILE]).env_remove("RAE_MODELS");
        if let Some(m) = models_env {
            c.env("RAE_MODELS", m);
        }
        c.output().unwrap()
    };
    let out = run(None);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}{}", String::from_utf8_lossy(&out.stderr));
    assert!(text.contains("rae-color.safetensors"), "the model beside the binary: {text}");
    let empty = tmp.path().join("no-models");
    std::fs::create_dir(&empty).unwrap();
    let out = run(Some(&empty));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("no-models"), "RAE_MODELS is where it looked: {err}");
}

#[test]
fn the_shipped_model_that_fits_is_chosen() {
    // The model with the most inputs among those whose buffers the sequence has.
    let tmp = tempfile::tempdir().unwrap();
    let chosen = |dir: &Path| -> String {
        let out = rae().arg("denoise").arg(dir).args(["--no-compile-helper", "--tile", REFERENCE_TILE]).output().unwrap();
        let text = String::from_utf8_lossy(&out.stdout).to_string();
        assert!(out.status.success(), "{text}{}", String::from_utf8_lossy(&out.stderr));
        text
    };
    let full = seq_dir(&tmp);
    per_buffer_sequence(&full, 2);
    assert!(chosen(&full).contains("rae-default.safetensors"));
    // Without depth and roughness: color + albedo + normal.
    let can = tmp.path().join("can");
    std::fs::create_dir(&can).unwrap();
    for e in std::fs::read_dir(&full).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_name().unwrap().to_string_lossy().to_string();
        if !name.starts_with("depth") && !name.starts_with("roughness") {
            std::fs::copy(&p, can.join(&name)).unwrap();
        }
    }
    assert!(chosen(&can).contains("rae-color-albedo-normal.safetensors"));
    // Color alone.
    let only_color = tmp.path().join("c");
    std::fs::create_dir(&only_color).unwrap();
    write_rgb(&only_color.join("color_0000.exr"), W, H, &wave(W * H * 3, 0.01));
    assert!(chosen(&only_color).contains("rae-color.safetensors"));
}

#[test]
fn bench_refuses_a_tile_the_kernel_does_not_have() {
    for (tile, shown) in [
        ("3x1", "3x1"),
        ("8x1w3", "8x1w3"),
        ("8x1g128", "8x1g128"),
        ("big", "big"),
        ("lanes16x4w2", "lanes16x4w2"),
        ("mma24", "mma24"),
        ("mma", "mma"),
        ("mma80x3", "mma80x3"),
        ("mma32x2", "mma32x2"),
        ("wino4lanes16x4", "wino4lanes16x4"),
    ] {
        let out = rae().args(["bench", &fixture("weights_full.safetensors"), "--sizes", "32x32", "--tile", tile]).output().unwrap();
        assert!(!out.status.success(), "--tile {tile} must fail");
        let err = String::from_utf8(out.stderr).unwrap();
        assert!(err.contains(&format!("tile `{shown}`")), "{err}");
    }
}

#[test]
fn bench_and_info_refuse_a_bad_size_before_opening_a_device() {
    // A lanes tile parses too; the size is refused by the argument parser, before any GPU work.
    for (cmd, size, why) in [("bench", "0x8", "empty"), ("bench", "12", "not WxH"), ("info", "64xA", "height")] {
        let flag = if cmd == "bench" { "--sizes" } else { "--size" };
        let mut args = vec![cmd.to_string(), fixture("weights_full.safetensors"), flag.to_string(), size.to_string()];
        if cmd == "bench" {
            args.extend(["--tile".to_string(), "lanes16x4".to_string()]);
        }
        let out = rae().args(&args).output().unwrap();
        assert!(!out.status.success(), "{cmd} {flag} {size} must fail");
        let err = String::from_utf8(out.stderr).unwrap();
        assert!(err.contains(&format!("size `{size}`")) && err.contains(why), "{err}");
        assert!(!String::from_utf8(out.stdout).unwrap().contains("adapter"), "no device opened");
    }
}

/// `rae-cli bench` of the full fixture network at 32x32 in f32 with `frames` timed frames and
/// `extra` arguments: its table, after asserting that it ran.
fn bench_32x32(frames: &str, extra: &[&str]) -> String {
    let out = rae()
        .args(["bench", &fixture("weights_full.safetensors"), "--sizes", "32x32", "--frames", frames, "--precision", "f32"])
        .args(extra)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8(out.stdout).unwrap()
}

/// Every column name of bench's tables (the timing table and `--interleave`'s).
const BENCH_COLUMNS: [&str; 23] = [
    "size",
    "precision",
    "tile",
    "weights",
    "sources",
    "motion",
    "tiles",
    "held MiB",
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
    "err",
    "median ms",
    "fastest",
    "vs first",
];

/// The rows of `bench`'s table for frame size `size`, each as column name -> value, found by
/// the header: every column is right-aligned, so a value ends where its column's name ends
/// (an `unsupported: ...` row has only the columns before its reason).
fn bench_rows(text: &str, size: &str) -> Vec<std::collections::HashMap<&'static str, String>> {
    let header = text.lines().find(|l| l.trim_start().starts_with("size ")).unwrap_or_else(|| panic!("a header: {text}"));
    let ends: Vec<(&str, usize)> = BENCH_COLUMNS
        .iter()
        .filter_map(|&name| {
            header
                .match_indices(name)
                .find(|&(at, _)| {
                    let before = header[..at].chars().last().is_none_or(|c| c == ' ');
                    let after = header[at + name.len()..].chars().next().is_none_or(|c| c == ' ');
                    before && after
                })
                .map(|(at, _)| (name, at + name.len()))
        })
        .collect();
    text.lines()
        .filter(|l| l.split_whitespace().next() == Some(size))
        .map(|row| {
            let mut values = std::collections::HashMap::new();
            let mut end = 0;
            for word in row.split(' ') {
                end += word.len();
                if let Some(&(name, _)) = ends.iter().find(|&&(_, e)| e == end && !word.is_empty()) {
                    values.insert(name, word.to_string());
                }
                end += 1;
            }
            values
        })
        .collect()
}

#[test]
fn bench_times_sampled_and_storage_sources() {
    // The sources column says what each denoiser was built with; `auto` is storage textures on
    // lavapipe (sampled on GPUs). A small tile: each source kind is its own compile.
    let text = bench_32x32("1", &["--tile", "2x1", "--sources", "sampled,storage,auto"]);
    let rows = bench_rows(&text, "32x32");
    assert_eq!(rows.iter().map(|r| r["sources"].as_str()).collect::<Vec<_>>(), ["sampled", "storage", "storage"], "{text}");
    let bad = rae().args(["bench", &fixture("weights_full.safetensors"), "--sizes", "32x32", "--sources", "buffer"]).output().unwrap();
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("sources `buffer`"), "{}", String::from_utf8_lossy(&bad.stderr));
}

#[test]
fn bench_reports_each_combinations_error_and_skips_what_it_cannot_run() {
    // The err column: the reference is the CPU drivers' direct tile, which `auto` runs or
    // (with 16-lane subgroups) replaces by Winograd's on the 32-channel convs above 8x8, off
    // by Winograd's rounding; the matrix-unit kernel (emulated on lavapipe) rounds its operands
    // to f16, off by more, and its split tiles by far less; with uniform weights they cannot
    // run, which is a row saying so, not a failed run. The uniform rows come from a second run
    // without `auto`: `auto` with uniform weights everywhere is a plan of its own to compile
    // (31 s of compiling here) that tells nothing about the skipping. No warm-up frames: an
    // emulated mma frame takes 1-5 s on lavapipe, and the err column needs the reference to run
    // as many frames as the row's denoiser, which a row of err < 1e-5 checks.
    let bench = |tiles: &str, memories: &str| {
        let text = bench_32x32("1", &["--warmup", "0", "--tile", tiles, "--weights-memory", memories]);
        assert!(text.lines().next().is_some_and(|l| l.ends_with("1 timed frames after 0 warm-up")), "{text}");
        let rows = bench_rows(&text, "32x32");
        let lines: Vec<String> = text.lines().filter(|l| l.split_whitespace().next() == Some("32x32")).map(str::to_string).collect();
        (text, rows, lines)
    };
    let (text, rows, _) = bench("auto,mma16,mma16x3", "storage");
    assert!(text.contains(&format!("with the {REFERENCE_TILE} tile")), "bench's reference tile is REFERENCE_TILE: {text}");
    assert_eq!(rows.len(), 3, "{text}");
    let err = |k: usize| -> f64 { rows[k]["err"].parse().unwrap_or_else(|_| panic!("err of row {k}: {text}")) };
    let tile = |k: usize| rows[k]["tile"].as_str();
    let weights = |k: usize| rows[k]["weights"].as_str();
    assert_eq!((tile(0), weights(0)), ("auto", "storage"), "{text}");
    assert!(err(0) < 1e-5, "{text}");
    assert_eq!((tile(1), weights(1)), ("mma16", "storage"), "{text}");
    assert!((1e-6..1e-2).contains(&err(1)), "{text}");
    assert_eq!((tile(2), weights(2)), ("mma16x3", "storage"), "{text}");
    assert!(err(2) < err(1) / 10.0, "split operands: {text}");
    let (text, rows, lines) = bench("mma16,mma16x3", "uniform");
    assert_eq!(rows.len(), 2, "{text}");
    for (row, line) in rows.iter().zip(&lines) {
        assert!(row["tile"].starts_with("mma16") && row["weights"] == "uniform", "{text}");
        assert!(line.contains("unsupported:") && line.contains("storage buffer"), "{text}");
    }
}

#[test]
fn bench_times_frames_with_and_without_motion() {
    // `--motion off,warp,on`: the second and third rows' frames carry a pan, so every block's
    // state is reprojected (and the third's output accumulated); each row's error is against
    // reference frames with the same motion.
    let text = bench_32x32("1", &["--tile", REFERENCE_TILE, "--motion", "off,warp,on"]);
    let rows = bench_rows(&text, "32x32");
    assert_eq!(rows.iter().map(|r| r["motion"].as_str()).collect::<Vec<_>>(), ["off", "warp", "on"], "{text}");
    for r in &rows {
        assert!(r["err"].parse::<f64>().unwrap() < 1e-6, "the reference tile against its own frames: {text}");
    }
}

#[test]
fn bench_interleave_prints_a_row_per_combination_against_the_first() {
    // Three combinations timed round-robin, the first its own reference: bench's reference
    // tile twice, whose pipelines the other bench runs compile for their error's reference
    // frames, and the 2x1 tile bench_times_sampled_and_storage_sources compiles (lavapipe
    // compiles each distinct pipeline for seconds, the F(4x4) ones for 10-20).
    let text = bench_32x32("2", &["--tile", &format!("{REFERENCE_TILE},2x1,{REFERENCE_TILE}"), "--interleave"]);
    let rows = bench_rows(&text, "32x32");
    assert_eq!(rows.iter().map(|r| r["tile"].as_str()).collect::<Vec<_>>(), [REFERENCE_TILE, "2x1", REFERENCE_TILE], "{text}");
    assert_eq!(rows[0]["vs first"], "1.000", "{text}");
    for r in &rows {
        let number = |k: &str| -> f64 { r[k].parse().unwrap_or_else(|_| panic!("{k}: {text}")) };
        let (median, fastest, ratio) = (number("median ms"), number("fastest"), number("vs first"));
        assert!(fastest > 0.0 && fastest <= median && ratio > 0.0, "{text}");
    }
}

#[test]
fn lavapipe_gets_wide_vectors_unless_the_user_chose_a_width() {
    // rae-cli asks lavapipe for 512-bit vectors where the CPU has AVX-512 and the variable is
    // unset (rae_core::gpu::prefer_wide_cpu_vectors); a width the user set is kept.
    let avx512 = std::fs::read_to_string("/proc/cpuinfo").is_ok_and(|s| s.split_whitespace().any(|f| f == "avx512f"));
    let lavapipe = |width: Option<&str>| {
        let mut cmd = rae();
        cmd.arg("devices").env_remove("LP_NATIVE_VECTOR_WIDTH");
        if let Some(w) = width {
            cmd.env("LP_NATIVE_VECTOR_WIDTH", w);
        }
        let out = cmd.output().unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        String::from_utf8(out.stdout).unwrap().lines().find(|l| l.contains("llvmpipe") && l.contains("Vulkan")).map(str::to_string)
    };
    let Some(default) = lavapipe(None) else { return }; // no lavapipe on this machine
    assert_eq!(default.contains("512 bits"), avx512, "{default}");
    let chosen = lavapipe(Some("256")).expect("lavapipe");
    assert!(chosen.contains("256 bits"), "{chosen}");
}

#[test]
fn an_output_disk_that_fills_up_fails_naming_the_file_and_leaves_no_partial_file() {
    // The output goes to a 16 KiB tmpfs, mounted in a private mount namespace (`unshare`: as
    // root or where user namespaces are allowed) that ends with the command; inside it, what
    // the folder holds when rae-cli stops is listed and copied out.
    if !Command::new("unshare").args(["-rm", "true"]).status().is_ok_and(|s| s.success()) {
        eprintln!("skipped: no mount namespace here (unshare -rm)");
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let seq = seq_dir(&tmp);
    per_buffer_sequence(&seq, 6);
    let (small, copy) = (tmp.path().join("small"), tmp.path().join("copy"));
    std::fs::create_dir(&small).unwrap();
    let script = r#"mount -t tmpfs -o size=16k tmpfs "$SMALL" || exit 99
"$@"; status=$?
echo "listing: $(ls -A "$SMALL/out" | tr '\n' ' ')"
cp -r "$SMALL/out" "$COPY"
exit $status"#;
    let weights = fixture("weights_full.safetensors");
    let out = Command::new("unshare")
        .args(["-rm", "sh", "-c", script, "sh", env!("CARGO_BIN_EXE_rae-cli"), "denoise"])
        .arg(&seq)
        .args(["-o", &format!("{}/out", small.display()), "--weights", &weights, "--no-compile-helper", "--tile", REFERENCE_TILE])
        .env("SMALL", &small)
        .env("COPY", &copy)
        .output()
        .unwrap();
    let (stdout, stderr) = (String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert_ne!(out.status.code(), Some(99), "mount failed: {stderr}");
    assert!(!out.status.success(), "a full disk is an error: {stdout}");
    let listing_line = stdout.lines().find(|l| l.starts_with("listing:")).expect("the folder was listed");
    let written: Vec<&str> = listing_line["listing:".len()..].split_whitespace().collect();
    assert!(written.len() < 6, "the disk filled before the last frame: {written:?}");
    assert!(written.iter().all(|f| f.starts_with("denoised_") && !f.contains("partial")), "no partial file is left: {written:?}");
    let failed = format!("denoised_{:04}.exr", written.len());
    assert!(stderr.contains(&failed) && stderr.to_lowercase().contains("space"), "the error names {failed} and the problem: {stderr}");
    // What is there is whole: each frame reads back at full size.
    for f in &written {
        let pixels = pixels(&copy.join(f));
        assert_eq!(pixels.len(), W * H, "{f}");
    }
}

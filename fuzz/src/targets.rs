//! The fuzz targets: rae's weights loader, golden reader, sequence readers (per-buffer EXR,
//! multi-layer EXR with rae's and Blender's layer names, PNG and JPEG, the mosaic PNG) and the
//! command line. Each has a corpus of valid inputs built from the sample sequence and the test
//! fixtures, a dictionary of words its format cares about, and a function that runs one case.
//! A case may fail with an error; it must not panic, and a reader's error must name the file.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Parser;
use rae_core::Weights;
use rae_core::golden::Golden;
use rae_core::graph::Graph;
use rae_core::io::{Sequence, write_exr_channels};

/// What a case did.
pub enum Outcome {
    /// The input was read.
    Accepted,
    /// The input was refused with this error.
    Refused(String),
    /// The harness's own checks failed (an error that names no file, a bad value let through).
    Finding(String),
}

/// Prefix of an error that is a finding, not a refusal.
const FINDING: &str = "finding: ";

/// One target.
pub struct Target {
    /// Its name (`fuzz.sh`'s table, the crash file names, `regressions/NAME/`).
    pub name: &'static str,
    /// Valid inputs to mutate.
    pub corpus: Vec<Vec<u8>>,
    /// Words its format cares about, inserted by the mutator.
    pub words: Vec<Vec<u8>>,
    kind: Kind,
    /// The folder its cases are written into, for the readers that read files.
    dir: PathBuf,
    /// Per-buffer targets: the valid file of every slot, restored after each case.
    files: Vec<(String, Vec<u8>)>,
}

#[derive(Clone, Copy, PartialEq)]
enum Kind {
    Weights,
    Golden,
    PerBufferExr,
    MultiLayer,
    Image,
    Args,
}

/// Per-buffer slots in the order a case's first byte picks them.
const SLOTS: [&str; 7] = ["color", "albedo", "normal", "depth", "roughness", "motion", "reference"];

/// Size of the frames the corpus is cut to: small cases run fast.
const W: u32 = 16;
const H: u32 = 12;

/// Channel names of a per-buffer file of `ch` channels.
fn plain(ch: usize) -> Vec<String> {
    let names: &[&str] = match ch {
        1 => &["Y"],
        2 => &["R", "G"],
        _ => &["R", "G", "B"],
    };
    names.iter().map(|c| c.to_string()).collect()
}

fn words(list: &[&str]) -> Vec<Vec<u8>> {
    list.iter().map(|w| w.as_bytes().to_vec()).collect()
}

/// Every target, with its corpus built from the repository at `root` into `work`.
pub fn all(root: &Path, work: &Path) -> Result<Vec<Target>> {
    let fixtures = root.join("tests/fixtures");
    let read = |p: PathBuf| std::fs::read(&p).with_context(|| format!("reading seed {}", p.display()));
    let sample = Sequence::scan(&root.join("samples/random2026")).context("reading the sample sequence")?;
    let frame = sample.load(0).context("reading the sample's first frame")?;
    let crop = |data: &[f32], ch: usize| -> Vec<f32> {
        let w = sample.width as usize;
        (0..H as usize).flat_map(|y| data[(y * w) * ch..(y * w + W as usize) * ch].to_vec()).collect()
    };
    let slot_data: Vec<(&str, usize, Vec<f32>)> = frame
        .buffers
        .iter()
        .map(|(slot, data)| {
            let ch = data.len() / (sample.width * sample.height) as usize;
            (slot.name(), ch, crop(data, ch))
        })
        .collect();
    let mut targets = Vec::new();
    let mut target =
        |name: &'static str, kind: Kind, corpus: Vec<Vec<u8>>, words: Vec<Vec<u8>>, files: Vec<(String, Vec<u8>)>| -> Result<()> {
            let dir = work.join(name);
            std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
            for (f, bytes) in &files {
                std::fs::write(dir.join(f), bytes).with_context(|| format!("writing {}", dir.join(f).display()))?;
            }
            targets.push(Target { name, corpus, words, kind, dir, files });
            Ok(())
        };

    let tensor_words = words(&[
        "__metadata__",
        "rae.arch",
        "\"dtype\":\"F16\"",
        "\"shape\":[",
        "data_offsets",
        "4294967296",
        "-1",
        "1e308",
        "null",
        "[]",
        "{}",
        "\"F32\"",
    ]);
    target(
        "weights",
        Kind::Weights,
        vec![read(fixtures.join("weights_color_tiny.safetensors"))?, read(fixtures.join("weights_paper_tiny.safetensors"))?],
        [
            tensor_words.clone(),
            words(&["\"levels\":", "\"channels\":[", "\"inputs\":[\"color\"]", "\"recurrent\":", "\"features\":", "0", "99999999"]),
        ]
        .concat(),
        vec![],
    )?;
    target(
        "golden",
        Kind::Golden,
        vec![read(fixtures.join("golden_paper_tiny_40x24.safetensors"))?, read(fixtures.join("golden_color_tiny_64x32.safetensors"))?],
        [
            tensor_words,
            words(&[
                "rae.golden",
                "\"frames\":",
                "\"width\":",
                "\"height\":",
                "frame0.",
                "frame99.",
                "output",
                "color",
                "motion",
                "0",
                "18446744073709551615",
            ]),
        ]
        .concat(),
        vec![],
    )?;

    // Per-buffer EXR: a frame of every slot, each in f32 and f16; a case is a slot byte and
    // one file.
    let exr_bytes = |channels: &[String], data: &[f32], half: bool| -> Result<Vec<u8>> {
        let p = work.join(".seed.exr");
        let names: Vec<&str> = channels.iter().map(String::as_str).collect();
        write_exr_channels(&p, W, H, &names, data, half)?;
        read(p)
    };
    let mut files = Vec::new();
    let mut corpus = Vec::new();
    for (slot, ch, data) in &slot_data {
        let f32_file = exr_bytes(&plain(*ch), data, false)?;
        let i = SLOTS.iter().position(|s| s == slot).context("a slot of the sample")? as u8;
        corpus.push([&[i][..], &f32_file].concat());
        corpus.push([&[i][..], &exr_bytes(&plain(*ch), data, true)?].concat());
        files.push((format!("{slot}_0000.exr"), f32_file));
    }
    let exr_words = words(&[
        "channels",
        "dataWindow",
        "displayWindow",
        "compression",
        "lineOffsets",
        "box2i",
        "chlist",
        "R",
        "G",
        "B",
        "Y",
        "Z",
        "name",
        "type",
    ]);
    target("exr", Kind::PerBufferExr, corpus, exr_words.clone(), files)?;

    // Multi-layer EXR: rae's layer names and a real Cycles render's.
    let mut names = Vec::new();
    let mut data: Vec<f32> = Vec::new();
    let n = (W * H) as usize;
    let mut interleaved = vec![Vec::new(); n];
    for (slot, ch, d) in &slot_data {
        for c in plain(*ch) {
            names.push(format!("{slot}.{c}"));
        }
        for (p, px) in interleaved.iter_mut().enumerate() {
            px.extend_from_slice(&d[p * ch..(p + 1) * ch]);
        }
    }
    interleaved.into_iter().for_each(|px| data.extend(px));
    let rae_layers = exr_bytes(&names, &data, true)?;
    let blender = read(fixtures.join("blender_vector/frame_0001.exr"))?;
    let layer_words = words(&[
        "ViewLayer.",
        "Combined",
        "Denoising Albedo",
        "Denoising Normal",
        "Denoising Depth",
        "Vector",
        "Noisy Image",
        "Mist",
        "roughness",
        "reference",
        "motion",
        ".X",
        ".W",
    ]);
    target("multilayer", Kind::MultiLayer, vec![rae_layers, blender], [exr_words, layer_words].concat(), vec![])?;

    // PNG and JPEG: a per-buffer color PNG, a color JPEG and a mosaic PNG; a case is a kind
    // byte and one file.
    let srgb = |v: f32| (rae_core::io::tonemap(v) * 255.0) as u8;
    let color = &slot_data.iter().find(|(s, _, _)| *s == "color").context("sample color")?.2;
    let rgb8 = image::RgbImage::from_fn(W, H, |x, y| {
        let i = ((y * W + x) * 3) as usize;
        image::Rgb([srgb(color[i]), srgb(color[i + 1]), srgb(color[i + 2])])
    });
    let encode = |img: &image::RgbImage, format: image::ImageFormat| -> Result<Vec<u8>> {
        let mut out = std::io::Cursor::new(Vec::new());
        img.write_to(&mut out, format)?;
        Ok(out.into_inner())
    };
    let mosaic = image::RgbImage::from_fn(2 * W, 3 * H, |x, y| *rgb8.get_pixel(x % W, y % H));
    let image_corpus = vec![
        [&[0u8][..], &encode(&rgb8, image::ImageFormat::Png)?].concat(),
        [&[1u8][..], &encode(&rgb8, image::ImageFormat::Jpeg)?].concat(),
        [&[2u8][..], &encode(&mosaic, image::ImageFormat::Png)?].concat(),
    ];
    target("image", Kind::Image, image_corpus, words(&["IHDR", "IDAT", "IEND", "PLTE", "tRNS", "\u{ff}\u{d8}", "JFIF"]), vec![])?;

    // The command line: arguments separated by NUL bytes.
    let lines: [&[&str]; 8] = [
        &["denoise", "seq", "--frames", "2..5", "--reset-at", "3,7", "--tile", "auto", "--precision", "f16"],
        &["denoise", "seq", "-o", "out", "--frames", "..4", "--motion-convention", "optix", "--no-motion"],
        &["info", "model.safetensors", "--size", "1920x1080,64x64", "--max-memory", "1024"],
        &[
            "bench",
            "w.safetensors",
            "--sizes",
            "256x256",
            "--tile",
            "lanes8x2w2,wino4lanes4x4g16,tuned:mma16+16x4",
            "--weights-memory",
            "uniform,auto",
        ],
        &["bench", "w.safetensors", "--sources", "sampled,storage", "--motion", "off,on", "--frames", "3", "--max-memory", "none,512"],
        &["verify", "a.safetensors", "b.safetensors", "--tile", "mma32x3"],
        &["denoise", "seq", "--frames", "7"],
        &["devices"],
    ];
    let args_corpus = lines.iter().map(|l| l.join("\0").into_bytes()).collect();
    let args_words = words(&[
        "\0",
        "--frames",
        "..",
        "--tile",
        "--size",
        "x",
        "4294967296",
        "-1",
        "0x0",
        "--reset-at",
        ",",
        "lanes",
        "wino",
        "mma",
        "tuned:",
        "+",
        "g",
        "k",
        "w",
        "--precision",
        "--max-memory",
        "none",
        "=",
        "--",
    ]);
    target("args", Kind::Args, args_corpus, args_words, vec![])?;
    Ok(targets)
}

impl Target {
    /// Runs one case. A panic propagates.
    pub fn run(&self, case: &[u8]) -> Outcome {
        match self.outcome(case) {
            Ok(()) => Outcome::Accepted,
            Err(message) if message.starts_with(FINDING) => Outcome::Finding(message[FINDING.len()..].to_string()),
            Err(message)
                if self.kind == Kind::Args || message.contains(&self.dir.display().to_string()) || message.contains("case.safetensors") =>
            {
                Outcome::Refused(message)
            }
            Err(message) => Outcome::Finding(format!("an error that names no file: {message}")),
        }
    }

    fn outcome(&self, case: &[u8]) -> std::result::Result<(), String> {
        match self.kind {
            Kind::Weights => Weights::from_bytes(case, "case.safetensors")
                .map(|w| {
                    let graph = Graph::new(&w.arch);
                    let _ = graph.macs_per_pixel();
                })
                .map_err(|e| e.to_string()),
            Kind::Golden => Golden::from_bytes(case, "case.safetensors").map_err(|e| e.to_string()).and_then(|g| {
                for i in 0..g.frames.len() {
                    g.inputs(i)
                        .validate(&[rae_core::InputBuffer::Color], g.width, g.height)
                        .map_err(|e| format!("case.safetensors: {e}"))?;
                }
                Ok(())
            }),
            Kind::Args => run_args(case),
            Kind::PerBufferExr => {
                let Some((&first, file)) = case.split_first() else { return Ok(()) };
                let slot = SLOTS[first as usize % SLOTS.len()];
                let path = self.dir.join(format!("{slot}_0000.exr"));
                std::fs::write(&path, file).map_err(|e| format!("harness: {e}"))?;
                let outcome = read_sequence(&self.dir);
                let good = self.files.iter().find(|(f, _)| f.starts_with(slot)).map(|(_, b)| b.as_slice()).unwrap_or(&[]);
                if good.is_empty() {
                    let _ = std::fs::remove_file(&path);
                } else {
                    std::fs::write(&path, good).map_err(|e| format!("harness: {e}"))?;
                }
                outcome
            }
            Kind::MultiLayer => self.one_file("frame_0000.exr", case),
            Kind::Image => {
                let Some((&first, file)) = case.split_first() else { return Ok(()) };
                self.one_file(["color_0000.png", "color_0000.jpg", "mosaic_0000.png"][first as usize % 3], file)
            }
        }
    }

    /// The folder holds only `name`, with `bytes`; the sequence in it is read.
    fn one_file(&self, name: &str, bytes: &[u8]) -> std::result::Result<(), String> {
        let path = self.dir.join(name);
        std::fs::write(&path, bytes).map_err(|e| format!("harness: {e}"))?;
        let outcome = read_sequence(&self.dir);
        std::fs::remove_file(&path).map_err(|e| format!("harness: {e}"))?;
        outcome
    }

    /// What an error says, without the numbers and paths that vary: cases that reach a new
    /// kind of refusal join the corpus.
    pub fn error_kind(message: &str) -> String {
        message.chars().filter(|c| !c.is_ascii_digit()).take(80).collect()
    }
}

/// Reads a sequence as `rae-cli denoise` does before it opens a device: scan, every frame,
/// their buffers' sizes checked.
fn read_sequence(dir: &Path) -> std::result::Result<(), String> {
    let seq = Sequence::scan(dir).map_err(|e| e.to_string())?;
    for i in 0..seq.numbers.len() {
        let frame = seq.load(i).map_err(|e| e.to_string())?;
        frame.inputs().validate(&seq.inputs(), seq.width, seq.height).map_err(|e| format!("{}: {e}", dir.display()))?;
        if let Some(r) = frame.reference()
            && r.len() != 3 * (seq.width * seq.height) as usize
        {
            return Err(format!("{FINDING}{}: the reference has {} values", dir.display(), r.len()));
        }
    }
    Ok(())
}

fn run_args(case: &[u8]) -> std::result::Result<(), String> {
    let text = String::from_utf8_lossy(case);
    let args = std::iter::once("rae-cli").chain(text.split('\0'));
    let outcome: Result<()> = (|| {
        let cli = rae_cli::args::Cli::try_parse_from(args)?;
        cli.command.check()?;
        if let rae_cli::args::Command::Info { size, max_memory, .. } = &cli.command {
            if size.iter().any(|&(w, h)| w == 0 || h == 0) {
                bail!("a zero size passed the parser");
            }
            // The plan under the cap, as `info` makes it: a panic here is a finding.
            if let Some(cap) = max_memory {
                let arch = rae_core::Arch::reference();
                let limits = wgpu::Limits::default();
                for &(w, h) in size {
                    for p in [rae_core::Precision::F32, rae_core::Precision::F16] {
                        let cap = Some(cap.saturating_mul(1 << 20));
                        let _ = rae_core::denoiser::MemoryPlan::new(&arch, w, h, p, cap, None, false, &limits);
                    }
                }
            }
        }
        Ok(())
    })();
    match outcome {
        Err(e) if e.to_string().contains("passed the parser") => Err(format!("{FINDING}{e}")),
        other => other.map_err(|e| e.to_string()),
    }
}

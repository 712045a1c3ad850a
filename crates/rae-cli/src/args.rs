//! rae-cli's command line: its subcommands, their arguments and the parsers of the values
//! clap leaves as text.

use std::path::PathBuf;

use anyhow::{Result, bail};
use clap::{Parser, Subcommand};
use rae_core::frame::parse_size;
use rae_core::{Precision, SourceAccess, TileChoice, WeightMemory};

use crate::denoise;

/// rae-cli's command line.
#[derive(Parser)]
#[command(name = "rae-cli", version, about = "Recurrent denoising autoencoder for path-traced sequences, on wgpu")]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands and their arguments.
#[derive(Subcommand)]
pub enum Command {
    /// Denoise a folder of frames (per-buffer EXR/PNG, multi-layer EXR or mosaic PNG) into EXR,
    /// reporting time per frame and, where a reference exists, relMSE, PSNR, SSIM and temporal
    /// error of the input and of the result.
    Denoise {
        /// Folder holding one frame sequence.
        input: PathBuf,
        /// Output folder (default: a new folder beside the input).
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Weights file (default: the shipped model that fits the buffers present).
        #[arg(long)]
        weights: Option<PathBuf>,
        /// Folder of shipped models (default: $RAE_MODELS, else `models/` beside the executable
        /// or in `../share/rae/` from it, else the source tree's `models/`).
        #[arg(long)]
        models: Option<PathBuf>,
        /// Frame numbers to denoise: A..B, A.., ..B or A (inclusive).
        #[arg(long)]
        frames: Option<String>,
        /// Frame numbers at which the hidden state is reset (scene cuts), e.g. 12,40.
        #[arg(long, value_delimiter = ',')]
        reset_at: Vec<u32>,
        /// Also write tonemapped sRGB PNG previews.
        #[arg(long)]
        png: bool,
        /// Storage precision of activations on the GPU (arithmetic is f32 either way); default
        /// f32, or f16 where --max-memory is too small for f32.
        #[arg(long, value_enum)]
        precision: Option<PrecisionArg>,
        /// Cap in MiB on the GPU memory the denoiser holds (its transfer buffers included):
        /// frames whose whole plan exceeds it run in overlapping tiles, the largest that fit
        /// (frames past the device's texture or binding limits too, cap or not).
        #[arg(long)]
        max_memory: Option<u64>,
        /// Write half-float EXR instead of float.
        #[arg(long)]
        half: bool,
        /// Replace NaN/Inf input values (input policy) instead of refusing the frame.
        #[arg(long)]
        allow_nonfinite: bool,
        /// Write per-frame times (upload, GPU, download ms) and, where a reference exists,
        /// relMSE/PSNR/SSIM of input and result to this CSV file.
        #[arg(long)]
        csv: Option<PathBuf>,
        /// Conv register tile, as `bench --tile` takes it (one): `auto` (tuned on GPUs; on CPU
        /// drivers wino4lanes4x4 on levels of 64x64 and more, winolanes4x4 for convs of 32+
        /// channels below those (down to 16x16 on 16-lane subgroups, to 1x1 on 8-lane ones),
        /// lanes8x2 for the others, lanes4x2 on levels of at most 8x8), `tuned`, or a fixed
        /// tile. On lavapipe a two-column lanes tile (`lanes8x2w2`) runs faster on large levels
        /// than a one-column one and compiles into an empty shader cache for eight times as long.
        #[arg(long, default_value = "auto")]
        tile: String,
        /// On CPU drivers, do not compile kernels on a second device while a slow first frame
        /// compiles them (lavapipe compiles at first use, one core per device; the helper starts
        /// only if the first frame takes longer than a warm one could, i.e. into an empty shader
        /// cache).
        #[arg(long)]
        no_compile_helper: bool,
        /// Do not reproject the hidden state with the sequence's motion (motion_NNNN.exr, or a
        /// multi-layer EXR's motion layer or Blender Vector pass), for comparison.
        #[arg(long)]
        no_motion: bool,
        /// Do not blend each output frame with the previous one along the motion (temporal
        /// accumulation, rae_core::accumulate), for comparison; it runs wherever the hidden
        /// state is reprojected.
        #[arg(long)]
        no_accumulate: bool,
        /// What the motion files mean: `rae` (where the pixel's surface point was in the
        /// previous frame minus where it is now, in pixels, x right, y down) or `optix` (current
        /// minus previous, OptiX's flow). Blender's Vector pass is converted whatever this says.
        #[arg(long, value_enum, default_value_t = denoise::MotionConvention::Rae)]
        motion_convention: denoise::MotionConvention,
    },
    /// Print a weights file's architecture, inputs, parameter count and cost per pixel.
    Info {
        /// A .safetensors weights file written by weights-tool.
        file: PathBuf,
        /// Also report GPU memory for these frame sizes (WxH), f32 and f16.
        #[arg(long, value_delimiter = ',', value_parser = parse_size)]
        size: Vec<(u32, u32)>,
        /// With --size: the plan under this cap in MiB (whole frame or tiles), on a device
        /// with WebGPU's default limits (8192-pixel textures, 128 MiB storage bindings).
        #[arg(long)]
        max_memory: Option<u64>,
    },
    /// List the adapters wgpu sees (WGPU_BACKEND filters; WGPU_ADAPTER_NAME picks one).
    Devices,
    /// Run golden sequences (written by weights-tool) on the GPU and report the error against
    /// PyTorch and the time per frame; fails if any value is outside 1e-4 * max(1, |torch|).
    Verify {
        /// Golden .safetensors files; their weights file is looked up beside them.
        #[arg(required = true)]
        golden: Vec<PathBuf>,
        /// The conv tile to hold to PyTorch, as `bench --tile` takes it (one): `auto` (what
        /// `denoise` uses), a fixed tile such as `mma32x3`, or `tuned`.
        #[arg(long, default_value = "auto")]
        tile: String,
    },
    /// Time frames of a weights file on the chosen adapter: median ms per frame (after
    /// warm-up) split into upload, GPU and download, achieved GFLOP/s (and share of a stated
    /// peak), and the GPU memory the denoiser holds (its peak: frames allocate nothing).
    Bench {
        /// A .safetensors weights file.
        weights: PathBuf,
        /// Frame sizes, WxH.
        #[arg(long, value_delimiter = ',', default_value = "256x256,512x512,1280x720", value_parser = parse_size)]
        sizes: Vec<(u32, u32)>,
        /// Timed frames per size (after the warm-up frames).
        #[arg(long, default_value_t = 10)]
        frames: usize,
        /// Untimed frames before the timed ones, in each timed run (host to host, resident,
        /// interleaved): the first frame compiles on drivers that compile at first use
        /// (lavapipe), and caches and clocks settle. 0 times the first frames too.
        #[arg(long, default_value_t = 2)]
        warmup: usize,
        /// Also time every stage with GPU timestamp queries and print a table per size.
        #[arg(long)]
        layers: bool,
        /// Storage precisions to time.
        #[arg(long, value_enum, value_delimiter = ',', default_value = "f32,f16")]
        precision: Vec<PrecisionArg>,
        /// The adapter's fp32 peak in GFLOP/s, to report the share achieved (e.g. 156 for this
        /// project's 2-core lavapipe machine; NVIDIA H100 SXM: 67,000).
        #[arg(long)]
        peak_gflops: Option<f64>,
        /// Conv register tiles to time, as rae_core::Tile and TileChoice parse them:
        /// ROWSxBLOCKS[wCOLS][gGROUPX][kSPLIT] (rows 1, 2, 4, 8, 16; blocks 1, 2, 4 (4 with one
        /// column); columns 1, 2; workgroups 8, 16, 32, 64 wide; input blocks split 1 to 16
        /// ways), the same prefixed `lanes` (weights loaded across the subgroup, devices with
        /// subgroups of 8 or more lanes; 4 blocks also in 2 columns, two columns at most 8 rows,
        /// e.g. lanes8x2w2), winoROWSxBLOCKS[gGROUPX] (Winograd F(2x2, 3x3); rows 2, 4),
        /// winolanes4xBLOCKS[gGROUPX] (Winograd with weights across the subgroup, the same
        /// devices; blocks 1, 2, 4) or wino4lanes4xBLOCKS[gGROUPX] (Winograd F(4x4, 3x3) in 4
        /// columns, weights from a texture across the subgroup, the same devices) for one tile
        /// everywhere; `tuned` (each conv timed with every candidate on this device while
        /// building; on CPU drivers with subgroups of 8 or more lanes lanes8x2, lanes4x2,
        /// winolanes4x4 and wino4lanes4x4); `auto` (tuned-mma on GPUs; on CPU drivers
        /// wino4lanes4x4 on levels of 64x64 and more, winolanes4x4 for convs of 32+ channels
        /// below those (down to 16x16 on 16-lane subgroups, to 1x1 on 8-lane ones), lanes8x2
        /// for the others, lanes4x2 on levels of at most 8x8; 16x4 without subgroups: what
        /// `denoise` uses). `mma16`, `mma32`, `mma48`, `mma64`: the matrix-unit kernel (f16
        /// products summed in f32, 16 to 64 output channels per workgroup; tensor cores where
        /// wgpu's cooperative matrices have 16x16x16 f16 -> f32, emulated and slow elsewhere;
        /// storage weights and SHADER_F16); `mma16x3` to `mma64x3`: the same with every operand
        /// split into two f16 halves and three products (f32-class results); `tuned-mma`:
        /// `tuned` with the split tiles (f32) or the plain ones (f16) among the candidates where
        /// the device has matrix units; `tuned:T+T+...`: tuned among these tiles only (fewer
        /// pipelines to compile; with `--sources auto` it still picks each conv's source kind).
        #[arg(long, value_delimiter = ',', default_value = "auto")]
        tile: Vec<String>,
        /// Where the convs read weights: `uniform` (64 KiB chunks), `storage` (one buffer, a
        /// dispatch per conv) or `auto` (storage on GPUs; on CPU drivers storage for levels of at
        /// most 32x32 pixels, uniform above: `mixed` in the table).
        #[arg(long, value_delimiter = ',', default_value = "auto")]
        weights_memory: Vec<String>,
        /// How the convs read their input activations: `sampled` (sampled textures, read at
        /// level 0), `storage` (read-only storage textures) or `auto` (with a tuned tile, each
        /// conv the faster kind as timed; else storage on CPU drivers, where lavapipe's sampler
        /// sets up every fetch with a level, and sampled on GPUs).
        #[arg(long, value_delimiter = ',', default_value = "auto")]
        sources: Vec<String>,
        /// Build every combination first, then time them in turn, one frame each per round, for
        /// `--frames` rounds: a side-by-side table (median and fastest ms per frame, and the
        /// median of each round's ratio to the first combination) that a machine whose speed
        /// drifts over seconds (a shared host) cannot tilt towards one combination.
        #[arg(long)]
        interleave: bool,
        /// Frames with or without motion: `off`; `warp` (a smooth pan, so every recurrent block's
        /// state is reprojected: the cost of the warp); `on` (the pan, reprojected and the output
        /// accumulated along it, as `denoise` runs a sequence with motion); or several.
        #[arg(long, value_delimiter = ',', default_value = "off")]
        motion: Vec<String>,
        /// Caps in MiB on the denoiser's GPU memory, or `none`: sizes whose whole plan exceeds
        /// a cap run in tiles (the table's tiles column: columns x rows).
        #[arg(long, value_delimiter = ',', default_value = "none")]
        max_memory: Vec<String>,
    },
}

/// `--precision` values.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum PrecisionArg {
    /// rgba32float activations.
    F32,
    /// rgba16float activations (f32 arithmetic).
    F16,
}

impl From<PrecisionArg> for Precision {
    fn from(p: PrecisionArg) -> Self {
        match p {
            PrecisionArg::F32 => Precision::F32,
            PrecisionArg::F16 => Precision::F16,
        }
    }
}

/// `--tile` values.
pub fn parse_tile(s: &str) -> Result<TileChoice> {
    Ok(s.parse()?)
}

/// `--sources` values.
pub fn parse_sources(s: &str) -> Result<Option<SourceAccess>> {
    match s {
        "auto" => Ok(None),
        "sampled" => Ok(Some(SourceAccess::Sampled)),
        "storage" => Ok(Some(SourceAccess::Storage)),
        _ => bail!("sources `{s}`: sampled, storage or auto"),
    }
}

/// `--weights-memory` values.
pub fn parse_memory(s: &str) -> Result<Option<WeightMemory>> {
    match s {
        "auto" => Ok(None),
        "uniform" => Ok(Some(WeightMemory::Uniform)),
        "storage" => Ok(Some(WeightMemory::Storage)),
        _ => bail!("weights memory `{s}`: uniform, storage or auto"),
    }
}

/// `bench --max-memory` values: `none` or MiB, in bytes.
pub fn parse_cap(s: &str) -> Result<Option<u64>> {
    match s {
        "none" => Ok(None),
        _ => match s.parse::<u64>() {
            Ok(m) if m > 0 => Ok(Some(m.saturating_mul(1 << 20))),
            _ => bail!("max memory `{s}`: MiB (a positive whole number) or none"),
        },
    }
}

/// `bench --motion` values, as (reproject the hidden state, accumulate the output): `off`,
/// `warp` and `on`.
pub fn parse_motion(s: &str) -> Result<(bool, bool)> {
    match s {
        "off" => Ok((false, false)),
        "warp" => Ok((true, false)),
        "on" => Ok((true, true)),
        _ => bail!("motion `{s}`: off, warp or on"),
    }
}

impl Command {
    /// Checks every value clap leaves as text (frame ranges, tiles, weight memories, sources,
    /// motion), without reading a file or opening a device: what `main` parses again to run.
    pub fn check(&self) -> Result<()> {
        match self {
            Command::Denoise { frames, tile, .. } => {
                frames.as_deref().map(denoise::parse_range).transpose()?;
                parse_tile(tile)?;
            }
            Command::Verify { tile, .. } => {
                parse_tile(tile)?;
            }
            Command::Bench { tile, weights_memory, sources, motion, max_memory, .. } => {
                for m in max_memory {
                    parse_cap(m)?;
                }
                for t in tile {
                    parse_tile(t)?;
                }
                for m in weights_memory {
                    parse_memory(m)?;
                }
                for s in sources {
                    parse_sources(s)?;
                }
                for m in motion {
                    parse_motion(m)?;
                }
            }
            Command::Info { .. } | Command::Devices => {}
        }
        Ok(())
    }
}

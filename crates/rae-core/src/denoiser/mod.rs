//! The per-(model, width, height) runtime: every GPU resource built once, then one command
//! encoder and one submit per frame.
//!
//! # Buffers and their lifetimes
//! - **Input** (packed network input), **temporaries** and **pooled copies** live within one
//!   frame, in arenas: full-resolution texture arrays that they share by lifetime whatever
//!   their level ([`Graph::place`]). A value below full resolution takes cells of an arena's
//!   layers, a grid of images of its level's size, which the kernels address through its
//!   [`Carve`]; so the memory the first level's temporaries hold while the encoder runs deeper
//!   serves the deeper levels'. At 1080p that is the floor of any sharing by lifetime
//!   ([`Graph::least_live_bytes`]).
//! - **Hidden state**: each recurrent block owns one texture. Block `k` reads last frame's state
//!   in its recurrent conv (`d{k}.l2.0`), the only reader of the old state, and its last conv
//!   (`d{k}.l2.2`) writes the new state (its output) over it. A denoiser built for motion
//!   ([`Options::motion`]) gives each block two textures, `hidden[k][0]` and `hidden[k][1]`,
//!   that ping-pong: the warp gathers last frame's state from `hidden[k][p]` into
//!   `hidden[k][1 - p]`, which the block then writes its new state into; the next frame has
//!   parity `1 - p`. Nothing is copied. Bind groups for both parities are built up front (the
//!   pool pass's too: it reads the state written this frame); with one texture they are alike.
//! - **Pooled copies**: right after block `k` writes its state, a pool pass (or the conv itself)
//!   writes it max-pooled at the next level ([`crate::graph::Pool`]), which the next block
//!   and the decoder's skip read, until its last reader.
//! - **Reset** (first frame, scene cut) does not clear anything: for that frame the recurrent
//!   convs run with a uniform block that reads zero channels from the hidden state, which is
//!   exactly a zero hidden state (the skipped terms are the last summed), so frame 0 after
//!   `reset()` is bit-identical to frame 0 of a fresh denoiser.
//! - **Weights**: on CPU adapters, one uniform buffer of 64 KiB chunks, one per dispatch (as
//!   many of a conv's output-block groups as fit), bound by dynamic offset ([`ConvPlan`]):
//!   every invocation of a workgroup reads the same weight at once, which lavapipe broadcasts
//!   from one load. On GPUs, one read-only storage buffer and one dispatch per conv, so the
//!   deep levels' few pixels still fill the machine ([`WeightMemory`]).
//! - **Staged outputs** (CPU drivers, [`Options::staging`]): an F(4x4) conv on a level a
//!   multiple of 16 wide writes its output into the plan's one buffer ([`ConvPlan::staged`]),
//!   and the frame ends its compute pass there, copies the buffer into the conv's texture and
//!   begins the next pass. The buffer lives from that conv to its copy; the next staged conv
//!   overwrites it. On lavapipe a vec4 store into a buffer is one loop over the lanes and a
//!   texel store of rgba32float four, and the copy is a memcpy: the 256x256 frame in 0.92-0.95x
//!   the time, for one buffer the size of the largest staged output (8 MiB there). Where the
//!   device has 64-bit integers the staged stores pack two floats to a word, half the loops
//!   ([`crate::kernels::wide_staged_stores`]).
//! - **Tiles**: on GPUs each conv's register tile, and whether it reads its sources as sampled
//!   or storage textures, is chosen while building, by timing the candidates on the device
//!   ([`TileChoice::Tuned`], [`Options::sources`]); the candidates' plans are dropped after.
//!
//! Frames are `width x height`; the network runs at the size padded to a multiple of
//! `2^levels` (the prep kernel replicates edge pixels into the padding) and the output kernel
//! crops back.

mod accumulate;
mod build;
mod host;
mod motion;
mod record;
mod tiles;
mod tuning;

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use crate::error::{Error, Result};
use crate::frame::{FrameInputs, FrameTimings};
use crate::graph::{Graph, Place, Placement, Read, Source, Value};
use crate::kernels::{
    Carve, ConvPlan, ConvSpec, Guide, Kernels, MMA_WORKGROUP_BYTES, Method, MotionKernels, MotionParams, OutputParams, Precision,
    PrepLayout, PrepParams, SourceAccess, Tile, TileList, WORKGROUP, WeightMemory, blocks, per_conv,
};
use crate::model::{Arch, InputBuffer, Transfer};
use crate::weights::Weights;

pub use accumulate::accumulate_bytes;
use accumulate::{AccumulateIo, Accumulation};
pub use build::*;
pub use host::*;
use motion::Motion;
pub use motion::motion_bytes;
pub use record::*;
pub use tiles::{FrameTiles, MemoryPlan, Span, TILE_OVERLAP, TilePlan};
use tiles::{Network, TileAt, Tiles};
pub use tuning::*;

/// How a [`Denoiser`] stores activations, reads weights and tiles its convolutions.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Options {
    /// Storage precision of activations and hidden state.
    pub precision: Precision,
    /// Register tile of the conv kernel.
    pub tiles: TileChoice,
    /// Where the convs read weights; `None`: each conv by adapter type and level
    /// ([`WeightMemory::for_conv`], also while tuning times it), or storage for an Mma tile
    /// ([`Tile::mma`], [`Tile::mma_split`]). The lanes module's tiles (two-column lanes,
    /// Winograd lanes) read the weight texture and take storage whatever this says
    /// ([`crate::kernels::TEXEL_WEIGHTS`]).
    pub weights: Option<WeightMemory>,
    /// How the convs read their sources. `None`: where tiles are tuned, each conv the faster
    /// of both kinds as timed with its tile (on the H100 storage-texture sources took 0.88x the
    /// time of sampled ones in one direct conv and were slower in the matrix-unit tiles,
    /// `docs/perf/h100-2026-11-24-s15.log`); elsewhere by adapter type and limits ([`SourceAccess::for_device`]).
    pub sources: Option<SourceAccess>,
    /// Whether the F(4x4) convs write their outputs into a buffer that the frame copies into
    /// their textures ([`Kernels::stage_outputs`]). `None`: on CPU drivers, where a buffer store
    /// costs less than a texel store (lavapipe: the 256x256 frame in 0.92-0.95x the time,
    /// `docs/perf/lavapipe-2026-12-02-s28.log`).
    pub staging: Option<bool>,
    /// Whether frames may carry motion ([`FrameInputs::motion`], [`GpuFrameIo::motion`]) to
    /// reproject the hidden state with (a pyramid of motion textures, 16 bytes a pixel at full
    /// resolution and a third more below; [`Denoiser::gpu_bytes`] counts it). A frame without
    /// motion runs as without this.
    pub motion: bool,
    /// Whether frames with motion blend their output with the previous frame's accumulated
    /// output along the motion ([`crate::accumulate`], shaders/accumulate.wgsl; three RGB f32
    /// frames more, [`Denoiser::gpu_bytes`] counts them). Only with [`Self::motion`]: frames
    /// carry motion only then.
    pub accumulate: bool,
    /// A cap on the bytes the denoiser holds ([`Denoiser::gpu_bytes`], the host path's
    /// transfer buffers included). A frame whose whole plan exceeds it runs in tiles, the
    /// largest that fit ([`MemoryPlan`]); a cap below the smallest tiles' cost is
    /// [`Error::MemoryCap`]. `None`: frames run whole unless they exceed the device's limits.
    pub max_memory: Option<u64>,
    /// Tiles fixed by the caller, whatever the cap (tests, benchmarks, measurements).
    pub frame_tiles: Option<FrameTiles>,
}

/// Runs one model at one frame size, frame after frame, keeping the hidden state on the GPU.
pub struct Denoiser {
    id: u64,
    device: wgpu::Device,
    queue: wgpu::Queue,
    arch: Arch,
    graph: Graph,
    width: u32,
    height: u32,
    pwidth: u32,
    pheight: u32,
    kernels: Kernels,
    /// prep.wgsl specialised to this model's input layout.
    prep: wgpu::ComputePipeline,
    convs: ConvPlan,
    /// `[parity][node]`.
    conv_groups: [Vec<wgpu::BindGroup>; 2],
    /// `[parity][pool]` (a pool reads the state written this frame, whose texture alternates).
    pool_groups: [Vec<wgpu::BindGroup>; 2],
    /// `[parity][node]`: the texture a conv writes and where each output block starts there
    /// (its cell, for a temporary), for the copy of a staged output ([`ConvPlan::staged`]).
    conv_outputs: [Vec<(wgpu::Texture, Vec<wgpu::Origin3d>)>; 2],
    prep_params: wgpu::Buffer,
    output_params: wgpu::Buffer,
    /// The packed input's view, which prep writes and the history test reads.
    input_view: wgpu::TextureView,
    /// The arena holding the packed input, and the input's place there ([`Self::read_input`]).
    input_at: (wgpu::Texture, Place),
    output_view: wgpu::TextureView,
    dummy: wgpu::Buffer,
    /// Per-frame statistics prep writes and output reads (the frame's largest prepared color);
    /// cleared at the start of every frame.
    stats: wgpu::Buffer,
    textures: Vec<wgpu::Texture>,
    /// `[block][0|1]`, as in the module docs (the same texture twice without motion).
    hidden_textures: Vec<[wgpu::Texture; 2]>,
    precision: Precision,
    bytes: u64,
    host: Option<HostIo>,
    profiler: Option<Profiler>,
    /// The reprojection's resources ([`Options::motion`]).
    motion: Option<Motion>,
    /// The frame's tiles and the state kept between them, where the frame runs in tiles.
    tiles: Option<Tiles>,
    /// Each conv's tuning finalists, fastest first (empty where not tuned).
    tuning: Vec<Vec<Finalist>>,
    parity: usize,
    reset_pending: bool,
    /// The output's temporal accumulation ([`Options::accumulate`]).
    accumulation: Option<Accumulation>,
}

impl Denoiser {
    /// Build everything for `weights` at `width` x `height` on a device, with f32 activations:
    /// pipelines, textures, weights, uniforms and the bind groups of both hidden-state parities.
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, weights: &Weights, width: u32, height: u32) -> Result<Self> {
        Self::with_precision(device, queue, weights, width, height, Precision::F32)
    }

    /// [`Self::new`] with activations and hidden state stored in `precision`.
    pub fn with_precision(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        weights: &Weights,
        width: u32,
        height: u32,
        precision: Precision,
    ) -> Result<Self> {
        Self::with_options(device, queue, weights, width, height, Options { precision, ..Default::default() })
    }

    /// The architecture being run.
    pub fn arch(&self) -> &Arch {
        &self.arch
    }

    /// The dataflow being run.
    pub fn graph(&self) -> &Graph {
        &self.graph
    }

    /// Frame size.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Size the network runs at (padded to a multiple of `2^levels`).
    pub fn padded_size(&self) -> (u32, u32) {
        (self.pwidth, self.pheight)
    }

    /// Bytes of GPU memory held for activations, hidden state, weights and uniforms, plus the
    /// host-slice path's I/O buffers once [`Self::denoise_into`] has made them. Frames allocate
    /// nothing, so this is also the peak.
    pub fn gpu_bytes(&self) -> u64 {
        self.bytes + self.host.as_ref().map_or(0, HostIo::bytes)
    }

    /// Forget the hidden state: the next frame is denoised as the first of a sequence.
    pub fn reset(&mut self) {
        self.reset_pending = true;
    }

    /// Storage precision of activations and hidden state.
    pub fn precision(&self) -> Precision {
        self.precision
    }

    /// The tile each conv runs with, in [`Graph::nodes`] order.
    pub fn conv_tiles(&self) -> &[Tile] {
        self.convs.tiles()
    }

    /// Where the convs read their weights, where every conv reads them alike (`None`: mixed,
    /// [`Self::weight_memories`]).
    pub fn weight_memory(&self) -> Option<WeightMemory> {
        match self.weight_memories() {
            [first, rest @ ..] if rest.iter().all(|m| m == first) => Some(*first),
            _ => None,
        }
    }

    /// Where the convs read their weights, for tables: the kind's name where all read alike,
    /// else `mixed`.
    pub fn weights_name(&self) -> &'static str {
        self.weight_memory().map_or("mixed", WeightMemory::name)
    }

    /// Whether each conv writes its output into the buffer the frame copies from
    /// ([`Options::staging`]).
    pub fn staged_convs(&self) -> Vec<bool> {
        (0..self.graph.nodes.len()).map(|i| self.convs.staged(i)).collect()
    }

    /// Where each conv reads its weights, in [`Graph::nodes`] order: the weight buffer binding
    /// its pipeline takes. The lanes module's tiles (two-column lanes, Winograd lanes) read the
    /// plan's weight texture and take [`WeightMemory::Storage`] ([`crate::kernels::TEXEL_WEIGHTS`]).
    pub fn weight_memories(&self) -> &[WeightMemory] {
        self.convs.memories()
    }

    /// Each conv's tuning finalists in [`Graph::nodes`] order, fastest (the one it runs) first:
    /// how close the runners-up came. Empty where the tiles were not tuned; without a choice
    /// to make (one candidate, one kind) each conv's one entry has no time (NaN).
    pub fn tuning(&self) -> &[Vec<Finalist>] {
        &self.tuning
    }

    /// How each conv reads its sources, in [`Graph::nodes`] order.
    pub fn conv_sources(&self) -> &[SourceAccess] {
        self.convs.sources()
    }

    /// How the convs read their sources, for tables: the kind's name where all read alike,
    /// else `mixed`.
    pub fn sources_name(&self) -> &'static str {
        match self.conv_sources() {
            [first, rest @ ..] if rest.iter().all(|s| s == first) => first.name(),
            _ => "mixed",
        }
    }

    /// The frame's tiles, where it runs in tiles ([`Options::max_memory`]).
    pub fn tile_plan(&self) -> Option<&TilePlan> {
        self.tiles.as_ref().map(|t| &t.plan)
    }

    /// Whether a tiled denoiser keeps the frame's hidden state in host memory (where the cap
    /// leaves no room for it on the GPU; [`MemoryPlan::host_state`]).
    pub fn state_on_host(&self) -> bool {
        self.tiles.as_ref().is_some_and(Tiles::state_on_host)
    }

    /// Textures held (for memory reports and tests).
    pub fn texture_count(&self) -> usize {
        self.textures.len()
    }
}

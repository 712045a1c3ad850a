//! The per-(model, width, height) runtime: every GPU resource built once, then one command
//! encoder and one submit per frame.
//!
//! # Buffers and their lifetimes
//! - **Input** (packed network input) and **temporaries** live for one frame. Temporaries are
//!   texture arrays shared by lifetime ([`Graph::allocate_temps`]): two values whose live
//!   ranges do not overlap at a resolution use the same texture.
//! - **Hidden state**: each recurrent block owns two textures, `hidden[k][0]` and
//!   `hidden[k][1]`, and they ping-pong. On a frame of parity `p`, block `k` reads last frame's
//!   state from `hidden[k][p]` and writes the new one (its output) into `hidden[k][1 - p]`; the
//!   next frame has parity `1 - p`. Nothing is copied. Bind groups for both parities are built
//!   up front (the pool pass's too: it reads the state written this frame).
//! - **Pooled copies**: right after block `k` writes its state, a pool pass writes it max-pooled
//!   into a texture of its own at the next level ([`crate::graph::Pool`]), which the next block
//!   and the decoder's skip read; it lives for the rest of the frame.
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

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use crate::error::{Error, Result};
use crate::frame::{FrameInputs, FrameTimings};
use crate::graph::{Graph, Read, Value};
use crate::kernels::{
    ConvPlan, ConvSpec, Kernels, MMA_WORKGROUP_BYTES, Method, OutputParams, Precision, PrepLayout, PrepParams, SourceAccess, Tile,
    WORKGROUP, WeightMemory, blocks, per_conv,
};
use crate::model::{Arch, InputBuffer, Transfer};
use crate::weights::Weights;

static NEXT_ID: AtomicU64 = AtomicU64::new(1);

/// The caller's GPU buffers for one frame (tightly packed f32, same layout as [`FrameInputs`]);
/// each needs `STORAGE` usage. `output` receives RGB radiance at the frame size.
#[derive(Debug, Clone, Copy)]
pub struct GpuFrameIo<'a> {
    /// Noisy radiance, RGB.
    pub color: &'a wgpu::Buffer,
    /// Albedo, RGB.
    pub albedo: Option<&'a wgpu::Buffer>,
    /// Normal, xyz.
    pub normal: Option<&'a wgpu::Buffer>,
    /// Depth.
    pub depth: Option<&'a wgpu::Buffer>,
    /// Roughness.
    pub roughness: Option<&'a wgpu::Buffer>,
    /// Denoised radiance, RGB (written).
    pub output: &'a wgpu::Buffer,
}

impl GpuFrameIo<'_> {
    fn get(&self, b: InputBuffer) -> Option<&wgpu::Buffer> {
        match b {
            InputBuffer::Color => Some(self.color),
            InputBuffer::Albedo => self.albedo,
            InputBuffer::Normal => self.normal,
            InputBuffer::Depth => self.depth,
            InputBuffer::Roughness => self.roughness,
        }
    }
}

/// Bind groups that connect a set of caller buffers to one [`Denoiser`]; make it once per set
/// of buffers with [`Denoiser::bind_io`] and reuse it every frame.
pub struct IoBinding {
    owner: u64,
    prep: wgpu::BindGroup,
    output: wgpu::BindGroup,
}

/// Buffers of the host-slice path, made on its first use and kept: a frame creates no buffer.
///
/// `upload` is a persistent staging buffer (MAP_WRITE) holding every input back to back. It is
/// mapped between frames: a frame writes the host slices into it, unmaps it, and the frame's
/// encoder copies it into the input buffers; after the submit it is mapped again in the same
/// poll that maps `readback`. (`queue.write_buffer` would stage through a fresh allocation in
/// wgpu on every frame.)
struct HostIo {
    inputs: Vec<(InputBuffer, wgpu::Buffer)>,
    /// Offset of each input in `upload`, in the order of `inputs`.
    offsets: Vec<u64>,
    upload: wgpu::Buffer,
    /// Whether `upload` is mapped now (wgpu has no query for it).
    upload_mapped: std::sync::atomic::AtomicBool,
    output: wgpu::Buffer,
    readback: wgpu::Buffer,
    binding: IoBinding,
}

impl HostIo {
    fn bytes(&self) -> u64 {
        self.inputs.iter().map(|(_, b)| b.size()).sum::<u64>() + self.upload.size() + self.output.size() + self.readback.size()
    }
}

/// Timestamp queries and their buffers for [`Denoiser::denoise_profiled`], made on first use.
struct Profiler {
    queries: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    readback: wgpu::Buffer,
    count: u32,
}

/// How a [`Denoiser`] picks the conv kernel's register tile.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum TileChoice {
    /// [`TileChoice::TunedMma`] on GPUs that have timestamps inside passes (that is
    /// [`TileChoice::Tuned`] where the device has no matrix units), [`Tile::cpu_for`] each
    /// conv's level on CPU drivers (lavapipe compiles each variant for seconds, and its tiles
    /// are known: Winograd F(4x4) and F(2x2) in 4 rows with weights across the subgroup, direct
    /// 8 x 2 in two columns for the convs of fewer than 32 channels below 32 x 32, 4 rows on
    /// the smallest levels), the default tile elsewhere.
    #[default]
    Auto,
    /// One tile for every conv (smaller where a level or a conv is smaller).
    Fixed(Tile),
    /// Time every conv with each of [`TUNE_TILES`] on this device while building
    /// ([`TUNE_TILES_LANES_WINOGRAD`] on CPU drivers with subgroups), and keep the fastest per conv: big
    /// levels want tall tiles (fewer weight loads), deep levels want small ones (enough
    /// invocations to fill the GPU).
    Tuned,
    /// [`TileChoice::Tuned`] among these candidates only (fewer pipelines to compile).
    TunedAmong(&'static [Tile]),
    /// [`TileChoice::Tuned`] with matrix-unit tiles among the candidates where the device has
    /// matrix units ([`crate::kernels::matrix_units_supported`]) and the weights are in a
    /// storage buffer, those that keep the precision's accuracy: with f32 activations the split
    /// tiles [`MMA_SPLIT_TILES`] (f32-class results, [`Tile::mma_split`]), with f16 ones
    /// [`MMA_TILES`] (f16 products summed in f32, [`Tile::mma`]). What [`TileChoice::Auto`]
    /// does on GPUs (session 15: on the H100 the split tiles pass the goldens, and f32 frames
    /// take 0.89x the time of [`TileChoice::Tuned`]'s, docs/PERF.md). The TF32-like plain tiles
    /// with f32 activations are fixed tiles only (`Fixed(Tile::mma(32))`).
    TunedMma,
    /// [`TileChoice::TunedMma`] with these tiles among the candidates as well, wherever it
    /// tunes: for timing kernels that are not yet candidates (e.g. [`Tile::mma_split_prefetch`])
    /// beside those that are.
    TunedMmaWith(&'static [Tile]),
}

/// The matrix-unit tiles [`TileChoice::TunedMma`] adds to [`TUNE_TILES`] with f16 activations:
/// 16 to 64 output channels per workgroup.
pub const MMA_TILES: [Tile; 4] = [
    Tile { rows: 4, blocks: 4, cols: 1, group_x: 8, method: Method::Mma, split: 1 },
    Tile { rows: 4, blocks: 8, cols: 1, group_x: 8, method: Method::Mma, split: 1 },
    Tile { rows: 4, blocks: 12, cols: 1, group_x: 8, method: Method::Mma, split: 1 },
    Tile { rows: 4, blocks: 16, cols: 1, group_x: 8, method: Method::Mma, split: 1 },
];

/// The split matrix-unit tiles [`TileChoice::TunedMma`] adds to [`TUNE_TILES`] with f32
/// activations: 16 to 64 output channels per workgroup ([`Tile::mma_split`]).
pub const MMA_SPLIT_TILES: [Tile; 4] = [
    Tile { rows: 4, blocks: 4, cols: 1, group_x: 8, method: Method::MmaSplit, split: 1 },
    Tile { rows: 4, blocks: 8, cols: 1, group_x: 8, method: Method::MmaSplit, split: 1 },
    Tile { rows: 4, blocks: 12, cols: 1, group_x: 8, method: Method::MmaSplit, split: 1 },
    Tile { rows: 4, blocks: 16, cols: 1, group_x: 8, method: Method::MmaSplit, split: 1 },
];

/// The tiles [`TileChoice::Tuned`] times on CPU drivers with subgroups (lavapipe), where the
/// direct tiles of [`TUNE_TILES`] gave 1.9x the frame time of [`Tile::CPU_LANES`]. Tuning
/// among six lanes tiles (8, 4 and 2 rows x 2 blocks in two columns; 8 x 4, 4 x 4 and 16 x 2 in
/// one) at 256x256 kept only these two (docs/PERF.md, session 21).
pub const TUNE_TILES_LANES: [Tile; 2] = [Tile::CPU_LANES, Tile { rows: 4, ..Tile::CPU_LANES }];

/// [`TUNE_TILES_LANES`] and the CPU drivers' Winograd tiles of 4 and 8 rows
/// ([`Tile::CPU_WINOGRAD`], [`Tile::CPU_WINOGRAD_TALL`], [`Tile::CPU_WINOGRAD4`],
/// [`Tile::CPU_WINOGRAD4_TALL`]): what [`TileChoice::Tuned`] times on CPU drivers with subgroups
/// of 8 lanes or more ([`crate::kernels::winograd_lanes_supported`]); every tile
/// [`Tile::cpu_for`] gives there is among them.
pub const TUNE_TILES_LANES_WINOGRAD: [Tile; 6] = [
    Tile::CPU_LANES,
    Tile { rows: 4, ..Tile::CPU_LANES },
    Tile::CPU_WINOGRAD,
    Tile::CPU_WINOGRAD_TALL,
    Tile::CPU_WINOGRAD4,
    Tile::CPU_WINOGRAD4_TALL,
];

/// The tiles [`TileChoice::Tuned`] times on GPUs (and CPU drivers without subgroups).
pub const TUNE_TILES: [Tile; 33] = [
    Tile { rows: 16, blocks: 2, cols: 1, group_x: 8, method: Method::Direct, split: 1 },
    Tile { rows: 8, blocks: 2, cols: 1, group_x: 8, method: Method::Direct, split: 1 },
    Tile { rows: 4, blocks: 2, cols: 1, group_x: 8, method: Method::Direct, split: 1 },
    Tile { rows: 2, blocks: 2, cols: 1, group_x: 8, method: Method::Direct, split: 1 },
    Tile { rows: 1, blocks: 2, cols: 1, group_x: 8, method: Method::Direct, split: 1 },
    Tile { rows: 8, blocks: 1, cols: 1, group_x: 8, method: Method::Direct, split: 1 },
    Tile { rows: 4, blocks: 1, cols: 1, group_x: 8, method: Method::Direct, split: 1 },
    Tile { rows: 1, blocks: 1, cols: 1, group_x: 8, method: Method::Direct, split: 1 },
    Tile { rows: 16, blocks: 1, cols: 2, group_x: 8, method: Method::Direct, split: 1 },
    Tile { rows: 8, blocks: 2, cols: 2, group_x: 8, method: Method::Direct, split: 1 },
    Tile { rows: 8, blocks: 1, cols: 2, group_x: 8, method: Method::Direct, split: 1 },
    Tile { rows: 4, blocks: 2, cols: 2, group_x: 8, method: Method::Direct, split: 1 },
    Tile { rows: 4, blocks: 1, cols: 2, group_x: 8, method: Method::Direct, split: 1 },
    Tile { rows: 16, blocks: 2, cols: 1, group_x: 32, method: Method::Direct, split: 1 },
    Tile { rows: 8, blocks: 1, cols: 1, group_x: 32, method: Method::Direct, split: 1 },
    Tile { rows: 8, blocks: 1, cols: 2, group_x: 16, method: Method::Direct, split: 1 },
    Tile { rows: 4, blocks: 2, cols: 2, group_x: 16, method: Method::Direct, split: 1 },
    Tile { rows: 4, blocks: 1, cols: 1, group_x: 16, method: Method::Direct, split: 1 },
    Tile { rows: 8, blocks: 1, cols: 1, group_x: 16, method: Method::Direct, split: 1 },
    Tile { rows: 8, blocks: 1, cols: 2, group_x: 32, method: Method::Direct, split: 1 },
    Tile { rows: 8, blocks: 1, cols: 1, group_x: 64, method: Method::Direct, split: 1 },
    Tile { rows: 16, blocks: 2, cols: 1, group_x: 64, method: Method::Direct, split: 1 },
    Tile { rows: 4, blocks: 4, cols: 1, group_x: 32, method: Method::Direct, split: 1 },
    Tile { rows: 8, blocks: 4, cols: 1, group_x: 32, method: Method::Direct, split: 1 },
    Tile { rows: 2, blocks: 1, cols: 2, group_x: 8, method: Method::Winograd, split: 1 },
    Tile { rows: 2, blocks: 1, cols: 2, group_x: 32, method: Method::Winograd, split: 1 },
    Tile { rows: 2, blocks: 2, cols: 2, group_x: 32, method: Method::Winograd, split: 1 },
    Tile { rows: 4, blocks: 1, cols: 2, group_x: 32, method: Method::Winograd, split: 1 },
    Tile { rows: 4, blocks: 1, cols: 1, group_x: 8, method: Method::Direct, split: 4 },
    Tile { rows: 4, blocks: 1, cols: 1, group_x: 8, method: Method::Direct, split: 8 },
    Tile { rows: 2, blocks: 1, cols: 1, group_x: 8, method: Method::Direct, split: 8 },
    Tile { rows: 8, blocks: 1, cols: 1, group_x: 32, method: Method::Direct, split: 4 },
    Tile { rows: 4, blocks: 2, cols: 1, group_x: 16, method: Method::Direct, split: 8 },
];

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
    /// docs/PERF.md session 15); elsewhere by adapter type ([`SourceAccess::for_device_type`]).
    pub sources: Option<SourceAccess>,
    /// Whether the F(4x4) convs write their outputs into a buffer that the frame copies into
    /// their textures ([`Kernels::stage_outputs`]). `None`: on CPU drivers, where a buffer store
    /// costs less than a texel store (lavapipe: the 256x256 frame in 0.92-0.95x the time,
    /// docs/PERF.md session 28).
    pub staging: Option<bool>,
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
    /// `[parity][node]`: the texture a conv writes, for the copy of a staged output
    /// ([`ConvPlan::staged`]).
    conv_outputs: [Vec<wgpu::Texture>; 2],
    prep_params: wgpu::Buffer,
    output_params: wgpu::Buffer,
    input_texture: wgpu::Texture,
    output_view: wgpu::TextureView,
    dummy: wgpu::Buffer,
    /// Per-frame statistics prep writes and output reads (the frame's largest prepared color);
    /// cleared at the start of every frame.
    stats: wgpu::Buffer,
    textures: Vec<wgpu::Texture>,
    /// `[block][0|1]`, as in the module docs.
    hidden_textures: Vec<[wgpu::Texture; 2]>,
    precision: Precision,
    bytes: u64,
    host: Option<HostIo>,
    profiler: Option<Profiler>,
    /// Each conv's tuning finalists, fastest first (empty where not tuned).
    tuning: Vec<Vec<Finalist>>,
    parity: usize,
    reset_pending: bool,
}

fn texture(
    device: &wgpu::Device,
    label: &str,
    w: u32,
    h: u32,
    layers: u32,
    format: wgpu::TextureFormat,
) -> (wgpu::Texture, wgpu::TextureView) {
    let t = device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: layers },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::STORAGE_BINDING
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let v = t.create_view(&wgpu::TextureViewDescriptor { dimension: Some(wgpu::TextureViewDimension::D2Array), ..Default::default() });
    (t, v)
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

    /// [`Self::new`] with every choice spelled out: storage precision and the conv tile.
    pub fn with_options(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        weights: &Weights,
        width: u32,
        height: u32,
        options: Options,
    ) -> Result<Self> {
        let Options { precision, tiles, weights: chosen_memory, sources, staging } = options;
        let device_type = device.adapter_info().device_type;
        // Mma tiles read storage weights: a fixed one picks them where the caller left it open.
        let fixed_mma = matches!(tiles, TileChoice::Fixed(t) if t.method.is_mma());
        let memory = chosen_memory.unwrap_or(if fixed_mma { WeightMemory::Storage } else { WeightMemory::for_device_type(device_type) });
        let default_sources = sources.unwrap_or(SourceAccess::for_device_type(device_type));
        let arch = weights.arch.clone();
        let multiple = 1u32 << arch.levels();
        let limits = device.limits();
        let size_err = |reason: String| Error::FrameSize { width, height, reason };
        if width == 0 || height == 0 {
            return Err(size_err("empty frame".into()));
        }
        let (pwidth, pheight) = (width.next_multiple_of(multiple), height.next_multiple_of(multiple));
        if pwidth > limits.max_texture_dimension_2d || pheight > limits.max_texture_dimension_2d {
            return Err(size_err(format!("exceeds the device's texture limit {}", limits.max_texture_dimension_2d)));
        }
        let graph = Graph::new(&arch);
        let mut kernels = Kernels::with_sources(device, precision, memory, default_sources);
        // The padded levels halve exactly, so the convs may read their zero padding from
        // outside the textures where the device reads zero there (before tuning makes any).
        kernels.pad_from_bounds();
        let format = precision.format();
        let mut textures = Vec::new();
        let mut bytes = 0u64;
        let mut make = |label: &str, level: usize, channels: usize| {
            let (w, h, l) = (pwidth >> level, pheight >> level, blocks(channels));
            bytes += w as u64 * h as u64 * l as u64 * precision.texel_bytes();
            let (t, v) = texture(device, label, w, h, l, format);
            textures.push(t.clone());
            (t, v)
        };

        // Activations: input, hidden pairs, temporaries by lifetime.
        let (input_texture, input_view) = make("input", 0, graph.in_channels);
        let hidden_pairs: Vec<[(wgpu::Texture, wgpu::TextureView); 2]> =
            graph.hidden.iter().map(|&(c, level)| [make("hidden", level, c), make("hidden", level, c)]).collect();
        let hidden: Vec<[wgpu::TextureView; 2]> = hidden_pairs.iter().map(|[a, b]| [a.1.clone(), b.1.clone()]).collect();
        let hidden_textures: Vec<[wgpu::Texture; 2]> = hidden_pairs.iter().map(|[a, b]| [a.0.clone(), b.0.clone()]).collect();
        let (assign, slots) = graph.allocate_temps();
        let slot_textures: Vec<(wgpu::Texture, wgpu::TextureView)> = slots.iter().map(|&(level, c)| make("temp", level, c)).collect();
        let slot_views: Vec<wgpu::TextureView> = slot_textures.iter().map(|(_, v)| v.clone()).collect();
        let pooled_views: Vec<wgpu::TextureView> = graph.pools.iter().map(|p| make("pooled", p.level, p.channels).1).collect();
        let view = |v: Value, parity: usize| -> &wgpu::TextureView {
            match v {
                Value::Input => &input_view,
                Value::HiddenPrev(k) => &hidden[k][parity],
                Value::HiddenNew(k) => &hidden[k][1 - parity],
                Value::Temp(t) => &slot_views[assign[t]],
                Value::Pooled(k) => &pooled_views[k],
            }
        };
        // The texture of a value a conv writes.
        let written = |v: Value, parity: usize| -> wgpu::Texture {
            match v {
                Value::HiddenNew(k) => hidden_textures[k][1 - parity].clone(),
                Value::Temp(t) => slot_textures[assign[t]].0.clone(),
                _ => unreachable!("a conv writes a temporary or a new hidden state"),
            }
        };
        let conv_outputs: [Vec<wgpu::Texture>; 2] =
            std::array::from_fn(|parity| graph.nodes.iter().map(|n| written(n.out, parity)).collect());
        let Value::Temp(out_temp) = graph.output else { unreachable!("the output is a temporary") };
        let output_view = slot_views[assign[out_temp]].clone();

        // Weights and parameters of every conv, in uniform chunks (see kernels::ConvPlan).
        let tensors: Vec<_> = graph
            .nodes
            .iter()
            .map(|n| {
                let w = weights.get(&format!("{}.weight", n.name)).expect("validated at load");
                let b = weights.get(&format!("{}.bias", n.name)).expect("validated at load");
                (w, b)
            })
            .collect();
        // The pooled value node i's output is max-pooled into, if any.
        let pooled_by = |i: usize| graph.pools.iter().position(|p| p.after == i).map(|k| &pooled_views[k]);
        let specs: Vec<ConvSpec> = graph
            .nodes
            .iter()
            .zip(&tensors)
            .enumerate()
            .map(|(i, (n, (w, b)))| ConvSpec {
                name: &n.name,
                width: pwidth >> n.level,
                height: pheight >> n.level,
                ca: n.a.channels,
                cb: n.b.map_or(0, |b| b.channels),
                cout: n.cout,
                weight: &w.data,
                bias: &b.data,
                read_a: n.a.read,
                read_b: n.b.map_or(Read::Direct, |b| b.read),
                leaky: n.leaky,
                slope: arch.negative_slope,
                b_is_hidden: n.b.is_some_and(|b| matches!(b.value, Value::HiddenPrev(_))),
                pooled: pooled_by(i).is_some(),
            })
            .collect();
        // Sources, destination and pooled value of every conv at parity 0 (for tuning).
        let node_views: Vec<NodeViews> = graph
            .nodes
            .iter()
            .enumerate()
            .map(|(i, n)| NodeViews {
                a: view(n.a.value, 0).clone(),
                b: view(n.b.map_or(n.a.value, |b| b.value), 0).clone(),
                out: view(n.out, 0).clone(),
                pooled: pooled_by(i).cloned(),
            })
            .collect();
        let timestamps = device.features().contains(wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES);
        // Tuning times both source kinds unless the caller fixed one.
        let both = [default_sources, if default_sources == SourceAccess::Sampled { SourceAccess::Storage } else { SourceAccess::Sampled }];
        let accesses = if sources.is_some() { &both[..1] } else { &both[..] };
        // A conv's weight memory under a tile: the caller's or a fixed Mma tile's choice, else
        // storage for an Mma tile and by level otherwise. Tuning times each candidate with it,
        // so that it times what the plan it picks will run.
        let memory_of = |tile: Tile, spec: &ConvSpec| -> WeightMemory {
            if chosen_memory.is_some() || fixed_mma {
                memory
            } else if tile.method.is_mma() {
                // Mma tiles read only storage weights.
                WeightMemory::Storage
            } else {
                // (The lanes module's tiles read the plan's weight texture, and the plan gives
                // them storage, which needs no 64 KiB chunk beside it: kernels::TEXEL_WEIGHTS.)
                WeightMemory::for_conv(device_type, spec.width, spec.height)
            }
        };
        let tune_among = |kernels: &mut Kernels, candidates: &[Tile]| {
            tune(device, queue, kernels, &specs, &node_views, candidates, accesses, &memory_of)
        };
        // One tile and kind for every conv, or each conv's fastest tuning finalist.
        let fixed = |t: Tile| (vec![t], vec![default_sources], Vec::new());
        let picks = |finalists: Vec<Vec<Finalist>>| {
            let (tiles, sources) = finalists.iter().map(|f| (f[0].tile, f[0].sources)).unzip();
            (tiles, sources, finalists)
        };
        // Matrix-unit tiles join tuning where they run in hardware, with their weights in a
        // storage buffer and room for their workgroup memory.
        let mma = kernels.matrix_units()
            && memory == WeightMemory::Storage
            && device.limits().max_compute_workgroup_storage_size >= MMA_WORKGROUP_BYTES;
        // CPU drivers with subgroups of 8 lanes or more tune among the lanes tiles, Winograd's
        // among them (they run wherever the direct lanes tiles do): the direct ones take about
        // twice as long there.
        let lanes = device_type == wgpu::DeviceType::Cpu && Tile::cpu(device) == Tile::CPU_LANES;
        let base: &[Tile] = if lanes { &TUNE_TILES_LANES_WINOGRAD } else { &TUNE_TILES };
        let candidates = tuning_candidates(tiles, precision, mma, base);
        let (tiles, conv_sources, tuning): (Vec<Tile>, Vec<SourceAccess>, Vec<Vec<Finalist>>) = match tiles {
            TileChoice::Fixed(t) => fixed(t),
            // The CPU tile by level (shorter on the smallest).
            TileChoice::Auto if device_type == wgpu::DeviceType::Cpu => {
                let tiles = specs.iter().map(|s| Tile::cpu_for(device, s.width, s.height, blocks(s.ca) + blocks(s.cb))).collect();
                (tiles, vec![default_sources], Vec::new())
            }
            _ if timestamps && !candidates.is_empty() => picks(tune_among(&mut kernels, &candidates)?),
            _ => fixed(Tile::default()),
        };
        let memories: Vec<WeightMemory> = specs.iter().enumerate().map(|(i, s)| memory_of(per_conv(&tiles, i), s)).collect();
        // On CPU drivers the F(4x4) convs write their outputs into a buffer that the frame copies
        // into their textures (Kernels::stage_outputs; record_with records the copies). Tuning,
        // above, timed the convs unstaged: a copy costs every candidate the same.
        if staging.unwrap_or(device_type == wgpu::DeviceType::Cpu) {
            kernels.stage_outputs();
        }
        let convs = ConvPlan::with_choices(device, queue, &mut kernels, &specs, &tiles, &conv_sources, &memories)?;
        debug_assert_eq!(bytes, activation_bytes(&graph, pwidth, pheight, precision));
        bytes += convs.bytes();
        // Bind groups of both parities (the reset variant only changes the dynamic offset).
        let conv_groups: [Vec<wgpu::BindGroup>; 2] = std::array::from_fn(|parity| {
            graph
                .nodes
                .iter()
                .enumerate()
                .map(|(i, node)| {
                    // A one-source conv binds its source a as b too (never read: its cin4_b is 0).
                    let src_b = view(node.b.map_or(node.a.value, |b| b.value), parity);
                    convs.bind_group(device, &kernels, i, view(node.a.value, parity), src_b, view(node.out, parity), pooled_by(i))
                })
                .collect()
        });

        let pool_groups: [Vec<wgpu::BindGroup>; 2] = std::array::from_fn(|parity| {
            graph
                .pools
                .iter()
                .enumerate()
                .map(|(i, p)| {
                    device.create_bind_group(&wgpu::BindGroupDescriptor {
                        label: Some("pool"),
                        layout: &kernels.pool_layout,
                        entries: &[
                            wgpu::BindGroupEntry {
                                binding: 0,
                                resource: wgpu::BindingResource::TextureView(view(Value::HiddenNew(p.hidden), parity)),
                            },
                            wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(&pooled_views[i]) },
                        ],
                    })
                })
                .collect()
        });

        // Prep and output uniforms.
        let mut offsets = [None; 5];
        let mut ch = 0u32;
        for b in &arch.inputs {
            offsets[InputBuffer::ALL.iter().position(|x| x == b).expect("known buffer")] = Some(ch);
            ch += b.channels() as u32;
        }
        let transfer = match arch.transfer {
            Transfer::None => 0,
            Transfer::Log1p => 1,
        };
        let prep_layout = PrepLayout {
            offsets,
            layers: blocks(graph.in_channels),
            demodulate: arch.demodulate,
            log1p: matches!(arch.transfer, Transfer::Log1p),
            albedo_eps: arch.albedo_eps,
        };
        let prep_pipeline = kernels.prep_pipeline(device, &prep_layout);
        let prep = PrepParams { width, height, pwidth, pheight };
        let out = OutputParams { width, height, demodulate: arch.demodulate as u32, transfer, albedo_eps: arch.albedo_eps, _pad: [0; 3] };
        let prep_params = create_init(device, "prep params", bytemuck::bytes_of(&prep), wgpu::BufferUsages::UNIFORM);
        let output_params = create_init(device, "output params", bytemuck::bytes_of(&out), wgpu::BufferUsages::UNIFORM);
        let dummy = create_init(device, "absent buffer", &[0u8; 16], wgpu::BufferUsages::STORAGE);
        let stats = create_init(
            device,
            "frame stats",
            &[0u8; 16],
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        );

        Ok(Self {
            id: NEXT_ID.fetch_add(1, Ordering::Relaxed),
            device: device.clone(),
            queue: queue.clone(),
            arch,
            graph,
            width,
            height,
            pwidth,
            pheight,
            kernels,
            prep: prep_pipeline,
            convs,
            conv_groups,
            pool_groups,
            conv_outputs,
            prep_params,
            output_params,
            input_texture,
            output_view,
            dummy,
            stats,
            textures,
            hidden_textures,
            precision,
            bytes,
            host: None,
            profiler: None,
            tuning,
            parity: 0,
            reset_pending: true,
        })
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

    /// Connect caller buffers (see [`GpuFrameIo`]); checks presence, sizes and usages.
    pub fn bind_io(&self, io: &GpuFrameIo) -> Result<IoBinding> {
        let pixels = self.width as u64 * self.height as u64;
        let needed = self.arch.required_buffers();
        let check = |name: &'static str, buf: &wgpu::Buffer, channels: u64| -> Result<()> {
            let want = pixels * channels * 4;
            if buf.size() < want {
                return Err(Error::GpuBuffer { buffer: name, reason: format!("{} bytes, need {want}", buf.size()) });
            }
            if !buf.usage().contains(wgpu::BufferUsages::STORAGE) {
                return Err(Error::GpuBuffer { buffer: name, reason: "lacks STORAGE usage".into() });
            }
            Ok(())
        };
        for &b in &needed {
            let buf =
                io.get(b).ok_or_else(|| Error::MissingInput { buffer: b.name(), needed: needed.iter().map(|b| b.name()).collect() })?;
            check(b.name(), buf, b.channels() as u64)?;
        }
        check("output", io.output, 3)?;
        let pick = |b: InputBuffer| if needed.contains(&b) { io.get(b).expect("checked") } else { &self.dummy };
        let prep = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("prep"),
            layout: &self.kernels.prep_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: self.prep_params.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: pick(InputBuffer::Color).as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: pick(InputBuffer::Albedo).as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: pick(InputBuffer::Normal).as_entire_binding() },
                wgpu::BindGroupEntry { binding: 4, resource: pick(InputBuffer::Depth).as_entire_binding() },
                wgpu::BindGroupEntry { binding: 5, resource: pick(InputBuffer::Roughness).as_entire_binding() },
                wgpu::BindGroupEntry {
                    binding: 6,
                    resource: wgpu::BindingResource::TextureView(&self.input_texture.create_view(&wgpu::TextureViewDescriptor {
                        dimension: Some(wgpu::TextureViewDimension::D2Array),
                        ..Default::default()
                    })),
                },
                wgpu::BindGroupEntry { binding: 7, resource: self.stats.as_entire_binding() },
            ],
        });
        let output = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("output"),
            layout: &self.kernels.output_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: self.output_params.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(&self.output_view) },
                wgpu::BindGroupEntry { binding: 2, resource: pick(InputBuffer::Albedo).as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: io.output.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 4, resource: self.stats.as_entire_binding() },
            ],
        });
        Ok(IoBinding { owner: self.id, prep, output })
    }

    /// Record one frame into the caller's encoder: read the buffers bound in `io`, write its
    /// output buffer. Frames must be submitted in the order they are recorded (the hidden state
    /// advances at record time).
    pub fn record(&mut self, encoder: &mut wgpu::CommandEncoder, io: &IoBinding) -> Result<()> {
        self.record_with(encoder, io, None)
    }

    /// [`Self::record`], writing a timestamp before the frame and after each stage into `queries`
    /// (prep, every conv, output: [`Graph::nodes`]` + 3` queries).
    fn record_with(&mut self, encoder: &mut wgpu::CommandEncoder, io: &IoBinding, queries: Option<&wgpu::QuerySet>) -> Result<()> {
        if io.owner != self.id {
            return Err(Error::GpuBuffer { buffer: "io", reason: "binding was made by another Denoiser".into() });
        }
        let (reset, parity) = (self.reset_pending, self.parity);
        encoder.clear_buffer(&self.stats, 0, None);
        let stamp = |pass: &mut wgpu::ComputePass, i: u32| {
            if let Some(q) = queries {
                pass.write_timestamp(q, i);
            }
        };
        let n = self.conv_groups[parity].len();
        let mut pools = self.graph.pools.iter().zip(&self.pool_groups[parity]).peekable();
        // The frame is one compute pass, split after each staged conv for the copy of its output
        // into its texture (ConvPlan::staged). That conv's stage is stamped at the start of the
        // next pass, so its time holds the copy.
        let mut next = 0;
        let mut pending_stamp = None;
        loop {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("rae frame"), timestamp_writes: None });
            if let Some(i) = pending_stamp.take() {
                stamp(&mut pass, i);
            }
            if next == 0 {
                if let Some(q) = queries {
                    write_opening_timestamp(&mut pass, q, 0, self.graph.nodes.len() as u32 + 3);
                }
                pass.set_pipeline(&self.prep);
                pass.set_bind_group(0, &io.prep, &[]);
                pass.dispatch_workgroups(self.pwidth.div_ceil(WORKGROUP), self.pheight.div_ceil(WORKGROUP), 1);
                stamp(&mut pass, 1);
            }
            let mut staged = None;
            while next < n {
                let i = next;
                next += 1;
                self.convs.record(&mut pass, i, reset, &self.conv_groups[parity][i]);
                if self.convs.staged(i) {
                    staged = Some(i);
                    break;
                }
                // The pool of a block's new state runs right after the conv that writes it (its
                // time is counted with that conv's stage), unless that conv pooled it itself.
                if let Some((p, g)) = pools.next_if(|(p, _)| p.after == i)
                    && !self.convs.pools(i)
                {
                    let (w, h) = (self.pwidth >> p.level, self.pheight >> p.level);
                    pass.set_pipeline(&self.kernels.pool);
                    pass.set_bind_group(0, g, &[]);
                    pass.dispatch_workgroups(w.div_ceil(WORKGROUP), h.div_ceil(WORKGROUP), blocks(p.channels));
                }
                stamp(&mut pass, 2 + i as u32);
            }
            if let Some(i) = staged {
                drop(pass);
                self.convs.copy_staged(encoder, i, &self.conv_outputs[parity][i]);
                // A staged conv pools its own output (F(4x4) tiles always can).
                debug_assert!(self.graph.pools.iter().all(|p| p.after != i) || self.convs.pools(i));
                let _ = pools.next_if(|(p, _)| p.after == i);
                pending_stamp = Some(2 + i as u32);
                continue;
            }
            pass.set_pipeline(&self.kernels.output);
            pass.set_bind_group(0, &io.output, &[]);
            pass.dispatch_workgroups(self.width.div_ceil(WORKGROUP), self.height.div_ceil(WORKGROUP), 1);
            stamp(&mut pass, 2 + self.graph.nodes.len() as u32);
            break;
        }
        self.parity ^= 1;
        self.reset_pending = false;
        Ok(())
    }

    /// Dispatch every pipeline of a frame once, last stage first, with one workgroup each, and
    /// wait: a helper that compiles pipelines for another denoiser's first frame
    /// ([`crate::gpu::CompileHelper`]; CPU drivers compile at a pipeline's first dispatch, and
    /// one workgroup costs no arithmetic to speak of at any frame size). What it writes is
    /// meaningless, so the hidden state is reset after it.
    pub fn compile_backwards(&mut self) -> Result<()> {
        if self.host.is_none() {
            self.host = Some(self.make_host_io()?);
        }
        let host = self.host.as_ref().expect("made above");
        let parity = self.parity;
        let mut encoder = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("rae compile") });
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("rae compile"), timestamp_writes: None });
            pass.set_pipeline(&self.kernels.output);
            pass.set_bind_group(0, &host.binding.output, &[]);
            pass.dispatch_workgroups(1, 1, 1);
            let pools: Vec<_> = self.graph.pools.iter().zip(&self.pool_groups[parity]).collect();
            for (i, group) in self.conv_groups[parity].iter().enumerate().rev() {
                if let Some((_, g)) = pools.iter().find(|(p, _)| p.after == i)
                    && !self.convs.pools(i)
                {
                    pass.set_pipeline(&self.kernels.pool);
                    pass.set_bind_group(0, *g, &[]);
                    pass.dispatch_workgroups(1, 1, 1);
                }
                self.convs.record_compile(&mut pass, i, group);
            }
            pass.set_pipeline(&self.prep);
            pass.set_bind_group(0, &host.binding.prep, &[]);
            pass.dispatch_workgroups(1, 1, 1);
        }
        self.queue.submit(Some(encoder.finish()));
        self.device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| Error::Gpu(e.to_string()))?;
        self.reset_pending = true;
        Ok(())
    }

    /// Denoise one frame from host slices; returns RGB radiance (`width * height * 3`).
    pub fn denoise(&mut self, frame: &FrameInputs) -> Result<Vec<f32>> {
        let mut out = vec![0.0; self.width as usize * self.height as usize * 3];
        self.denoise_into(frame, &mut out)?;
        Ok(out)
    }

    /// Denoise one frame from host slices into `out` (`width * height * 3`), with timings.
    pub fn denoise_into(&mut self, frame: &FrameInputs, out: &mut [f32]) -> Result<FrameTimings> {
        let needed = self.arch.required_buffers();
        frame.validate(&needed, self.width, self.height)?;
        let n = self.width as usize * self.height as usize * 3;
        if out.len() != n {
            return Err(Error::InputSize {
                buffer: "output",
                found: out.len(),
                expected: n,
                width: self.width,
                height: self.height,
                channels: 3,
            });
        }
        if self.host.is_none() {
            self.host = Some(self.make_host_io()?);
        }
        let t0 = Instant::now();
        let host = self.host.take().expect("made above");
        let mut encoder = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("rae frame") });
        let uploaded = self.upload(&host, frame, &mut encoder);
        let recorded = uploaded.and_then(|_| self.record(&mut encoder, &host.binding));
        encoder.copy_buffer_to_buffer(&host.output, 0, &host.readback, 0, host.output.size());
        let t1 = Instant::now();
        self.queue.submit(Some(encoder.finish()));
        let waited = self.device.poll(wgpu::PollType::wait_indefinitely());
        let t2 = Instant::now();
        let result = recorded
            .and(waited.map(|_| ()).map_err(|e| Error::Gpu(e.to_string())))
            .and_then(|_| finish_host_frame(&self.device, &host, out));
        let t3 = Instant::now();
        self.host = Some(host);
        result.map(|_| FrameTimings { upload: t1 - t0, gpu: t2 - t1, download: t3 - t2 })
    }

    /// Copy the frame's host slices into the mapped staging buffer, unmap it and record its
    /// copies into the input buffers.
    fn upload(&self, host: &HostIo, frame: &FrameInputs, encoder: &mut wgpu::CommandEncoder) -> Result<()> {
        if !host.upload_mapped.load(Ordering::Relaxed) {
            // Only after a failed frame: map it again (a frame normally ends with it mapped).
            let (tx, rx) = std::sync::mpsc::channel();
            host.upload.map_async(wgpu::MapMode::Write, .., move |r| {
                let _ = tx.send(r);
            });
            self.device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| Error::Gpu(e.to_string()))?;
            rx.recv().map_err(|e| Error::Gpu(e.to_string()))?.map_err(|e| Error::Gpu(e.to_string()))?;
            host.upload_mapped.store(true, Ordering::Relaxed);
        }
        {
            let mut view = host.upload.get_mapped_range_mut(..).map_err(|e| Error::Gpu(format!("staging buffer: {e:?}")))?;
            for ((b, buf), &off) in host.inputs.iter().zip(&host.offsets) {
                let src: &[u8] = bytemuck::cast_slice(frame.get(*b).expect("validated"));
                view.slice(off as usize..off as usize + src.len()).copy_from_slice(src);
                debug_assert_eq!(src.len() as u64, buf.size());
            }
        }
        host.upload.unmap();
        host.upload_mapped.store(false, Ordering::Relaxed);
        for ((_, buf), &off) in host.inputs.iter().zip(&host.offsets) {
            encoder.copy_buffer_to_buffer(&host.upload, off, buf, 0, buf.size());
        }
        Ok(())
    }

    /// Denoise one frame from host slices with a timestamp after every stage; returns each
    /// stage's GPU time in milliseconds: `prep`, every conv by module name, `output`. Needs
    /// `TIMESTAMP_QUERY_INSIDE_PASSES` (lavapipe and most Vulkan drivers have it).
    pub fn denoise_profiled(&mut self, frame: &FrameInputs, out: &mut [f32]) -> Result<Vec<(String, f64)>> {
        if !self.device.features().contains(wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES) {
            return Err(Error::Gpu("the device has no TIMESTAMP_QUERY_INSIDE_PASSES: no per-stage times".into()));
        }
        let needed = self.arch.required_buffers();
        frame.validate(&needed, self.width, self.height)?;
        if self.host.is_none() {
            self.host = Some(self.make_host_io()?);
        }
        if self.profiler.is_none() {
            // A timestamp before the frame and after each stage, and the opening one's spare.
            let count = self.graph.nodes.len() as u32 + 4;
            let queries =
                self.device.create_query_set(&wgpu::QuerySetDescriptor { label: Some("stages"), ty: wgpu::QueryType::Timestamp, count });
            let buffer = |usage| {
                self.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("timestamps"),
                    size: count as u64 * 8,
                    usage,
                    mapped_at_creation: false,
                })
            };
            let resolved = buffer(wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC);
            let readback = buffer(wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST);
            self.profiler = Some(Profiler { queries, resolved, readback, count });
        }
        let prof = self.profiler.take().expect("made above");
        let count = prof.count;
        let host = self.host.take().expect("made above");
        let mut encoder = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("rae frame (profiled)") });
        let uploaded = self.upload(&host, frame, &mut encoder);
        let recorded = uploaded.and_then(|_| self.record_with(&mut encoder, &host.binding, Some(&prof.queries)));
        encoder.resolve_query_set(&prof.queries, 0..count, &prof.resolved, 0);
        encoder.copy_buffer_to_buffer(&prof.resolved, 0, &prof.readback, 0, count as u64 * 8);
        encoder.copy_buffer_to_buffer(&host.output, 0, &host.readback, 0, host.output.size());
        self.queue.submit(Some(encoder.finish()));
        let result = recorded.and_then(|_| finish_host_frame(&self.device, &host, out));
        self.host = Some(host);
        let mut ticks = vec![0f32; 2 * count as usize];
        let read = result.and_then(|_| read_buffer(&self.device, &prof.readback, &mut ticks));
        self.profiler = Some(prof);
        read?;
        let ticks: Vec<u64> = bytemuck::pod_collect_to_vec(&ticks);
        let period = self.queue.get_timestamp_period() as f64;
        let pooled = |i: usize| self.graph.pools.iter().any(|p| p.after == i);
        let conv_names =
            self.graph.nodes.iter().enumerate().map(|(i, n)| if pooled(i) { format!("{}+pool", n.name) } else { n.name.clone() });
        let names = std::iter::once("prep".to_string()).chain(conv_names).chain(std::iter::once("output".to_string()));
        // The last query is the spare of the opening timestamp (`names` ends before it).
        Ok(names.zip(ticks.windows(2)).map(|(n, w)| (n, w[1].saturating_sub(w[0]) as f64 * period * 1e-6)).collect())
    }

    fn make_host_io(&self) -> Result<HostIo> {
        let pixels = self.width as u64 * self.height as u64;
        let buffer = |label, size, usage| {
            self.device.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false })
        };
        let inputs: Vec<_> = self
            .arch
            .required_buffers()
            .into_iter()
            .map(|b| (b, buffer(b.name(), pixels * b.channels() as u64 * 4, wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST)))
            .collect();
        let mut offsets = Vec::with_capacity(inputs.len());
        let mut staged = 0u64;
        for (_, b) in &inputs {
            offsets.push(staged);
            staged += b.size().next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT);
        }
        let upload = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("upload staging"),
            size: staged,
            usage: wgpu::BufferUsages::MAP_WRITE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: true,
        });
        let output = buffer("output", pixels * 12, wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC);
        let readback = buffer("readback", pixels * 12, wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST);
        let get = |b: InputBuffer| inputs.iter().find(|(x, _)| *x == b).map(|(_, buf)| buf);
        let binding = self.bind_io(&GpuFrameIo {
            color: get(InputBuffer::Color).expect("color is always an input"),
            albedo: get(InputBuffer::Albedo),
            normal: get(InputBuffer::Normal),
            depth: get(InputBuffer::Depth),
            roughness: get(InputBuffer::Roughness),
            output: &output,
        })?;
        Ok(HostIo { inputs, offsets, upload, upload_mapped: std::sync::atomic::AtomicBool::new(true), output, readback, binding })
    }

    /// The packed network input of the last frame, channel-major (`channels x ph x pw`), for
    /// checking the prep kernel.
    pub fn read_input(&self) -> Result<Vec<f32>> {
        let all = read_texture(&self.device, &self.queue, &self.input_texture)?;
        let (w, h) = (self.pwidth as usize, self.pheight as usize);
        let c = self.graph.in_channels;
        Ok((0..c * h * w)
            .map(|i| {
                let (ch, p) = (i / (h * w), i % (h * w));
                all[((ch / 4) * h * w + p) * 4 + ch % 4]
            })
            .collect())
    }

    /// The largest prepared (demodulated, transfer-space) color value of the last frame, as
    /// prep recorded it for the output's bound: for checking the prep kernel's reduction.
    pub fn read_color_max(&self) -> Result<f32> {
        let readback = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("stats readback"),
            size: 16,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("read stats") });
        encoder.copy_buffer_to_buffer(&self.stats, 0, &readback, 0, 16);
        self.queue.submit(Some(encoder.finish()));
        let mut v = [0f32; 4];
        read_buffer(&self.device, &readback, &mut v)?;
        Ok(v[0])
    }

    /// Storage precision of activations and hidden state.
    pub fn precision(&self) -> Precision {
        self.precision
    }

    /// Largest |value| of each recurrent block's current hidden state (d1 .. bottleneck), read
    /// back from the GPU: for watching the state over long sequences. A reset denoiser reports
    /// the state it will ignore on its next frame.
    pub fn hidden_max_abs(&self) -> Result<Vec<f32>> {
        self.hidden_textures
            .iter()
            .map(|pair| {
                let v = read_texture(&self.device, &self.queue, &pair[self.parity])?;
                Ok(v.iter().fold(0.0f32, |m, x| if x.is_nan() { f32::NAN } else { m.max(x.abs()) }))
            })
            .collect()
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

    /// Textures held (for memory reports and tests).
    pub fn texture_count(&self) -> usize {
        self.textures.len()
    }
}

/// Bytes of the activation and hidden-state textures a [`Denoiser`] allocates for `graph` at
/// the padded size `pwidth` x `pheight`: the input, two textures per recurrent block, the
/// temporaries as shared by liveness, and the pooled copies of the encoder blocks' outputs. Weights and uniforms are not included. Needs no device,
/// so memory at any size can be reported (`rae-cli info --size`).
pub fn activation_bytes(graph: &Graph, pwidth: u32, pheight: u32, precision: Precision) -> u64 {
    let tex = |level: usize, channels: usize| {
        (pwidth >> level) as u64 * (pheight >> level) as u64 * blocks(channels) as u64 * precision.texel_bytes()
    };
    let input = tex(0, graph.in_channels);
    let hidden: u64 = graph.hidden.iter().map(|&(c, level)| 2 * tex(level, c)).sum();
    let temps: u64 = graph.allocate_temps().1.iter().map(|&(level, c)| tex(level, c)).sum();
    let pooled: u64 = graph.pools.iter().map(|p| tex(p.level, p.channels)).sum();
    input + hidden + temps + pooled
}

fn create_init(device: &wgpu::Device, label: &str, contents: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
    use wgpu::util::DeviceExt;
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
}

/// After a host-path frame's submit: map the staging buffer for the next frame's writes and the
/// readback for this frame's output in one poll, then copy the output into `out`.
fn finish_host_frame(device: &wgpu::Device, host: &HostIo, out: &mut [f32]) -> Result<()> {
    // Each callback says which buffer it is, so the staging buffer's flag is right even when
    // the readback fails (a lost device): the next frame then maps it only if it is unmapped.
    let (tx, rx) = std::sync::mpsc::channel();
    let tx2 = tx.clone();
    host.upload.map_async(wgpu::MapMode::Write, .., move |r| {
        let _ = tx2.send((true, r));
    });
    host.readback.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send((false, r));
    });
    device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| Error::Gpu(e.to_string()))?;
    let (mut failed, mut readback_mapped) = (None, false);
    for _ in 0..2 {
        let (upload, r) = rx.recv().map_err(|e| Error::Gpu(e.to_string()))?;
        match r {
            Ok(()) if upload => host.upload_mapped.store(true, Ordering::Relaxed),
            Ok(()) => readback_mapped = true,
            Err(e) => failed = Some(Error::Gpu(e.to_string())),
        }
    }
    if let Some(e) = failed {
        // Leave the readback unmapped for the next frame's copy.
        if readback_mapped {
            host.readback.unmap();
        }
        return Err(e);
    }
    {
        let view = host.readback.get_mapped_range(..).map_err(|e| Error::Gpu(format!("{e:?}")))?;
        out.copy_from_slice(&bytemuck::cast_slice::<u8, f32>(&view)[..out.len()]);
    }
    host.readback.unmap();
    Ok(())
}

/// A tile and source kind that reached the second round of tuning for a conv, with its time
/// there ([`Denoiser::tuning`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Finalist {
    /// The candidate tile (before a conv's size shrinks it, [`Denoiser::conv_tiles`]).
    pub tile: Tile,
    /// How the conv read its sources.
    pub sources: SourceAccess,
    /// The conv's time with them: the lower of its two medians, in nanoseconds.
    pub ns: f64,
}

/// Timed runs of the convs per timing of a candidate plan ([`tune`]).
const TUNE_ROUNDS: usize = 5;

/// Tiles per conv that the first round of [`tune`] passes to the second.
const TUNE_SHORTLIST: usize = 2;

/// The tiles a [`Denoiser`] times for `choice` on a device with timestamps inside passes
/// (empty where `choice` fixes the tile): [`TUNE_TILES`], a [`TileChoice::TunedAmong`] list, or
/// for [`TileChoice::Auto`] and the tuned-mma choices [`TUNE_TILES`], a
/// [`TileChoice::TunedMmaWith`] list, and where `mma` (matrix units, storage weights, room for
/// their workgroup memory) the precision's matrix-unit tiles.
fn tuning_candidates(choice: TileChoice, precision: Precision, mma: bool, base: &[Tile]) -> Vec<Tile> {
    let mut candidates = match choice {
        TileChoice::Fixed(_) => return Vec::new(),
        TileChoice::Tuned => return base.to_vec(),
        TileChoice::TunedAmong(list) => return list.to_vec(),
        TileChoice::Auto | TileChoice::TunedMma | TileChoice::TunedMmaWith(_) => base.to_vec(),
    };
    if let TileChoice::TunedMmaWith(extra) = choice {
        candidates.extend(extra);
    }
    if mma {
        candidates.extend(match precision {
            Precision::F32 => MMA_SPLIT_TILES,
            Precision::F16 => MMA_TILES,
        });
    }
    candidates
}

/// The textures one conv is bound to while tuning: its sources, its destination, and the
/// value its output is max-pooled into, if any.
struct NodeViews {
    a: wgpu::TextureView,
    b: wgpu::TextureView,
    out: wgpu::TextureView,
    pooled: Option<wgpu::TextureView>,
}

/// The fastest tile and source access for each conv on this device, among `candidates` and
/// `accesses`, in two rounds:
/// 1. Every candidate with `accesses[0]`, one plan at a time; each conv's
///    [`TUNE_SHORTLIST`] fastest tiles go on.
/// 2. Every tile some conv shortlisted, with every access, all plans built first and then
///    timed twice, in one order and then the reverse, with nothing compiled between; each conv
///    keeps the tile and access of its lowest time. Timing the finalists side by side, and
///    each in both halves of the run, is what makes the picks steady: in round 1 each
///    candidate is timed right after its own pipelines were compiled, at whatever clock the
///    GPU had come back to, and picks of near-equal tiles varied from build to build (about
///    0.3 ms of a 1080p frame on the H100, docs/PERF.md session 15).
///
/// A timing runs the plan's convs once untimed (first dispatches) and then [`TUNE_ROUNDS`]
/// times in one pass, with a timestamp after each conv; a conv's time is the median of its
/// rounds. The activations hold whatever they hold (zeros on a fresh denoiser): the kernel's
/// time does not depend on values (no data-dependent branches). Each conv reads its weights
/// from `memory_of(tile, conv)`, the memory the plan built from the picks gives it.
#[allow(clippy::too_many_arguments)]
fn tune(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    kernels: &mut Kernels,
    specs: &[ConvSpec],
    views: &[NodeViews],
    candidates: &[Tile],
    accesses: &[SourceAccess],
    memory_of: &dyn Fn(Tile, &ConvSpec) -> WeightMemory,
) -> Result<Vec<Vec<Finalist>>> {
    let n = specs.len();
    if candidates.len() == 1 && accesses.len() == 1 {
        return Ok(vec![vec![Finalist { tile: candidates[0], sources: accesses[0], ns: f64::NAN }]; n]);
    }
    // Per round: the opening timestamp, its spare, one after each conv.
    let count = ((n + 2) * (TUNE_ROUNDS + 1)) as u32;
    let queries = device.create_query_set(&wgpu::QuerySetDescriptor { label: Some("tile tuning"), ty: wgpu::QueryType::Timestamp, count });
    let build = |kernels: &mut Kernels, tile: Tile, access: SourceAccess| -> Result<(ConvPlan, Vec<wgpu::BindGroup>)> {
        let memories: Vec<WeightMemory> = specs.iter().map(|s| memory_of(tile, s)).collect();
        let plan = ConvPlan::with_choices(device, queue, kernels, specs, &[tile], &[access], &memories)?;
        let groups =
            views.iter().enumerate().map(|(i, v)| plan.bind_group(device, kernels, i, &v.a, &v.b, &v.out, v.pooled.as_ref())).collect();
        Ok((plan, groups))
    };
    // Round 1: each conv's times of every candidate, then its shortlist.
    let mut times: Vec<Vec<f64>> = vec![Vec::with_capacity(candidates.len()); n];
    for &tile in candidates {
        let (plan, groups) = build(kernels, tile, accesses[0])?;
        for (conv, t) in times.iter_mut().zip(time_plan(device, queue, &queries, &plan, &groups)?) {
            conv.push(t);
        }
    }
    let mut finalists: Vec<Tile> = Vec::new();
    for conv in &times {
        let mut order: Vec<usize> = (0..candidates.len()).collect();
        order.sort_by(|&a, &b| conv[a].total_cmp(&conv[b]));
        for &k in order.iter().take(TUNE_SHORTLIST) {
            if !finalists.contains(&candidates[k]) {
                finalists.push(candidates[k]);
            }
        }
    }
    // Round 2: the finalists with every access, side by side, forwards then backwards.
    let entries: Vec<(Tile, SourceAccess)> = accesses.iter().flat_map(|&a| finalists.iter().map(move |&t| (t, a))).collect();
    let plans: Vec<(ConvPlan, Vec<wgpu::BindGroup>)> = entries.iter().map(|&(t, a)| build(kernels, t, a)).collect::<Result<_>>()?;
    let mut finals: Vec<Vec<Finalist>> =
        vec![entries.iter().map(|&(tile, sources)| Finalist { tile, sources, ns: f64::INFINITY }).collect(); n];
    let order: Vec<usize> = (0..plans.len()).chain((0..plans.len()).rev()).collect();
    for k in order {
        let (plan, groups) = &plans[k];
        for (conv, t) in finals.iter_mut().zip(time_plan(device, queue, &queries, plan, groups)?) {
            conv[k].ns = conv[k].ns.min(t);
        }
    }
    for conv in &mut finals {
        conv.sort_by(|a, b| a.ns.total_cmp(&b.ns));
    }
    Ok(finals)
}

/// One timing of a candidate plan for [`tune`]: the median time of each conv over
/// [`TUNE_ROUNDS`] rounds after an untimed one, in nanoseconds.
fn time_plan(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    queries: &wgpu::QuerySet,
    plan: &ConvPlan,
    groups: &[wgpu::BindGroup],
) -> Result<Vec<f64>> {
    let n = groups.len();
    let rounds = TUNE_ROUNDS + 1;
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("tile tuning") });
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("tile tuning"), timestamp_writes: None });
        for r in 0..rounds {
            let base = (r * (n + 2)) as u32;
            write_opening_timestamp(&mut pass, queries, base, base + n as u32 + 1);
            for (i, group) in groups.iter().enumerate() {
                plan.record(&mut pass, i, false, group);
                pass.write_timestamp(queries, base + 1 + i as u32);
            }
        }
    }
    queue.submit(Some(encoder.finish()));
    let ticks = read_timestamps(device, queue, queries, (rounds * (n + 2)) as u32)?;
    let period = queue.get_timestamp_period() as f64;
    Ok((0..n)
        .map(|i| {
            // Round 0 is the untimed one.
            let mut t: Vec<f64> =
                (1..rounds).map(|r| ticks[r * (n + 2) + i + 1].saturating_sub(ticks[r * (n + 2) + i]) as f64 * period).collect();
            t.sort_by(f64::total_cmp);
            t[t.len() / 2]
        })
        .collect())
}

/// Where a timestamp can be written: a command encoder or a compute pass.
pub trait TimestampWriter {
    /// Write timestamp `index` of `queries` here.
    fn write_timestamp_to(&mut self, queries: &wgpu::QuerySet, index: u32);
}

impl TimestampWriter for wgpu::CommandEncoder {
    fn write_timestamp_to(&mut self, queries: &wgpu::QuerySet, index: u32) {
        self.write_timestamp(queries, index);
    }
}

impl TimestampWriter for wgpu::ComputePass<'_> {
    fn write_timestamp_to(&mut self, queries: &wgpu::QuerySet, index: u32) {
        self.write_timestamp(queries, index);
    }
}

/// Write timestamp `index`, which opens a timed span, so that it is taken before the work
/// recorded after it runs: a second timestamp into the unused query `spare` follows it.
///
/// Lavapipe (Mesa 22.3's llvmpipe) does not read the clock when the command runs. It bins the
/// query into its rasterizer's current scene and reads the clock when that scene is next
/// flushed. A timestamp write flushes before binning its own query (wgpu writes at
/// BOTTOM_OF_PIPE), and so does a pipeline barrier; a compute dispatch does not. So an opening
/// timestamp followed by dispatches that need no barrier between them (a frame's prep: its
/// barriers are wgpu's, in the command buffer before the frame's) was read only at the first
/// barrier, after them. A 256x256 frame lost prep's 3-4 ms from its span, and a stage table lost
/// prep (docs/PERF.md, session 19). The spare's write flushes the scene holding `index` at
/// once. The timestamps that close a span need no spare: the next dispatch's barrier or the end
/// of the command buffer flushes them. Drivers that write timestamps as the GPU passes them lose
/// one query.
pub fn write_opening_timestamp(writer: &mut impl TimestampWriter, queries: &wgpu::QuerySet, index: u32, spare: u32) {
    writer.write_timestamp_to(queries, index);
    writer.write_timestamp_to(queries, spare);
}

/// Resolve the first `count` timestamps of `queries` (written by work already submitted) and
/// read them back, in ticks: multiply differences by `queue.get_timestamp_period()` for
/// nanoseconds. Makes its own buffers (set-up and benchmark use; `denoise_profiled` keeps
/// persistent ones) and waits for the GPU.
pub fn read_timestamps(device: &wgpu::Device, queue: &wgpu::Queue, queries: &wgpu::QuerySet, count: u32) -> Result<Vec<u64>> {
    let size = count as u64 * 8;
    let buffer =
        |usage| device.create_buffer(&wgpu::BufferDescriptor { label: Some("timestamps"), size, usage, mapped_at_creation: false });
    let resolved = buffer(wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC);
    let readback = buffer(wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST);
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("timestamps") });
    encoder.resolve_query_set(queries, 0..count, &resolved, 0);
    encoder.copy_buffer_to_buffer(&resolved, 0, &readback, 0, size);
    queue.submit(Some(encoder.finish()));
    let mut raw = vec![0f32; 2 * count as usize];
    read_buffer(device, &readback, &mut raw)?;
    Ok(bytemuck::pod_collect_to_vec(&raw))
}

/// Map a MAP_READ buffer and copy its f32s into `out`.
fn read_buffer(device: &wgpu::Device, buffer: &wgpu::Buffer, out: &mut [f32]) -> Result<()> {
    let (tx, rx) = std::sync::mpsc::channel();
    buffer.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| Error::Gpu(e.to_string()))?;
    rx.recv().map_err(|e| Error::Gpu(e.to_string()))?.map_err(|e| Error::Gpu(e.to_string()))?;
    {
        let view = buffer.get_mapped_range(..).map_err(|e| Error::Gpu(format!("{e:?}")))?;
        out.copy_from_slice(&bytemuck::cast_slice::<u8, f32>(&view)[..out.len()]);
    }
    buffer.unmap();
    Ok(())
}

/// Read a whole rgba32float or rgba16float texture array back: `layers x h x w x 4` f32.
pub fn read_texture(device: &wgpu::Device, queue: &wgpu::Queue, texture: &wgpu::Texture) -> Result<Vec<f32>> {
    let size = texture.size();
    let (w, h, l) = (size.width, size.height, size.depth_or_array_layers);
    let texel = match texture.format() {
        wgpu::TextureFormat::Rgba32Float => 16,
        wgpu::TextureFormat::Rgba16Float => 8,
        f => return Err(Error::Gpu(format!("read_texture: unsupported format {f:?}"))),
    };
    let row = (w * texel).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let buf = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("texture readback"),
        size: row as u64 * h as u64 * l as u64,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = device.create_command_encoder(&Default::default());
    enc.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buf,
            layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(row), rows_per_image: Some(h) },
        },
        size,
    );
    queue.submit(Some(enc.finish()));
    let mut raw = vec![0f32; (row / 4 * h * l) as usize];
    read_buffer(device, &buf, &mut raw)?;
    if texel == 8 {
        // Widen f16 texels: the same rows, each u16 to an f32.
        let halves: &[u16] = bytemuck::cast_slice(&raw);
        let rowh = (row / 2) as usize;
        let mut out = Vec::with_capacity((w * h * l * 4) as usize);
        for r in 0..(h * l) as usize {
            out.extend(halves[r * rowh..r * rowh + w as usize * 4].iter().map(|&b| half::f16::from_bits(b).to_f32()));
        }
        return Ok(out);
    }
    let rowf = (row / 4) as usize;
    let mut out = Vec::with_capacity((w * h * l * 4) as usize);
    for layer in 0..l as usize {
        for y in 0..h as usize {
            let start = (layer * h as usize + y) * rowf;
            out.extend_from_slice(&raw[start..start + w as usize * 4]);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tuning_times_the_choices_candidates() {
        let x3p: &'static [Tile] = Vec::leak(vec![Tile::mma_split_prefetch(32).unwrap()]);
        let join = |parts: &[&[Tile]]| parts.concat();
        // Plain tuning and a list ignore the matrix units; a fixed tile tunes nothing.
        assert_eq!(tuning_candidates(TileChoice::Tuned, Precision::F32, true, &TUNE_TILES), TUNE_TILES);
        assert_eq!(tuning_candidates(TileChoice::Tuned, Precision::F32, false, &TUNE_TILES_LANES), TUNE_TILES_LANES);
        assert_eq!(tuning_candidates(TileChoice::TunedAmong(x3p), Precision::F16, true, &TUNE_TILES), x3p);
        assert!(tuning_candidates(TileChoice::Fixed(Tile::default()), Precision::F32, true, &TUNE_TILES).is_empty());
        // Auto and tuned-mma add the precision's matrix-unit tiles where they run.
        for choice in [TileChoice::Auto, TileChoice::TunedMma] {
            assert_eq!(tuning_candidates(choice, Precision::F32, true, &TUNE_TILES), join(&[&TUNE_TILES, &MMA_SPLIT_TILES]));
            assert_eq!(tuning_candidates(choice, Precision::F16, true, &TUNE_TILES), join(&[&TUNE_TILES, &MMA_TILES]));
            assert_eq!(tuning_candidates(choice, Precision::F32, false, &TUNE_TILES), TUNE_TILES);
        }
        // tuned-mma+T+...: the listed tiles as well, whether or not the matrix units run.
        let with = TileChoice::TunedMmaWith(x3p);
        assert_eq!(tuning_candidates(with, Precision::F32, true, &TUNE_TILES), join(&[&TUNE_TILES, x3p, &MMA_SPLIT_TILES]));
        assert_eq!(tuning_candidates(with, Precision::F32, false, &TUNE_TILES), join(&[&TUNE_TILES, x3p]));
    }
}

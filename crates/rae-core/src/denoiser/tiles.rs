//! Frames in overlapping tiles, under a memory cap ([`Options::max_memory`]) or past the
//! device's limits: the plan ([`TilePlan`], [`MemoryPlan`]) and the recurrent state kept for
//! the whole frame between the tiles ([`Tiles`]).
//!
//! # The plan
//! The padded frame is cut into a grid of tile *interiors* (near-equal, multiples of
//! `2^levels`, so every level's coordinates are whole). The network runs on each tile's
//! *extent*: its interior and `overlap` pixels around it, shifted inward at the frame's edges so
//! that an extent never leaves the padded frame (there its zero padding is the untiled
//! network's). Only the interior of each tile's output is kept, so a seam sees `overlap` pixels
//! of context on each side. One network of the extent's size serves every tile.
//!
//! # The hidden state
//! Each recurrent block's state is kept for the whole frame in one texture (`global`). A tile
//! copies the state under its extent into the network's previous-state texture, runs, and
//! writes the new state of its *interior* back: every pixel's state is the one computed with
//! the most context, as untiled. Tiles run in rows, left to right. A tile's extent reaches into
//! the interiors of tiles that ran before it this frame (the row above, the tile to its left),
//! whose state is already the new one, so the old state there is saved before it is
//! overwritten: the band of the next row's margin, the whole frame wide, at the start of each
//! row (`above`, two that alternate), and the next tile's left margin before each write-back
//! (`left`). Copy-ins read the bands over the global state where they apply. Nothing is
//! allocated per frame or per tile.
//!
//! Where the state of the whole frame does not fit the cap beside the smallest tiles (8K in
//! f16 is 3.1 GiB of it), it is kept in host memory instead: a tile's old state is gathered on
//! the host into a staging buffer and copied into the network before it runs, and its
//! interior's new state copied back and scattered after, with the same bands.

use super::*;

/// The overlap a tile's extent takes around its interior, in pixels of the frame, when the
/// caller does not choose one ([`FrameTiles`]). Measured on the sample sequence (seams below the
/// golden tolerance's scale; `docs/PERF.md`).
pub const TILE_OVERLAP: u32 = 64;

/// Frame tiles as the caller fixes them ([`Options::frame_tiles`]): the largest interior
/// side and the overlap, in pixels (each rounded up to a multiple of the network's `2^levels`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameTiles {
    /// Largest tile interior side.
    pub tile: u32,
    /// Pixels of context around each interior (fewer at the frame's edges).
    pub overlap: u32,
    /// Keep the frame's state in host memory (staged per tile) rather than on the GPU.
    pub host_state: bool,
}

/// One tile's place along one axis of the padded frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Span {
    /// First pixel of the interior.
    pub start: u32,
    /// One past the interior's last pixel.
    pub end: u32,
    /// First pixel of the extent (the extent is [`TilePlan::extent`] long).
    pub extent_start: u32,
}

impl Span {
    /// How far the extent reaches before the interior.
    pub fn margin(&self) -> u32 {
        self.start - self.extent_start
    }
}

/// How a frame is cut into tiles.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TilePlan {
    /// Frame width.
    pub width: u32,
    /// Frame height.
    pub height: u32,
    /// Padded frame width (a multiple of `2^levels`).
    pub pwidth: u32,
    /// Padded frame height.
    pub pheight: u32,
    /// The extent every tile's network runs at.
    pub extent: (u32, u32),
    /// Overlap asked for (margins are at most this, more at the frame's far edges).
    pub overlap: u32,
    /// Tiles along x.
    pub columns: Vec<Span>,
    /// Tiles along y.
    pub rows: Vec<Span>,
}

impl TilePlan {
    /// Cut a `width` x `height` frame (padded to `multiple`) into tiles of at most `tiles.tile`
    /// pixels a side with `tiles.overlap` around each. The interior must be at least twice the
    /// overlap plus two multiples, so that an extent reaches into one neighbour at most.
    pub fn new(width: u32, height: u32, multiple: u32, tiles: FrameTiles) -> Result<Self> {
        let size_err = |reason: String| Error::FrameSize { width, height, reason };
        if width == 0 || height == 0 {
            return Err(size_err("empty frame".into()));
        }
        let overlap = tiles.overlap.next_multiple_of(multiple);
        let tile = tiles.tile.next_multiple_of(multiple);
        if tile < 2 * overlap + 2 * multiple {
            return Err(size_err(format!("a tile of {tile} pixels is smaller than twice the overlap ({overlap}) plus {}", 2 * multiple)));
        }
        let (pwidth, pheight) = (width.next_multiple_of(multiple), height.next_multiple_of(multiple));
        let (columns, ew) = spans(pwidth, multiple, tile, overlap);
        let (rows, eh) = spans(pheight, multiple, tile, overlap);
        Ok(TilePlan { width, height, pwidth, pheight, extent: (ew, eh), overlap, columns, rows })
    }

    /// Number of tiles.
    pub fn count(&self) -> usize {
        self.columns.len() * self.rows.len()
    }

    /// Largest interior (x, y).
    pub fn max_interior(&self) -> (u32, u32) {
        let max = |s: &[Span]| s.iter().map(|s| s.end - s.start).max().unwrap_or(0);
        (max(&self.columns), max(&self.rows))
    }

    /// Largest margin before an interior (x, y): the bands of old state a frame keeps.
    pub fn margins(&self) -> (u32, u32) {
        let max = |s: &[Span]| s.iter().map(Span::margin).max().unwrap_or(0);
        (max(&self.columns), max(&self.rows))
    }

    /// Pixels the network runs over per frame, against the padded frame's.
    pub fn work_ratio(&self) -> f64 {
        let (ew, eh) = self.extent;
        (self.count() as f64 * ew as f64 * eh as f64) / (self.pwidth as f64 * self.pheight as f64)
    }
}

/// Interiors and extents along an axis of `p` pixels.
fn spans(p: u32, multiple: u32, tile: u32, overlap: u32) -> (Vec<Span>, u32) {
    if p <= tile {
        return (vec![Span { start: 0, end: p, extent_start: 0 }], p);
    }
    let blocks = p / multiple;
    let n = p.div_ceil(tile);
    let (base, extra) = (blocks / n, blocks % n);
    let mut starts = Vec::with_capacity(n as usize + 1);
    let mut at = 0;
    for i in 0..n {
        starts.push(at);
        at += (base + u32::from(i < extra)) * multiple;
    }
    starts.push(p);
    let extent = ((base + u32::from(extra > 0)) * multiple + 2 * overlap).min(p);
    let spans =
        starts.windows(2).map(|w| Span { start: w[0], end: w[1], extent_start: w[0].saturating_sub(overlap).min(p - extent) }).collect();
    (spans, extent)
}

/// What a frame size costs under a plan, as [`MemoryPlan::new`] bounds it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MemoryPlan {
    /// The tiles, or `None`: the frame runs whole.
    pub tiles: Option<TilePlan>,
    /// Activation textures of the network (at the padded frame, or at a tile's extent).
    pub activations: u64,
    /// The hidden state kept for the whole frame between tiles on the GPU, with its bands (0
    /// untiled); or, with the state in host memory, the buffers that stage a tile's state.
    pub state: u64,
    /// The hidden state kept in host memory between tiles, with its bands: where the state on
    /// the GPU would not fit the cap (0 otherwise). Not counted by [`Self::total`].
    pub host_state: u64,
    /// Weights, parameters and split-K or staging buffers: a bound (their packing depends on
    /// the kernels the device gets).
    pub convs: u64,
    /// The host path's transfer buffers (inputs, staging, output, readback) of a frame or tile.
    pub io: u64,
    /// The reprojection's buffers (frames with motion; untiled only).
    pub motion: u64,
}

impl MemoryPlan {
    /// Bytes in all: what [`Options::max_memory`] caps.
    pub fn total(&self) -> u64 {
        self.activations + self.state + self.convs + self.io + self.motion
    }

    /// The plan for `arch` at `width` x `height`: whole where it fits `max_memory` and the
    /// device's `limits` (texture side, storage binding size), else tiles: those fixed by
    /// `tiles`, or the largest (fewest) that fit, with [`TILE_OVERLAP`]. A cap below the
    /// smallest tiles' cost is [`Error::MemoryCap`] naming the smallest that works.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        arch: &Arch,
        width: u32,
        height: u32,
        precision: Precision,
        max_memory: Option<u64>,
        tiles: Option<FrameTiles>,
        motion: bool,
        limits: &wgpu::Limits,
    ) -> Result<Self> {
        let max_side = limits.max_texture_dimension_2d;
        // The largest transfer buffer a plan binds: RGB f32 of a frame or an extent.
        let max_pixels = limits.max_storage_buffer_binding_size / 12;
        if width == 0 || height == 0 {
            return Err(Error::FrameSize { width, height, reason: "empty frame".into() });
        }
        let graph = Graph::new(arch);
        let multiple = 1u32 << arch.levels();
        let cap = max_memory.unwrap_or(u64::MAX);
        if let Some(t) = tiles {
            let plan = Self::tiled(arch, &graph, TilePlan::new(width, height, multiple, t)?, precision, t.host_state);
            return plan.check_side(max_side);
        }
        let whole = Self::whole(arch, &graph, width, height, precision, motion);
        let fits_side = width.next_multiple_of(multiple) <= max_side && height.next_multiple_of(multiple) <= max_side;
        if whole.total() <= cap && fits_side && width as u64 * height as u64 <= max_pixels {
            return Ok(whole);
        }
        // The largest tile that fits, every multiple from the largest down.
        let overlap = TILE_OVERLAP.next_multiple_of(multiple);
        let smallest = 2 * overlap + 2 * multiple;
        let largest = (max_side.saturating_sub(2 * overlap) / multiple * multiple).min(width.max(height).next_multiple_of(multiple));
        let candidates = (smallest / multiple..=largest / multiple).rev().map(|k| k * multiple);
        // The state on the GPU where some tiles fit with it, else in host memory.
        let mut last = None;
        for host in [false, true] {
            for tile in candidates.clone() {
                let tiles = TilePlan::new(width, height, multiple, FrameTiles { tile, overlap, host_state: host })?;
                let plan = Self::tiled(arch, &graph, tiles, precision, host);
                let fits = plan.tiles.as_ref().is_some_and(|t| {
                    t.extent.0 <= max_side && t.extent.1 <= max_side && t.extent.0 as u64 * t.extent.1 as u64 <= max_pixels
                });
                if fits && plan.total() <= cap {
                    return Ok(plan);
                }
                last = Some(plan);
            }
        }
        match last {
            Some(p) if p.tiles.as_ref().is_some_and(|t| t.extent.0 <= max_side && t.extent.1 <= max_side) => {
                Err(Error::MemoryCap { width, height, cap, smallest: p.total() })
            }
            // A frame smaller than the smallest tile: the whole frame is the least it takes.
            None if fits_side => Err(Error::MemoryCap { width, height, cap, smallest: whole.total() }),
            _ => Err(Error::FrameSize { width, height, reason: format!("no tiling fits the device's texture limit {max_side}") }),
        }
    }

    fn check_side(self, max_side: u32) -> Result<Self> {
        let t = self.tiles.as_ref().expect("a tiled plan");
        if t.extent.0 > max_side || t.extent.1 > max_side {
            return Err(Error::FrameSize {
                width: t.width,
                height: t.height,
                reason: format!("tiles of {}x{} exceed the device's texture limit {max_side}", t.extent.0, t.extent.1),
            });
        }
        Ok(self)
    }

    fn whole(arch: &Arch, graph: &Graph, width: u32, height: u32, precision: Precision, motion: bool) -> Self {
        let multiple = 1u32 << arch.levels();
        let (pw, ph) = (width.next_multiple_of(multiple), height.next_multiple_of(multiple));
        MemoryPlan {
            tiles: None,
            activations: activation_bytes(graph, pw, ph, precision, motion),
            state: 0,
            host_state: 0,
            convs: conv_bytes_bound(arch, pw, ph),
            io: io_bytes(arch, width as u64 * height as u64, width as u64 * height as u64),
            motion: if motion { motion_bytes(pw, ph, arch.levels(), true) } else { 0 },
        }
    }

    fn tiled(arch: &Arch, graph: &Graph, plan: TilePlan, precision: Precision, host: bool) -> Self {
        let (ew, eh) = plan.extent;
        let (iw, ih) = plan.max_interior();
        let (mx, my) = plan.margins();
        let kept: u64 = graph
            .hidden
            .iter()
            .map(|&(c, level)| {
                let layers = blocks(c) as u64 * precision.texel_bytes();
                let at = |w: u32, h: u32| (w >> level) as u64 * (h >> level) as u64 * layers;
                let above = if plan.rows.len() > 1 { 2 * at(plan.pwidth, my) } else { 0 };
                let left = if plan.columns.len() > 1 { at(mx, ih) } else { 0 };
                at(plan.pwidth, plan.pheight) + above + left
            })
            .sum();
        let (state, host_state) = if host { (staged_state_bytes(graph, &plan, precision), kept) } else { (kept, 0) };
        MemoryPlan {
            activations: activation_bytes(graph, ew, eh, precision, false),
            state,
            host_state,
            convs: conv_bytes_bound(arch, ew, eh),
            io: io_bytes(arch, ew as u64 * eh as u64, iw as u64 * ih as u64),
            motion: 0,
            tiles: Some(plan),
        }
    }
}

/// Bytes of the buffers that stage a tile's state to and from host memory: each block's state
/// under the extent (up) and under the largest interior (down), rows padded to a copy's pitch.
fn staged_state_bytes(graph: &Graph, plan: &TilePlan, precision: Precision) -> u64 {
    let (ew, eh) = plan.extent;
    let (iw, ih) = plan.max_interior();
    let layout = |w: u32, h: u32| state_layout(graph, w, h, precision).last().map_or(0, |r| r.offset + r.bytes());
    layout(ew, eh) + layout(iw, ih)
}

/// Where each block's state of a `w` x `h` rectangle (level 0 pixels) lies in a staging buffer.
#[derive(Debug, Clone, Copy)]
struct StagedRegion {
    offset: u64,
    /// Bytes per row, padded to `COPY_BYTES_PER_ROW_ALIGNMENT`.
    pitch: u32,
    rows: u32,
    layers: u32,
}

impl StagedRegion {
    fn bytes(&self) -> u64 {
        self.pitch as u64 * self.rows as u64 * self.layers as u64
    }
}

fn state_layout(graph: &Graph, w: u32, h: u32, precision: Precision) -> Vec<StagedRegion> {
    let mut offset = 0u64;
    graph
        .hidden
        .iter()
        .map(|&(c, level)| {
            let pitch = ((w >> level) * precision.texel_bytes() as u32).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
            let r = StagedRegion { offset, pitch, rows: h >> level, layers: blocks(c) };
            offset += r.bytes();
            r
        })
        .collect()
}

/// A bound on the conv plan's buffers ([`ConvPlan::bytes`]) at a network size: the weights
/// packed four times over in f32 (Winograd F(4x4) takes 36 taps for 9), and split-K's partial
/// sums ([`crate::kernels::PARTIAL_LAYERS`] layers) or the staged outputs (up to
/// [`crate::kernels::STAGING_BYTES`], 8 layers at most), whichever is larger. Measured on
/// lavapipe: 23 MiB at 256x256 and 57 MiB at 1024x1024 in f32 against bounds of 32 and 88.
fn conv_bytes_bound(arch: &Arch, pwidth: u32, pheight: u32) -> u64 {
    let pixels = pwidth as u64 * pheight as u64;
    let partial = (pixels * 16 * crate::kernels::PARTIAL_LAYERS).max((pixels * 16 * 8).min(crate::kernels::STAGING_BYTES));
    arch.parameter_count() as u64 * 16 + partial
}

/// The host path's buffers for `inputs` input pixels and `outputs` output pixels: the model's
/// input buffers and their staging, the output and its readback.
fn io_bytes(arch: &Arch, inputs: u64, outputs: u64) -> u64 {
    let channels: u64 = arch.required_buffers().iter().map(|b| b.channels() as u64).sum();
    2 * inputs * channels * 4 + 2 * outputs * 12 + 16
}

/// The recurrent state of a tiled [`Denoiser`] between its tiles, and each tile's uniforms.
pub(super) struct Tiles {
    pub(super) plan: TilePlan,
    /// Every tile, row by row.
    pub(super) at: Vec<TileAt>,
    /// Where the frame's state and its bands are kept.
    store: Store,
    /// Each tile's prep and output uniforms, row by row.
    pub(super) prep_params: Vec<wgpu::Buffer>,
    pub(super) output_params: Vec<wgpu::Buffer>,
    /// GPU bytes held (the state on the GPU, or its staging buffers).
    pub(super) bytes: u64,
}

/// The frame's state, each `[block]`: the whole padded frame (`global`), the old state of the
/// band above a row's interiors (`above`, by row parity) and of the next tile's left margin
/// (`left`).
enum Store {
    /// On the GPU, copied texture to texture.
    Gpu { global: Vec<wgpu::Texture>, above: [Vec<wgpu::Texture>; 2], left: Vec<wgpu::Texture> },
    /// In host memory, a tile's state staged up before it runs and back after.
    Host {
        global: Vec<HostImage>,
        above: [Vec<HostImage>; 2],
        left: Vec<HostImage>,
        /// Each block's state under the extent (written by the host, copied into the network).
        upload: wgpu::Buffer,
        up: Vec<StagedRegion>,
        /// Each block's new state under the interior (copied from the network, read by the host).
        readback: wgpu::Buffer,
        down: Vec<StagedRegion>,
    },
}

/// One block's state in host memory: `layers` x `height` x `width` texels of `texel` bytes.
struct HostImage {
    data: Vec<u8>,
    width: u32,
    height: u32,
    texel: usize,
}

impl HostImage {
    /// Zeroed; host memory that cannot be had is an error, not an abort.
    fn new(width: u32, height: u32, layers: u32, texel: usize) -> Result<Self> {
        let bytes = width as usize * height as usize * layers as usize * texel;
        let mut data = Vec::new();
        data.try_reserve_exact(bytes).map_err(|e| Error::FrameSize {
            width,
            height,
            reason: format!("{} MiB of host memory for the frame's state: {e}", bytes >> 20),
        })?;
        data.resize(bytes, 0);
        Ok(HostImage { data, width, height, texel })
    }

    /// Byte range of `w` texels of row `y` of layer `z` from column `x`.
    fn row(&self, z: u32, y: u32, x: u32, w: u32) -> std::ops::Range<usize> {
        let start = ((z as usize * self.height as usize + y as usize) * self.width as usize + x as usize) * self.texel;
        start..start + w as usize * self.texel
    }

    fn layers(&self) -> u32 {
        (self.data.len() / (self.width as usize * self.height as usize * self.texel).max(1)) as u32
    }
}

/// A place the state is copied from or to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Place {
    Global,
    Above(usize),
    Left,
    /// The network's state textures (its previous state, or the new one).
    Network,
}

/// A copy of a rectangle of every block's state, in level-0 pixels (each block's level scales
/// it).
#[derive(Debug, Clone, Copy)]
struct Move {
    from: Place,
    at: (u32, u32),
    to: Place,
    to_at: (u32, u32),
    size: (u32, u32),
}

/// One tile in a frame: its place and the rectangles it reads and writes, in frame pixels.
#[derive(Debug, Clone, Copy)]
pub(super) struct TileAt {
    pub(super) row: usize,
    pub(super) column: usize,
    /// The extent's origin.
    pub(super) x0: u32,
    pub(super) y0: u32,
    /// The extent's pixels inside the frame (the inputs uploaded).
    pub(super) valid: (u32, u32),
    /// The interior's pixels inside the frame (the output kept), and its origin.
    pub(super) ix0: u32,
    pub(super) iy0: u32,
    pub(super) interior: (u32, u32),
}

impl TilePlan {
    /// Every tile, row by row.
    pub(super) fn tiles(&self) -> impl Iterator<Item = TileAt> + '_ {
        self.rows.iter().enumerate().flat_map(move |(row, r)| {
            self.columns.iter().enumerate().map(move |(column, c)| TileAt {
                row,
                column,
                x0: c.extent_start,
                y0: r.extent_start,
                valid: ((self.width - c.extent_start).min(self.extent.0), (self.height - r.extent_start).min(self.extent.1)),
                ix0: c.start,
                iy0: r.start,
                interior: (c.end.min(self.width) - c.start, r.end.min(self.height) - r.start),
            })
        })
    }
}

impl Tiles {
    /// The state of the whole frame (on the GPU or in host memory) and each tile's uniforms.
    pub(super) fn new(device: &wgpu::Device, plan: TilePlan, graph: &Graph, arch: &Arch, precision: Precision, host: bool) -> Result<Self> {
        let (_, ih) = plan.max_interior();
        let (mx, my) = plan.margins();
        let (rows, columns) = (plan.rows.len() > 1, plan.columns.len() > 1);
        let mut bytes = 0u64;
        let store = if host {
            let texel = precision.texel_bytes() as usize;
            let image = |w: u32, h: u32, used: bool| -> Result<Vec<HostImage>> {
                if !used {
                    return Ok(Vec::new());
                }
                graph.hidden.iter().map(|&(c, l)| HostImage::new(w >> l, h >> l, blocks(c), texel)).collect()
            };
            let (ew, eh) = plan.extent;
            let (iw, ih) = plan.max_interior();
            let up = state_layout(graph, ew, eh, precision);
            let down = state_layout(graph, iw, ih, precision);
            let size = |r: &[StagedRegion]| r.last().map_or(4, |r| r.offset + r.bytes());
            let buffer = |label, size, usage, mapped_at_creation| {
                device.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation })
            };
            bytes += size(&up) + size(&down);
            Store::Host {
                global: image(plan.pwidth, plan.pheight, true)?,
                above: [image(plan.pwidth, my, rows)?, image(plan.pwidth, my, rows)?],
                left: image(mx, ih, columns)?,
                upload: buffer("state upload", size(&up), wgpu::BufferUsages::MAP_WRITE | wgpu::BufferUsages::COPY_SRC, false),
                up,
                readback: buffer("state readback", size(&down), wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST, false),
                down,
            }
        } else {
            let mut make = |w: u32, h: u32, used: bool| -> Vec<wgpu::Texture> {
                if !used {
                    return Vec::new();
                }
                graph
                    .hidden
                    .iter()
                    .map(|&(c, l)| {
                        let (w, h) = ((w >> l).max(1), (h >> l).max(1));
                        bytes += w as u64 * h as u64 * blocks(c) as u64 * precision.texel_bytes();
                        build::texture(device, "frame state", w, h, blocks(c), precision.format()).0
                    })
                    .collect()
            };
            Store::Gpu {
                global: make(plan.pwidth, plan.pheight, true),
                above: [make(plan.pwidth, my, rows), make(plan.pwidth, my, rows)],
                left: make(mx, ih, columns),
            }
        };
        let transfer = match arch.transfer {
            Transfer::None => 0,
            Transfer::Log1p => 1,
        };
        let (ew, eh) = plan.extent;
        let mut prep_params = Vec::new();
        let mut output_params = Vec::new();
        for t in plan.tiles() {
            let prep = PrepParams { width: t.valid.0, height: t.valid.1, pwidth: ew, pheight: eh };
            let output = OutputParams {
                x0: t.ix0 - t.x0,
                y0: t.iy0 - t.y0,
                width: t.interior.0,
                height: t.interior.1,
                in_stride: t.valid.0,
                demodulate: arch.demodulate as u32,
                transfer,
                albedo_eps: arch.albedo_eps,
            };
            let uniform = |label, bytes: &[u8]| build::create_init(device, label, bytes, wgpu::BufferUsages::UNIFORM);
            prep_params.push(uniform("tile prep params", bytemuck::bytes_of(&prep)));
            output_params.push(uniform("tile output params", bytemuck::bytes_of(&output)));
        }
        Ok(Tiles { at: plan.tiles().collect(), plan, store, prep_params, output_params, bytes })
    }

    /// Whether the frame's state is kept in host memory.
    pub(super) fn state_on_host(&self) -> bool {
        matches!(self.store, Store::Host { .. })
    }

    /// The copies of the old state under tile `t`'s extent into the network: the global state,
    /// then the bands where tiles before it have written the new one (the row above's, saved
    /// before it wrote; the left tile's, in the interior's rows).
    fn copy_in_moves(&self, t: &TileAt) -> [Option<Move>; 3] {
        let (ew, eh) = self.plan.extent;
        let global = Move { from: Place::Global, at: (t.x0, t.y0), to: Place::Network, to_at: (0, 0), size: (ew, eh) };
        let above = (t.row > 0).then(|| {
            let size = (ew, t.iy0 - t.y0);
            Move { from: Place::Above(t.row % 2), at: (t.x0, 0), to: Place::Network, to_at: (0, 0), size }
        });
        let left = (t.column > 0).then(|| {
            let r = self.plan.rows[t.row];
            let size = (t.ix0 - t.x0, r.end - r.start);
            Move { from: Place::Left, at: (0, 0), to: Place::Network, to_at: (0, t.iy0 - t.y0), size }
        });
        [Some(global), above, left]
    }

    /// The saves of the old state tile `t`'s successors read, before `t` writes its new state
    /// back: at a row's first tile the next row's top margin, and the next tile's left margin.
    fn band_moves(&self, t: &TileAt) -> [Option<Move>; 2] {
        let plan = &self.plan;
        let above = plan.rows.get(t.row + 1).filter(|_| t.column == 0).map(|next| {
            let size = (plan.pwidth, next.margin());
            Move { from: Place::Global, at: (0, next.extent_start), to: Place::Above((t.row + 1) % 2), to_at: (0, 0), size }
        });
        let left = plan.columns.get(t.column + 1).map(|next| {
            let r = plan.rows[t.row];
            let size = (next.margin(), r.end - r.start);
            Move { from: Place::Global, at: (next.extent_start, r.start), to: Place::Left, to_at: (0, 0), size }
        });
        [above, left]
    }

    /// The write-back of tile `t`'s new state: its interior, from the network into the global
    /// state.
    fn write_back_move(&self, t: &TileAt) -> Move {
        let (c, r) = (self.plan.columns[t.column], self.plan.rows[t.row]);
        let size = (c.end - c.start, r.end - r.start);
        Move { from: Place::Network, at: (c.margin(), r.margin()), to: Place::Global, to_at: (c.start, r.start), size }
    }

    /// Before tile `t` runs: its old state into `prev` (the network's previous-state textures),
    /// recorded into `encoder`; with the state in host memory, staged through the upload buffer
    /// (mapped here, which waits for the GPU).
    pub(super) fn copy_in(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        graph: &Graph,
        t: &TileAt,
        prev: &Network,
    ) -> Result<()> {
        let moves = self.copy_in_moves(t);
        match &self.store {
            Store::Gpu { .. } => {
                for m in moves.iter().flatten() {
                    self.record_move(encoder, graph, m, prev);
                }
            }
            Store::Host { global, above, left, upload, up, .. } => {
                map(device, upload, wgpu::MapMode::Write)?;
                {
                    let mut view = upload.get_mapped_range_mut(..).map_err(|e| Error::Gpu(format!("state staging: {e:?}")))?;
                    for m in moves.iter().flatten() {
                        for (k, &(_, l)) in graph.hidden.iter().enumerate() {
                            let src = match m.from {
                                Place::Global => &global[k],
                                Place::Above(i) => &above[i][k],
                                Place::Left => &left[k],
                                Place::Network => unreachable!("copy-ins read the kept state"),
                            };
                            let r = up[k];
                            let s = |v: u32| v >> l;
                            for z in 0..r.layers {
                                for y in 0..s(m.size.1) {
                                    let at = r.offset as usize
                                        + ((z * r.rows + s(m.to_at.1) + y) * r.pitch) as usize
                                        + s(m.to_at.0) as usize * src.texel;
                                    let row = src.row(z, s(m.at.1) + y, s(m.at.0), s(m.size.0));
                                    view.slice(at..at + row.len()).copy_from_slice(&src.data[row]);
                                }
                            }
                        }
                    }
                }
                upload.unmap();
                let (ew, eh) = self.plan.extent;
                for (k, &(_, l)) in graph.hidden.iter().enumerate() {
                    let r = up[k];
                    encoder.copy_buffer_to_texture(
                        wgpu::TexelCopyBufferInfo {
                            buffer: upload,
                            layout: wgpu::TexelCopyBufferLayout {
                                offset: r.offset,
                                bytes_per_row: Some(r.pitch),
                                rows_per_image: Some(r.rows),
                            },
                        },
                        texel_copy(prev.texture(k), (0, 0)),
                        wgpu::Extent3d { width: ew >> l, height: eh >> l, depth_or_array_layers: r.layers },
                    );
                }
            }
        }
        Ok(())
    }

    /// After tile `t` ran, recorded into the same encoder: on the GPU the band saves and the
    /// write-back of its interior from `new` (the network's new-state textures); with the state
    /// in host memory the copy of the interior into the readback buffer ([`Self::finish_tile`]
    /// saves the bands and writes it back). `history`: whether this frame reads old state (not a
    /// reset frame), which the bands serve.
    pub(super) fn record_write_back(&self, encoder: &mut wgpu::CommandEncoder, graph: &Graph, t: &TileAt, new: &Network, history: bool) {
        let back = self.write_back_move(t);
        match &self.store {
            Store::Gpu { .. } => {
                if history {
                    for m in self.band_moves(t).iter().flatten() {
                        self.record_move(encoder, graph, m, new);
                    }
                }
                self.record_move(encoder, graph, &back, new);
            }
            Store::Host { readback, down, .. } => {
                for (k, &(_, l)) in graph.hidden.iter().enumerate() {
                    let r = down[k];
                    encoder.copy_texture_to_buffer(
                        texel_copy(new.texture(k), (back.at.0 >> l, back.at.1 >> l)),
                        wgpu::TexelCopyBufferInfo {
                            buffer: readback,
                            layout: wgpu::TexelCopyBufferLayout {
                                offset: r.offset,
                                bytes_per_row: Some(r.pitch),
                                rows_per_image: Some(r.rows),
                            },
                        },
                        wgpu::Extent3d { width: back.size.0 >> l, height: back.size.1 >> l, depth_or_array_layers: r.layers },
                    );
                }
            }
        }
    }

    /// After tile `t`'s submit has finished, with the state in host memory: save the bands
    /// (where `history`) and write the interior's new state back from the readback buffer.
    pub(super) fn finish_tile(&mut self, device: &wgpu::Device, graph: &Graph, t: &TileAt, history: bool) -> Result<()> {
        let bands = if history { self.band_moves(t) } else { [None, None] };
        let back = self.write_back_move(t);
        let Store::Host { global, above, left, readback, down, .. } = &mut self.store else { return Ok(()) };
        for m in bands.into_iter().flatten() {
            for (k, &(_, l)) in graph.hidden.iter().enumerate() {
                let dst = match m.to {
                    Place::Above(i) => &mut above[i][k],
                    Place::Left => &mut left[k],
                    _ => unreachable!("bands are saved from the global state"),
                };
                let src = &global[k];
                let s = |v: u32| v >> l;
                for z in 0..src.layers() {
                    for y in 0..s(m.size.1) {
                        let from = src.row(z, s(m.at.1) + y, s(m.at.0), s(m.size.0));
                        let to = dst.row(z, s(m.to_at.1) + y, s(m.to_at.0), s(m.size.0));
                        dst.data[to].copy_from_slice(&src.data[from]);
                    }
                }
            }
        }
        map(device, readback, wgpu::MapMode::Read)?;
        {
            let view = readback.get_mapped_range(..).map_err(|e| Error::Gpu(format!("state readback: {e:?}")))?;
            for (k, &(_, l)) in graph.hidden.iter().enumerate() {
                let (r, dst) = (down[k], &mut global[k]);
                let s = |v: u32| v >> l;
                for z in 0..r.layers {
                    for y in 0..s(back.size.1) {
                        let to = dst.row(z, s(back.to_at.1) + y, s(back.to_at.0), s(back.size.0));
                        let at = r.offset as usize + ((z * r.rows + y) * r.pitch) as usize;
                        let n = to.len();
                        dst.data[to].copy_from_slice(&view[at..at + n]);
                    }
                }
            }
        }
        readback.unmap();
        Ok(())
    }

    /// Record a move between GPU textures, every block (`network`: the network's textures).
    fn record_move(&self, encoder: &mut wgpu::CommandEncoder, graph: &Graph, m: &Move, network: &Network) {
        let Store::Gpu { global, above, left } = &self.store else { unreachable!("GPU moves on the GPU store") };
        let texture = |p: Place, k: usize| -> &wgpu::Texture {
            match p {
                Place::Global => &global[k],
                Place::Above(i) => &above[i][k],
                Place::Left => &left[k],
                Place::Network => network.texture(k),
            }
        };
        for (k, &(_, l)) in graph.hidden.iter().enumerate() {
            let s = |(x, y): (u32, u32)| (x >> l, y >> l);
            copy(encoder, texture(m.from, k), s(m.at), texture(m.to, k), s(m.to_at), s(m.size));
        }
    }
}

/// One side of the network's state textures (`[block][0|1]`): the previous state (0) or the
/// new one (1); without motion both are the same texture.
pub(super) struct Network<'a> {
    pub(super) textures: &'a [[wgpu::Texture; 2]],
    pub(super) side: usize,
}

impl Network<'_> {
    fn texture(&self, block: usize) -> &wgpu::Texture {
        &self.textures[block][self.side]
    }
}

/// Map `buffer` and wait for it.
fn map(device: &wgpu::Device, buffer: &wgpu::Buffer, mode: wgpu::MapMode) -> Result<()> {
    let (tx, rx) = std::sync::mpsc::channel();
    buffer.map_async(mode, .., move |r| {
        let _ = tx.send(r);
    });
    device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| Error::Gpu(e.to_string()))?;
    rx.recv().map_err(|e| Error::Gpu(e.to_string()))?.map_err(|e| Error::Gpu(e.to_string()))
}

fn texel_copy(texture: &wgpu::Texture, (x, y): (u32, u32)) -> wgpu::TexelCopyTextureInfo<'_> {
    wgpu::TexelCopyTextureInfo { texture, mip_level: 0, origin: wgpu::Origin3d { x, y, z: 0 }, aspect: wgpu::TextureAspect::All }
}

/// Copy a `size` rectangle of every layer from `src` at `from` to `dst` at `to`.
fn copy(encoder: &mut wgpu::CommandEncoder, src: &wgpu::Texture, from: (u32, u32), dst: &wgpu::Texture, to: (u32, u32), size: (u32, u32)) {
    if size.0 == 0 || size.1 == 0 {
        return;
    }
    let at = |texture, (x, y): (u32, u32)| wgpu::TexelCopyTextureInfo {
        texture,
        mip_level: 0,
        origin: wgpu::Origin3d { x, y, z: 0 },
        aspect: wgpu::TextureAspect::All,
    };
    let layers = src.depth_or_array_layers();
    encoder.copy_texture_to_texture(
        at(src, from),
        at(dst, to),
        wgpu::Extent3d { width: size.0, height: size.1, depth_or_array_layers: layers },
    );
}

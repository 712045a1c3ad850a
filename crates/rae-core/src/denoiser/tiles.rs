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
    /// The hidden state kept for the whole frame between tiles, with its bands (0 untiled).
    pub state: u64,
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
            let plan = Self::tiled(arch, &graph, TilePlan::new(width, height, multiple, t)?, precision);
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
        let mut last = None;
        for tile in candidates {
            let plan = Self::tiled(arch, &graph, TilePlan::new(width, height, multiple, FrameTiles { tile, overlap })?, precision);
            let fits = plan
                .tiles
                .as_ref()
                .is_some_and(|t| t.extent.0 <= max_side && t.extent.1 <= max_side && t.extent.0 as u64 * t.extent.1 as u64 <= max_pixels);
            if fits && plan.total() <= cap {
                return Ok(plan);
            }
            last = Some(plan);
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
            convs: conv_bytes_bound(arch, pw, ph),
            io: io_bytes(arch, width as u64 * height as u64, width as u64 * height as u64),
            motion: if motion { motion_bytes(pw, ph, arch.levels(), true) } else { 0 },
        }
    }

    fn tiled(arch: &Arch, graph: &Graph, plan: TilePlan, precision: Precision) -> Self {
        let (ew, eh) = plan.extent;
        let (iw, ih) = plan.max_interior();
        let (mx, my) = plan.margins();
        let state: u64 = graph
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
        MemoryPlan {
            activations: activation_bytes(graph, ew, eh, precision, false),
            state,
            convs: conv_bytes_bound(arch, ew, eh),
            io: io_bytes(arch, ew as u64 * eh as u64, iw as u64 * ih as u64),
            motion: 0,
            tiles: Some(plan),
        }
    }
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
    /// `[block]`: the state of the whole padded frame.
    global: Vec<wgpu::Texture>,
    /// `[row parity][block]`: the old state of the band above a row's interiors.
    above: [Vec<wgpu::Texture>; 2],
    /// `[block]`: the old state of the next tile's left margin.
    left: Vec<wgpu::Texture>,
    /// Each tile's prep and output uniforms, row by row.
    pub(super) prep_params: Vec<wgpu::Buffer>,
    pub(super) output_params: Vec<wgpu::Buffer>,
    pub(super) bytes: u64,
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
    pub(super) fn new(device: &wgpu::Device, plan: TilePlan, graph: &Graph, arch: &Arch, precision: Precision) -> Self {
        let mut bytes = 0u64;
        let mut make = |label: &str, w: u32, h: u32, c: usize| {
            bytes += w as u64 * h as u64 * blocks(c) as u64 * precision.texel_bytes();
            build::texture(device, label, w.max(1), h.max(1), blocks(c), precision.format()).0
        };
        let (_, ih) = plan.max_interior();
        let (mx, my) = plan.margins();
        let global = graph.hidden.iter().map(|&(c, l)| make("frame state", plan.pwidth >> l, plan.pheight >> l, c)).collect();
        let band = |make: &mut dyn FnMut(&str, u32, u32, usize) -> wgpu::Texture, w: u32, h: u32, used: bool| -> Vec<wgpu::Texture> {
            if !used {
                return Vec::new();
            }
            graph.hidden.iter().map(|&(c, l)| make("state band", w >> l, h >> l, c)).collect()
        };
        let rows = plan.rows.len() > 1;
        let above = [band(&mut make, plan.pwidth, my, rows), band(&mut make, plan.pwidth, my, rows)];
        let left = band(&mut make, mx, ih, plan.columns.len() > 1);
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
            prep_params.push(build::create_init(device, "tile prep params", bytemuck::bytes_of(&prep), wgpu::BufferUsages::UNIFORM));
            output_params.push(build::create_init(device, "tile output params", bytemuck::bytes_of(&output), wgpu::BufferUsages::UNIFORM));
        }
        Tiles { plan, global, above, left, prep_params, output_params, bytes }
    }

    /// Record the copy of the old state under tile `t`'s extent into `prev` (the network's
    /// previous-state textures), the bands over the global state where tiles before it have
    /// written the new one.
    pub(super) fn copy_in(&self, encoder: &mut wgpu::CommandEncoder, graph: &Graph, t: &TileAt, prev: &[&wgpu::Texture]) {
        let (ew, eh) = self.plan.extent;
        for (k, &(_, l)) in graph.hidden.iter().enumerate() {
            let s = |v: u32| v >> l;
            copy(encoder, &self.global[k], (s(t.x0), s(t.y0)), prev[k], (0, 0), (s(ew), s(eh)));
            if t.row > 0 {
                // Rows above the interior: the row above's, saved before it wrote.
                copy(encoder, &self.above[t.row % 2][k], (s(t.x0), 0), prev[k], (0, 0), (s(ew), s(t.iy0 - t.y0)));
            }
            if t.column > 0 {
                // Columns left of the interior, in the interior's rows: the left tile's.
                let rows = self.plan.rows[t.row].end - self.plan.rows[t.row].start;
                copy(encoder, &self.left[k], (0, 0), prev[k], (0, s(t.iy0 - t.y0)), (s(t.ix0 - t.x0), s(rows)));
            }
        }
    }

    /// Record, before tile `t` writes its new state back, the saves of the old state its
    /// successors will read: at a row's first tile the next row's top margin, and before each
    /// tile the next tile's left margin.
    pub(super) fn save_bands(&self, encoder: &mut wgpu::CommandEncoder, graph: &Graph, t: &TileAt) {
        let plan = &self.plan;
        for (k, &(_, l)) in graph.hidden.iter().enumerate() {
            let s = |v: u32| v >> l;
            if t.column == 0
                && let Some(next) = plan.rows.get(t.row + 1)
            {
                let band = &self.above[(t.row + 1) % 2][k];
                copy(encoder, &self.global[k], (0, s(next.extent_start)), band, (0, 0), (s(plan.pwidth), s(next.margin())));
            }
            if let Some(next) = plan.columns.get(t.column + 1) {
                let r = plan.rows[t.row];
                let at = (s(next.extent_start), s(r.start));
                copy(encoder, &self.global[k], at, &self.left[k], (0, 0), (s(next.margin()), s(r.end - r.start)));
            }
        }
    }

    /// Record the write-back of tile `t`'s new state (its interior of `new`) into the global
    /// state.
    pub(super) fn write_back(&self, encoder: &mut wgpu::CommandEncoder, graph: &Graph, t: &TileAt, new: &[&wgpu::Texture]) {
        let (c, r) = (self.plan.columns[t.column], self.plan.rows[t.row]);
        for (k, &(_, l)) in graph.hidden.iter().enumerate() {
            let s = |v: u32| v >> l;
            let from = (s(c.start - c.extent_start), s(r.start - r.extent_start));
            copy(encoder, new[k], from, &self.global[k], (s(c.start), s(r.start)), (s(c.end - c.start), s(r.end - r.start)));
        }
    }
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

//! Planning frames in tiles: where each tile's interior and extent lie ([`TilePlan`]), and what
//! a plan holds ([`MemoryPlan`]): the whole frame where it fits the cap, else the largest tiles.

use super::*;

/// The overlap a tile's extent takes around its interior, in pixels of the frame, when the
/// caller does not choose one ([`FrameTiles`]). Chosen by measurement (`examples/tile_seams.rs`,
/// `docs/PERF.md`): with the model shipped then a tiled frame differs from the whole one by
/// 1.1-1.8e-4 of its mean value on average, and by up to 0.7 of it at the worst pixel by a seam;
/// 96 pixels cut that to 2.2-3.5e-5 and 0.07, but the state and the larger smallest tile no
/// longer fit 4K in 1 GiB on the GPU. A model that reaches further fails the engine's tiles test
/// (`docs/MODELS.md`, stage 12).
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
    // Each interior with the overlap on its inner sides (a tile at the frame's edge needs none
    // there), the largest of them: two tiles need one overlap each, not two.
    let extent = starts
        .windows(2)
        .enumerate()
        .map(|(i, w)| w[1] - w[0] + overlap * (u32::from(i > 0) + u32::from(i + 2 < starts.len())))
        .max()
        .unwrap_or(p)
        .min(p);
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
    /// The reprojection's buffers and the output's accumulation (frames with motion; untiled
    /// only): a bound, the accumulation counted whether or not it is asked for.
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
            motion: if motion { motion_bytes(pw, ph, arch.levels(), true) + accumulate_bytes(width, height) } else { 0 },
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
pub(super) struct StagedRegion {
    pub(super) offset: u64,
    /// Bytes per row, padded to `COPY_BYTES_PER_ROW_ALIGNMENT`.
    pub(super) pitch: u32,
    pub(super) rows: u32,
    pub(super) layers: u32,
}

impl StagedRegion {
    pub(super) fn bytes(&self) -> u64 {
        self.pitch as u64 * self.rows as u64 * self.layers as u64
    }
}

pub(super) fn state_layout(graph: &Graph, w: u32, h: u32, precision: Precision) -> Vec<StagedRegion> {
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

/// One tile in a frame: its place and the rectangles it reads and writes, in frame pixels.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TileAt {
    pub(crate) row: usize,
    pub(crate) column: usize,
    /// The extent's origin.
    pub(crate) x0: u32,
    pub(crate) y0: u32,
    /// The extent's pixels inside the frame (the inputs uploaded).
    pub(crate) valid: (u32, u32),
    /// The interior's pixels inside the frame (the output kept), and its origin.
    pub(crate) ix0: u32,
    pub(crate) iy0: u32,
    pub(crate) interior: (u32, u32),
}

impl TilePlan {
    /// Every tile, row by row.
    pub(crate) fn tiles(&self) -> impl Iterator<Item = TileAt> + '_ {
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

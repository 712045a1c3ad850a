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

mod plan;

pub use plan::*;

use super::*;

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
        let (ew, eh) = plan.extent;
        let mut prep_params = Vec::new();
        let mut output_params = Vec::new();
        for t in plan.tiles() {
            let prep = PrepParams { width: t.valid.0, height: t.valid.1, pwidth: ew, pheight: eh };
            let output = OutputParams::new(arch, (t.ix0 - t.x0, t.iy0 - t.y0), t.interior, t.valid.0);
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
                host::map_and_wait(device, upload, wgpu::MapMode::Write)?;
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
        host::map_and_wait(device, readback, wgpu::MapMode::Read)?;
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

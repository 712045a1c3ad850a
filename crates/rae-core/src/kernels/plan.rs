//! A network's convolutions planned on one device ([`ConvPlan`]): each conv's tile, weight memory
//! and source access, its pipeline, its packed weights and parameters, its dispatches.

use super::*;
use crate::graph::Read;

/// Full-resolution f32 texture layers split-K's partial sums may take ([`ConvPlan::new`]).
pub const PARTIAL_LAYERS: u64 = 4;

/// The most bytes one staged conv output may take ([`Kernels::stage_outputs`]): 32 channels
/// of 512 x 512 in f32, so that a 1080p frame stages its small levels only rather than hold
/// a 267 MB buffer for its first.
pub const STAGING_BYTES: u64 = 32 << 20;

/// One convolution to plan: its size, sources, weights and kernel variant.
#[derive(Debug, Clone, Copy)]
pub struct ConvSpec<'a> {
    /// Module name, for errors and labels.
    pub name: &'a str,
    /// Output width (the convolution's resolution).
    pub width: u32,
    /// Output height.
    pub height: u32,
    /// Channels of source a (and how it is read).
    pub ca: usize,
    /// Channels of source b (0: none).
    pub cb: usize,
    /// Output channels.
    pub cout: usize,
    /// PyTorch layout `[cout][ca + cb][3][3]`.
    pub weight: &'a [f32],
    /// `[cout]`.
    pub bias: &'a [f32],
    /// Read modes of a and b.
    pub read_a: Read,
    /// Read mode of b (Direct when absent).
    pub read_b: Read,
    /// LeakyReLU after the conv.
    pub leaky: bool,
    /// LeakyReLU slope.
    pub slope: f32,
    /// Source b is a recurrent hidden state: a reset frame reads none of its channels.
    pub b_is_hidden: bool,
    /// The output is read max-pooled 2x2 (an encoder block's last conv, [`crate::graph::Pool`]):
    /// the conv writes the pooled value itself where its tile allows ([`ConvPlan::pools`]).
    pub pooled: bool,
    /// Where source a, source b, the output and the pooled output are carved into an arena's
    /// cells ([`Carve`]; [`Carve::NONE`]: as bound).
    pub carves: [Carve; 4],
}

/// One dispatch: `count` consecutive output-block groups (workgroup z), their parameter and
/// weight offsets.
#[derive(Debug, Clone, Copy)]
struct Group {
    /// Offsets into the parameter buffer: normal frame, reset frame.
    params: [u32; 2],
    /// Offset into the weight buffer.
    weights: u32,
    /// Groups in this dispatch (their chunks follow each other, `group_stride` apart).
    count: u32,
}

/// Append a dispatch's two parameter blocks (normal frame, then reset frame, whose recurrent
/// conv reads no hidden-state blocks), each at an `align`-byte offset; returns the offsets.
fn push_params(params: &mut Vec<u8>, align: usize, s: &ConvSpec, ob0: u32, group_stride: u32, weight_texel: u32, pool: bool) -> [u32; 2] {
    let (cin4_a, cin4_b) = (blocks(s.ca), blocks(s.cb));
    std::array::from_fn(|reset| {
        let p = ConvParams {
            width: s.width,
            height: s.height,
            cin4_a,
            cin4_b: if reset == 1 && s.b_is_hidden { 0 } else { cin4_b },
            cin4_total: cin4_a + cin4_b,
            ob0,
            cout4: blocks(s.cout),
            slope: s.slope,
            group_stride,
            weight_texel,
            pool_out: pool as u32,
            _pad: 0,
            carve_a: s.carves[0],
            carve_b: s.carves[1],
            carve_dst: s.carves[2],
            carve_pool: s.carves[3],
        };
        params.resize(params.len().next_multiple_of(align), 0);
        let at = params.len() as u32;
        params.extend_from_slice(bytemuck::bytes_of(&p));
        at
    })
}

/// A planned convolution: its pipeline, workgroups and groups, and split-K's second pass.
struct Planned {
    pipeline: wgpu::ComputePipeline,
    /// How the conv reads its sources (its bind groups' layout).
    sources: SourceAccess,
    /// Where it reads its weights (its bind groups' layout and binding size).
    memory: WeightMemory,
    /// It writes its output max-pooled too ([`ConvPlan::pools`]).
    pool: bool,
    /// Its output's size (width, height, layers) where it writes it into the buffer to copy.
    staged: Option<[u32; 3]>,
    workgroups: (u32, u32),
    /// Parts per group (workgroup z runs over groups x parts).
    split: u32,
    groups: Vec<Group>,
    /// The reduce pipeline and its workgroups, when split.
    reduce: Option<(wgpu::ComputePipeline, [u32; 3])>,
}

/// A conv planned, before its pipelines are made ([`ConvPlan::with_choices`]).
struct Pending {
    variant: ConvVariant,
    /// It writes its output max-pooled too.
    pool: bool,
    workgroups: (u32, u32),
    split: u32,
    groups: Vec<Group>,
    /// Split-K's reduce pass: its variant and workgroups.
    reduce: Option<(ConvVariant, [u32; 3])>,
    /// Its output's size where it is staged ([`Planned::staged`]).
    staged: Option<[u32; 3]>,
    /// The tile it runs (after the level-height and weight-chunk limits).
    tile: Tile,
}

/// Refuses tiles with weights across the lanes on a device whose subgroups are too narrow.
fn check_subgroups(device: &wgpu::Device, tiles: &[Tile]) -> crate::Result<()> {
    let narrow = |t: &Tile| match t.method {
        Method::Lanes => (!lanes_supported(device)).then_some(("weights across lanes", 8)),
        Method::WinogradLanes | Method::Winograd4Lanes => {
            (!winograd_lanes_supported(device)).then_some(("Winograd weights across lanes", 8))
        }
        _ => None,
    };
    let Some((t, (what, lanes))) = tiles.iter().find_map(|t| narrow(t).map(|n| (t, n))) else { return Ok(()) };
    let info = device.adapter_info();
    let has = if device.features().contains(wgpu::Features::SUBGROUP) {
        format!("{} to {}", info.subgroup_min_size, info.subgroup_max_size)
    } else {
        "none".to_string()
    };
    Err(crate::Error::UnsupportedTile {
        tile: t.to_string(),
        reason: format!("{what} need subgroups of at least {lanes} lanes; {} has {has}", info.name),
    })
}

/// A plan's buffers as its convs are packed into them, one conv after another.
struct Packing {
    /// Offset alignment of every dispatch's parameters and weights: parameter blocks are
    /// uniform, and weights may be either, so every offset suits both.
    align: usize,
    params: Vec<u8>,
    weights: Vec<u8>,
    /// The lanes module's convs' weights, texel by texel (the weight texture).
    weight_texels: Vec<[f32; 4]>,
    /// The largest storage-weight conv's bytes (its binding's size).
    binding: u64,
    /// Bytes of the partial-sum (or staging) buffer.
    partial: u64,
    /// Split-K's partial sums may take as much memory as 16 channels at full resolution in f32
    /// ([`PARTIAL_LAYERS`] texture layers): enough to split the deep levels, where splitting
    /// pays, while a split full-resolution conv (gigabytes at 1080p) is split less or not at all.
    partial_budget: u64,
    /// The F(4x4) convs stage their outputs ([`Kernels::stage_outputs`]).
    staging: bool,
}

impl Packing {
    fn new(device: &wgpu::Device, specs: &[ConvSpec], staging: bool) -> Self {
        let limits = device.limits();
        Packing {
            align: limits.min_uniform_buffer_offset_alignment.max(limits.min_storage_buffer_offset_alignment) as usize,
            params: Vec::new(),
            weights: Vec::new(),
            weight_texels: Vec::new(),
            binding: 0,
            partial: 0,
            partial_budget: specs.iter().map(|s| s.width as u64 * s.height as u64).max().unwrap_or(0) * 16 * PARTIAL_LAYERS,
            staging,
        }
    }

    /// A matrix-unit conv ([`Method::is_mma`]): its weights as f16 tiles, one dispatch.
    fn mma_conv(
        &mut self,
        device: &wgpu::Device,
        s: &ConvSpec,
        tile: Tile,
        access: SourceAccess,
        memory: WeightMemory,
    ) -> crate::Result<Pending> {
        let unsupported = |reason: String| crate::Error::UnsupportedTile { tile: tile.to_string(), reason };
        if memory != WeightMemory::Storage {
            return Err(unsupported("Mma tiles read their weights from a storage buffer (weights memory `storage`)".into()));
        }
        if !device.features().contains(wgpu::Features::SHADER_F16) {
            return Err(unsupported(format!("Mma tiles need SHADER_F16, which {} lacks", device.adapter_info().name)));
        }
        let split = tile.method.is_mma_split();
        let shared = device.limits().max_compute_workgroup_storage_size;
        if shared < MMA_WORKGROUP_BYTES {
            return Err(unsupported(format!("{tile} uses {MMA_WORKGROUP_BYTES} bytes of workgroup memory; the device allows {shared}")));
        }
        let cin4 = blocks(s.ca) + blocks(s.cb);
        // Tiles of 16 output channels, at most as many per group as the conv has.
        let tiles16 = s.cout.div_ceil(16) as u32;
        let nt = (tile.blocks / 4).clamp(1, tiles16);
        // The hi tiles, with `split` their remainders, then the bias's two halves.
        let stride = cin4.div_ceil(4) * 9 * nt * 256 * (1 + split as u32) + 32 * nt;
        let group_count = tiles16.div_ceil(nt);
        self.binding = self.binding.max(group_count as u64 * stride as u64 * 2);
        let mut group = Group { params: [0; 2], weights: 0, count: group_count };
        group.params = push_params(&mut self.params, self.align, s, 0, stride, 0, false);
        self.weights.resize(self.weights.len().next_multiple_of(self.align), 0);
        group.weights = self.weights.len() as u32;
        for g in 0..group_count {
            let packed = pack_mma(s, (16 * nt * g) as usize, nt as usize, split);
            debug_assert_eq!(packed.len() as u32, stride);
            self.weights.extend_from_slice(bytemuck::cast_slice(&packed));
        }
        let variant = ConvVariant {
            read_a: s.read_a,
            read_b: s.read_b,
            source_b: s.cb > 0,
            leaky: s.leaky,
            ob: nt,
            rows: 1,
            cols: 1,
            group_x: WORKGROUP,
            method: tile.method,
            split: 1,
            reduce: false,
            sources: access,
            pool: false,
            memory,
            staged: false,
            carve_a: s.carves[0].is_carved(),
            carve_b: s.carves[1].is_carved(),
        };
        // Workgroups of 4 rows (conv3x3_mma.wgsl's ROWS) x 64 or 32 pixels (16 MT).
        let pixels = if split { MMA_SPLIT_PIXELS } else { MMA_PIXELS };
        Ok(Pending {
            variant,
            pool: false,
            workgroups: (s.width.div_ceil(pixels), s.height.div_ceil(4)),
            split: 1,
            groups: vec![group],
            reduce: None,
            staged: None,
            tile: Tile { blocks: 4 * nt, ..tile },
        })
    }

    /// A conv of conv3x3.wgsl's methods: its tile fitted to the conv, its weights in groups of
    /// output blocks (in the weight buffer, or in the weight texture for the lanes module's
    /// tiles), its parameters per dispatch, and split-K's reduce pass.
    fn conv(&mut self, s: &ConvSpec, tile: Tile, access: SourceAccess, memory: WeightMemory) -> crate::Result<Pending> {
        let cin4 = blocks(s.ca) + blocks(s.cb);
        let taps = tile.taps();
        // Two columns only where the level is wider than one (Winograd tiles are 2 wide).
        let cols = if s.width > 1 || tile.method.is_winograd() { tile.cols } else { 1 };
        // The tiles of the lanes module read their weights from the weight texture
        // (TEXEL_WEIGHTS), which takes no chunk.
        let texels = tile.method.is_winograd_lanes() || (tile.method == Method::Lanes && cols > 1);
        // Their pipelines then all take one weight memory, which they do not read: a conv
        // on a level of uniform weights shares the pipeline of its kind on a level of
        // storage ones (each an LLVM compile of seconds on lavapipe).
        let memory = if texels { WeightMemory::Storage } else { memory };
        let ob = match memory {
            _ if texels => 4,
            WeightMemory::Uniform => blocks_per_invocation(cin4, taps).ok_or_else(|| crate::Error::Arch {
                origin: s.name.to_string(),
                reason: format!(
                    "{} input channels ({cin4} blocks of 4, padded per source) exceed one 64 KiB weight chunk (at most {} blocks with {} tiles)",
                    s.ca + s.cb,
                    (WEIGHT_CHUNK - 1) / (taps * 4),
                    if tile.method.is_winograd() { "Winograd" } else { "direct" }
                ),
            })?,
            WeightMemory::Storage => 4,
        };
        let cout4 = blocks(s.cout);
        // No more blocks than the conv has output blocks to fill: the 3-channel output convs
        // would compute a second, discarded tile with OB = 2 (OB stays 1, 2 or 4).
        let mut ob = ob.min(tile.blocks);
        while ob > 1 && ob / 2 >= cout4 {
            ob /= 2;
        }
        // F(4x4, 3x3) computes whole 4x4 output tiles.
        let rows = rows_per_invocation(s.height, tile.rows).max(if tile.method == Method::Winograd4Lanes { 4 } else { 1 });
        // Split (direct tiles only) no further than one input block per part, nor beyond the
        // partial-sum budget.
        let part_bytes = cout4 as u64 * s.width as u64 * s.height as u64 * 16;
        let split = if !tile.method.is_winograd() { tile.split.min(cin4).min((self.partial_budget / part_bytes) as u32).max(1) } else { 1 };
        let used_tile = Tile { rows, blocks: ob, cols, group_x: tile.group_x, method: tile.method, split };
        // The conv pools its own output where each invocation holds whole 2x2 windows (its
        // pipeline has the pooled store wherever it can, ConvVariant::pool).
        let can_pool =
            (tile.method == Method::Lanes && cols == 2 && rows.is_multiple_of(2) && split == 1) || tile.method.is_winograd_lanes();
        let pool = s.pooled && can_pool;
        // Staged where asked, the row pitch a copy's (256 bytes), the buffer within bounds.
        let staged = (self.staging
            && tile.method == Method::Winograd4Lanes
            && (s.width * 16).is_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
            && part_bytes <= STAGING_BYTES)
            .then_some([s.width, s.height, cout4]);
        if staged.is_some() {
            self.partial = self.partial.max(part_bytes);
        }
        let variant = ConvVariant {
            read_a: s.read_a,
            read_b: s.read_b,
            source_b: s.cb > 0,
            leaky: s.leaky,
            ob,
            rows,
            cols,
            group_x: tile.group_x,
            method: tile.method,
            split,
            reduce: false,
            sources: access,
            pool: can_pool,
            memory,
            staged: staged.is_some(),
            carve_a: s.carves[0].is_carved(),
            carve_b: s.carves[1].is_carved(),
        };
        // Split-K's partial sums: one buffer for the largest split conv, which every split
        // conv overwrites in turn (the reduce of one runs before the next conv starts).
        if split > 1 {
            self.partial = self.partial.max(split as u64 * cout4 as u64 * s.width as u64 * s.height as u64 * 16);
        }
        // Groups of `ob` output blocks, as many per dispatch as fit one chunk (workgroup z).
        let stride = (cin4 * taps * 4 + 1) * ob;
        let group_count = cout4.div_ceil(ob);
        let per_dispatch = match memory {
            _ if texels => group_count,
            WeightMemory::Uniform => (WEIGHT_CHUNK / stride).min(group_count),
            WeightMemory::Storage => group_count,
        };
        if memory == WeightMemory::Storage && !texels {
            self.binding = self.binding.max(per_dispatch as u64 * stride as u64 * 16);
        }
        let mut groups = Vec::new();
        for first in (0..group_count).step_by(per_dispatch as usize) {
            let count = per_dispatch.min(group_count - first);
            let mut group = Group { params: [0; 2], weights: 0, count };
            group.params = push_params(&mut self.params, self.align, s, first * ob, stride, self.weight_texels.len() as u32, pool);
            if !texels {
                self.weights.resize(self.weights.len().next_multiple_of(self.align), 0);
                group.weights = self.weights.len() as u32;
            }
            for g in first..first + count {
                let chunk = pack_group(s, (g * ob) as usize, ob as usize, tile.method);
                debug_assert_eq!(chunk.len() as u32, stride);
                if texels {
                    self.weight_texels.extend_from_slice(&chunk);
                } else {
                    self.weights.extend_from_slice(bytemuck::cast_slice(&chunk));
                }
            }
            groups.push(group);
        }
        // The reduce pipeline depends on the activation and the part count only.
        let reduce_variant = ConvVariant {
            read_a: Read::Direct,
            read_b: Read::Direct,
            source_b: true,
            ob: 1,
            rows: 1,
            cols: 1,
            group_x: WORKGROUP,
            method: Method::Direct,
            reduce: true,
            pool: false,
            staged: false,
            ..variant
        };
        let reduce = (split > 1).then_some((reduce_variant, [s.width.div_ceil(8), s.height.div_ceil(8), cout4]));
        Ok(Pending {
            variant,
            pool,
            workgroups: (s.width.div_ceil(cols).div_ceil(tile.group_x), s.height.div_ceil(rows).div_ceil(tile.group_y())),
            split,
            groups,
            reduce,
            staged,
            tile: used_tile,
        })
    }

    /// The plan of `convs`, which run `tiles`: its buffers and weight texture made and filled.
    fn upload(mut self, device: &wgpu::Device, queue: &wgpu::Queue, convs: Vec<Planned>, tiles: Vec<Tile>) -> crate::Result<ConvPlan> {
        use wgpu::util::DeviceExt;
        // Every binding spans a whole chunk (or the largest storage conv) past its offset.
        let weight_binding = [WEIGHT_CHUNK_BYTES, self.binding.next_multiple_of(16).max(16)];
        let end = convs.iter().flat_map(|c| c.groups.iter().map(|g| g.weights as u64 + weight_binding[c.memory as usize])).max();
        self.weights.resize(end.unwrap_or(0) as usize, 0);
        self.params.resize(self.params.len().next_multiple_of(16), 0);
        let init = |label, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
        };
        let weight_usage = convs
            .iter()
            .map(|c| match c.memory {
                WeightMemory::Uniform => wgpu::BufferUsages::UNIFORM,
                WeightMemory::Storage => wgpu::BufferUsages::STORAGE,
            })
            .fold(wgpu::BufferUsages::empty(), |a, b| a | b);
        // A buffer past the device's limits would be created invalid, and filling it panics.
        let limits = device.limits();
        let (bytes, max_bytes) = (self.weights.len() as u64, limits.max_buffer_size);
        let (binding, max_binding) = (weight_binding[1], limits.max_storage_buffer_binding_size);
        if bytes > max_bytes || (weight_usage.contains(wgpu::BufferUsages::STORAGE) && binding > max_binding) {
            return Err(crate::Error::GpuBuffer {
                buffer: "conv weights",
                reason: format!(
                    "{bytes} bytes, {binding} bytes a storage binding: the device allows {max_bytes} bytes a buffer and {max_binding} a storage binding"
                ),
            });
        }
        // The weight texture: rows of WEIGHT_TEXELS_WIDTH texels (1 x 1 when no conv reads it).
        let (tex_w, tex_h) = if self.weight_texels.is_empty() {
            (1, 1)
        } else {
            (WEIGHT_TEXELS_WIDTH, (self.weight_texels.len() as u32).div_ceil(WEIGHT_TEXELS_WIDTH))
        };
        if tex_h > device.limits().max_texture_dimension_2d {
            return Err(crate::Error::UnsupportedTile {
                tile: Method::Winograd4Lanes.entry_point().to_string(),
                reason: format!(
                    "its weights need a {tex_w} x {tex_h} texture; the device allows {}",
                    device.limits().max_texture_dimension_2d
                ),
            });
        }
        self.weight_texels.resize((tex_w * tex_h) as usize, [0.0; 4]);
        let weight_texture = device.create_texture_with_data(
            queue,
            &wgpu::TextureDescriptor {
                label: Some("conv weight texels"),
                size: wgpu::Extent3d { width: tex_w, height: tex_h, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba32Float,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::STORAGE_BINDING,
                view_formats: &[],
            },
            wgpu::util::TextureDataOrder::LayerMajor,
            bytemuck::cast_slice(&self.weight_texels),
        );
        Ok(ConvPlan {
            weight_texels: weight_texture.create_view(&Default::default()),
            weight_texels_bytes: weight_texture.size().width as u64 * weight_texture.size().height as u64 * 16,
            params: init("conv params", &self.params, wgpu::BufferUsages::UNIFORM),
            weights: init("conv weights", &self.weights, weight_usage),
            partial: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("conv partial sums"),
                // Never empty: every conv binds it, the 64-bit staged stores as one 32-byte word
                // at least (conv3x3_stage64.wgsl), where the conv does not use it.
                size: self.partial.max(32),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            weight_binding,
            sources: convs.iter().map(|c| c.sources).collect(),
            memories: convs.iter().map(|c| c.memory).collect(),
            convs,
            tiles,
        })
    }
}

/// Every convolution of a network, ready to dispatch: one uniform buffer of parameter blocks
/// and one buffer of weights (each dispatch's groups at an aligned offset, bound by dynamic
/// offset), and the pipeline and dispatches of each conv. Built once per [`crate::Denoiser`].
pub struct ConvPlan {
    params: wgpu::Buffer,
    weights: wgpu::Buffer,
    /// Split-K's partial sums, or the staged outputs ([`Kernels::stage_outputs`]; 16 bytes
    /// when no conv needs it). Each split or staged conv overwrites it in turn.
    partial: wgpu::Buffer,
    /// Binding 7: the weights of Winograd lanes convs ([`Method::is_winograd_lanes`]),
    /// [`WEIGHT_TEXELS_WIDTH`] texels a row (1 x 1 where the plan has none).
    weight_texels: wgpu::TextureView,
    /// Bytes of the weight texture.
    weight_texels_bytes: u64,
    /// Bytes of a weight binding, `[WeightMemory as usize]`: one chunk for uniform weights, the
    /// largest storage-weight conv for storage ones.
    weight_binding: [u64; 2],
    convs: Vec<Planned>,
    tiles: Vec<Tile>,
    sources: Vec<SourceAccess>,
    memories: Vec<WeightMemory>,
}

impl ConvPlan {
    /// Pack and upload every conv's weights and parameters, conv `i` with at most `tiles[i]`
    /// (one tile for all when `tiles` has one entry; a split is capped so that the partial sums
    /// fit [`PARTIAL_LAYERS`] layers at the largest conv's resolution); fails when a conv is too
    /// wide for one uniform weight chunk. Every conv reads its sources as `kernels` does by
    /// default ([`Kernels::source_access`]).
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        kernels: &mut Kernels,
        specs: &[ConvSpec],
        tiles: &[Tile],
    ) -> crate::Result<Self> {
        let sources = kernels.sources;
        Self::with_sources(device, queue, kernels, specs, tiles, &[sources])
    }

    /// [`ConvPlan::new`] with conv `i` reading its sources as `sources[i]` says (one entry: all
    /// alike), as tuning picks them where both kinds run ([`crate::Denoiser`]).
    pub fn with_sources(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        kernels: &mut Kernels,
        specs: &[ConvSpec],
        tiles: &[Tile],
        sources: &[SourceAccess],
    ) -> crate::Result<Self> {
        let memory = kernels.memory;
        Self::with_choices(device, queue, kernels, specs, tiles, sources, &[memory])
    }

    /// [`ConvPlan::with_sources`] with conv `i` reading its weights from `memories[i]` (one
    /// entry: all alike), as [`WeightMemory::for_conv`] picks them by level on CPU drivers.
    pub fn with_choices(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        kernels: &mut Kernels,
        specs: &[ConvSpec],
        tiles: &[Tile],
        sources: &[SourceAccess],
        memories: &[WeightMemory],
    ) -> crate::Result<Self> {
        assert!(tiles.len() == 1 || tiles.len() == specs.len(), "one tile, or one per conv");
        assert!(sources.len() == 1 || sources.len() == specs.len(), "one source access, or one per conv");
        assert!(memories.len() == 1 || memories.len() == specs.len(), "one weight memory, or one per conv");
        check_subgroups(device, tiles)?;
        let mut packing = Packing::new(device, specs, kernels.staging);
        let pending = specs
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let (tile, access, memory) = (per_conv(tiles, i), per_conv(sources, i), per_conv(memories, i));
                if tile.method.is_mma() { packing.mma_conv(device, s, tile, access, memory) } else { packing.conv(s, tile, access, memory) }
            })
            .collect::<crate::Result<Vec<Pending>>>()?;
        // Every pipeline the plan needs, made side by side, then the convs' dispatches.
        let variants: Vec<ConvVariant> = pending.iter().flat_map(|p| std::iter::once(p.variant).chain(p.reduce.map(|r| r.0))).collect();
        kernels.prepare(device, &variants);
        let tiles = pending.iter().map(|p| p.tile).collect();
        let convs = pending
            .into_iter()
            .map(|p| Planned {
                pipeline: kernels.conv(device, p.variant),
                sources: p.variant.sources,
                memory: p.variant.memory,
                pool: p.pool,
                staged: p.staged,
                workgroups: p.workgroups,
                split: p.split,
                groups: p.groups,
                reduce: p.reduce.map(|(v, n)| (kernels.conv(device, v), n)),
            })
            .collect();
        packing.upload(device, queue, convs, tiles)
    }

    /// The tile each conv runs with (after the level-height and weight-chunk limits).
    pub fn tiles(&self) -> &[Tile] {
        &self.tiles
    }

    /// How each conv reads its sources.
    pub fn sources(&self) -> &[SourceAccess] {
        &self.sources
    }

    /// Where each conv reads its weights.
    pub fn memories(&self) -> &[WeightMemory] {
        &self.memories
    }

    /// Bytes of the weight, parameter and partial-sum buffers.
    pub fn bytes(&self) -> u64 {
        self.params.size() + self.weights.size() + self.partial.size() + self.weight_texels_bytes
    }

    /// Whether conv `i` writes its output max-pooled 2x2 too (conv3x3.wgsl's `pools`), so that
    /// the pool pass after it is not run: a conv whose [`ConvSpec::pooled`] is set, with a tile
    /// that can pool ([`ConvVariant::pool`]: two-column lanes tiles of an even number of rows,
    /// unsplit, and the Winograd lanes tiles). Its bind group takes the pooled value
    /// ([`ConvPlan::bind_group`]).
    pub fn pools(&self, i: usize) -> bool {
        self.convs[i].pool
    }

    /// Whether conv `i` writes its output into the plan's buffer ([`Kernels::stage_outputs`]):
    /// after [`ConvPlan::record`] the caller ends the pass and records this copy into the texture
    /// bound as the conv's output.
    pub fn staged(&self, i: usize) -> bool {
        self.convs[i].staged.is_some()
    }

    /// Copy conv `i`'s staged output into `dst`, its output texture, channel block `j` to
    /// the texel and layer `at[j]` (its cell where the output is carved; nothing where the
    /// conv is not staged). Consecutive layers from one corner go in one copy.
    pub fn copy_staged(&self, encoder: &mut wgpu::CommandEncoder, i: usize, dst: &wgpu::Texture, at: &[wgpu::Origin3d]) {
        let Some([width, height, layers]) = self.convs[i].staged else { return };
        let mut j = 0;
        while j < layers {
            let origin = at[j as usize];
            let run =
                (j + 1..layers).take_while(|&k| at[k as usize] == wgpu::Origin3d { z: origin.z + (k - j), ..origin }).count() as u32 + 1;
            encoder.copy_buffer_to_texture(
                wgpu::TexelCopyBufferInfo {
                    buffer: &self.partial,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: j as u64 * width as u64 * height as u64 * 16,
                        bytes_per_row: Some(width * 16),
                        rows_per_image: Some(height),
                    },
                },
                wgpu::TexelCopyTextureInfo { texture: dst, mip_level: 0, origin, aspect: wgpu::TextureAspect::All },
                wgpu::Extent3d { width, height, depth_or_array_layers: run },
            );
            j += run;
        }
    }

    /// Dispatches per frame.
    pub fn dispatches(&self) -> usize {
        self.convs.iter().map(|c| c.groups.len()).sum()
    }

    /// A bind group of conv `i` over the given textures (offsets are supplied per dispatch), in
    /// the layout of its source access and weight memory. `pooled` is the value its output
    /// max-pools into, where it has one; a conv that [pools](ConvPlan::pools) needs it, and one
    /// that does not binds `dst` there instead.
    #[allow(clippy::too_many_arguments)]
    pub fn bind_group(
        &self,
        device: &wgpu::Device,
        kernels: &Kernels,
        i: usize,
        a: &wgpu::TextureView,
        b: &wgpu::TextureView,
        dst: &wgpu::TextureView,
        pooled: Option<&wgpu::TextureView>,
    ) -> wgpu::BindGroup {
        // A conv that does not pool binds its output at binding 6 too (never written there: its
        // `pools` is false), or a texture of its own where the device wants one
        // ([`Kernels::pool_binding`]).
        let pooled = if self.pools(i) {
            pooled.unwrap_or_else(|| panic!("conv {i} pools its output: its bind group needs the pooled value"))
        } else {
            kernels.pool_binding(dst)
        };
        let buffer =
            |buffer, size| wgpu::BindingResource::Buffer(wgpu::BufferBinding { buffer, offset: 0, size: wgpu::BufferSize::new(size) });
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("conv3x3"),
            layout: kernels.conv_layout(self.convs[i].sources, self.convs[i].memory),
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: buffer(&self.params, std::mem::size_of::<ConvParams>() as u64) },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(a) },
                wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::TextureView(b) },
                wgpu::BindGroupEntry { binding: 3, resource: buffer(&self.weights, self.weight_binding[self.convs[i].memory as usize]) },
                wgpu::BindGroupEntry { binding: 4, resource: wgpu::BindingResource::TextureView(dst) },
                wgpu::BindGroupEntry { binding: 5, resource: self.partial.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 6, resource: wgpu::BindingResource::TextureView(pooled) },
                wgpu::BindGroupEntry { binding: 7, resource: wgpu::BindingResource::TextureView(&self.weight_texels) },
            ],
        })
    }

    /// Record conv `i` (every output-block group) into a pass.
    pub fn record(&self, pass: &mut wgpu::ComputePass, i: usize, reset: bool, group: &wgpu::BindGroup) {
        let c = &self.convs[i];
        pass.set_pipeline(&c.pipeline);
        for g in &c.groups {
            pass.set_bind_group(0, group, &[g.params[reset as usize], g.weights]);
            pass.dispatch_workgroups(c.workgroups.0, c.workgroups.1, g.count * c.split);
        }
        // Split-K: add the parts (the parameters of any group carry the conv's size).
        if let Some((pipeline, [x, y, z])) = &c.reduce {
            pass.set_pipeline(pipeline);
            pass.dispatch_workgroups(*x, *y, *z);
        }
    }

    /// Dispatch conv `i`'s pipelines (and its split-K reduce) with one workgroup each, on a
    /// reset frame's parameters: what makes a driver that compiles at first dispatch compile
    /// them, at no cost in arithmetic ([`crate::Denoiser::compile_backwards`]).
    pub fn record_compile(&self, pass: &mut wgpu::ComputePass, i: usize, group: &wgpu::BindGroup) {
        let c = &self.convs[i];
        pass.set_pipeline(&c.pipeline);
        if let Some(g) = c.groups.first() {
            pass.set_bind_group(0, group, &[g.params[1], g.weights]);
            pass.dispatch_workgroups(1, 1, 1);
        }
        if let Some((pipeline, _)) = &c.reduce {
            pass.set_pipeline(pipeline);
            pass.dispatch_workgroups(1, 1, 1);
        }
    }
}

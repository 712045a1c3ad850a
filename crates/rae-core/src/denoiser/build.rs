//! Building a [`Denoiser`]: frame size checks, activation textures, conv specs, tile choice
//! (fixed, by level, or tuned), the conv plan, bind groups of both parities, prep and output.

use super::*;

pub(super) static NEXT_ID: AtomicU64 = AtomicU64::new(1);

pub(super) fn texture(
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

/// The activation textures of a [`Denoiser`]: the arenas that the input, the temporaries and
/// the pooled values share by lifetime ([`Graph::place`]), and the hidden states, with the
/// views a conv binds.
pub(super) struct Activations {
    /// Every frame-local value's place in the arenas.
    placement: Placement,
    /// The arenas, full-resolution texture arrays.
    arenas: Vec<wgpu::Texture>,
    /// Per placed value, the view a pass binds: its own layers for a full-resolution value,
    /// the whole arena for a value carved into cells (the kernels find its cells,
    /// [`Carve`]).
    input_view: wgpu::TextureView,
    temp_views: Vec<wgpu::TextureView>,
    pooled_views: Vec<wgpu::TextureView>,
    /// `[block][0|1]`: the ping-pong pair of each recurrent block.
    hidden_textures: Vec<[wgpu::Texture; 2]>,
    hidden: Vec<[wgpu::TextureView; 2]>,
    /// The padded frame, which the cells' sizes follow.
    size: (u32, u32),
    /// Every texture above, for readback and accounting.
    textures: Vec<wgpu::Texture>,
    bytes: u64,
}

impl Activations {
    /// The textures at `pwidth` x `pheight`; the hidden state double-buffered only where
    /// `motion` (the warp gathers last frame's state into the texture this frame's is written
    /// to). Without motion each block's one texture holds last frame's state until its
    /// recurrent conv (`l2.0`) has read it, and its last conv (`l2.2`) writes the new state
    /// over it.
    fn new(device: &wgpu::Device, graph: &Graph, pwidth: u32, pheight: u32, precision: Precision, motion: bool) -> Self {
        let mut textures = Vec::new();
        let mut bytes = 0u64;
        let mut make = |label: &str, level: usize, layers: u32| {
            let (w, h) = (pwidth >> level, pheight >> level);
            bytes += w as u64 * h as u64 * layers as u64 * precision.texel_bytes();
            let (t, v) = texture(device, label, w, h, layers, precision.format());
            textures.push(t.clone());
            (t, v)
        };
        let placement = graph.place();
        let arenas: Vec<(wgpu::Texture, wgpu::TextureView)> =
            placement.arena_layers.iter().map(|&layers| make("arena", 0, layers)).collect();
        let pairs: Vec<[(wgpu::Texture, wgpu::TextureView); 2]> = graph
            .hidden
            .iter()
            .map(|&(c, level)| {
                let first = make("hidden", level, blocks(c));
                let second = if motion { make("hidden", level, blocks(c)) } else { first.clone() };
                [first, second]
            })
            .collect();
        let view = |p: &Place| {
            let (arena, whole) = &arenas[p.arena];
            if p.level > 0 {
                return whole.clone();
            }
            arena.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2Array),
                base_array_layer: p.first,
                array_layer_count: Some(p.blocks),
                ..Default::default()
            })
        };
        Activations {
            input_view: view(&placement.input),
            temp_views: placement.temps.iter().map(view).collect(),
            pooled_views: placement.pooled.iter().map(view).collect(),
            arenas: arenas.into_iter().map(|(t, _)| t).collect(),
            placement,
            hidden_textures: pairs.iter().map(|[a, b]| [a.0.clone(), b.0.clone()]).collect(),
            hidden: pairs.iter().map(|[a, b]| [a.1.clone(), b.1.clone()]).collect(),
            size: (pwidth, pheight),
            textures,
            bytes,
        }
    }

    /// The view of `v` on a frame of parity `parity`.
    pub(super) fn view(&self, v: Value, parity: usize) -> &wgpu::TextureView {
        match v {
            Value::Input => &self.input_view,
            Value::HiddenPrev(k) => &self.hidden[k][parity],
            Value::HiddenNew(k) => &self.hidden[k][1 - parity],
            Value::Temp(t) => &self.temp_views[t],
            Value::Pooled(k) => &self.pooled_views[k],
        }
    }

    /// Where the kernels find `v`'s cells in the view they bind ([`Self::view`]): carved for a
    /// value below full resolution in an arena, as bound otherwise.
    pub(super) fn carve(&self, v: Value) -> Carve {
        match self.placement.of(v) {
            Some(p) if p.level > 0 => Carve::of(&p, self.size.0, self.size.1),
            _ => Carve::NONE,
        }
    }

    /// The texture a conv writes `v` into (a temporary or a new hidden state), and where in it
    /// each of `v`'s `blocks` channel blocks starts (its cell in an arena).
    pub(super) fn written(&self, v: Value, parity: usize, blocks: u32) -> (wgpu::Texture, Vec<wgpu::Origin3d>) {
        let (texture, place) = match v {
            Value::HiddenNew(k) => (self.hidden_textures[k][1 - parity].clone(), None),
            Value::Temp(t) => {
                let p = self.placement.temps[t];
                (self.arenas[p.arena].clone(), Some(p))
            }
            _ => unreachable!("a conv writes a temporary or a new hidden state"),
        };
        let cells = (0..blocks)
            .map(|j| {
                let (x, y, z) = place.map_or((0, 0, j), |p| p.cell(j, self.size.0, self.size.1));
                wgpu::Origin3d { x, y, z }
            })
            .collect();
        (texture, cells)
    }

    /// The arena holding the packed input, and the input's place there.
    pub(super) fn input(&self) -> (wgpu::Texture, Place) {
        (self.arenas[self.placement.input.arena].clone(), self.placement.input)
    }

    /// The pooled value node `i`'s output is max-pooled into, if any.
    pub(super) fn pooled_by(&self, graph: &Graph, i: usize) -> Option<&wgpu::TextureView> {
        graph.pools.iter().position(|p| p.after == i).map(|k| &self.pooled_views[k])
    }
}

/// The frame padded to a multiple of `2^levels`, or why the device cannot take it.
fn padded_size(device: &wgpu::Device, arch: &Arch, width: u32, height: u32) -> Result<(u32, u32)> {
    let size_err = |reason: String| Error::FrameSize { width, height, reason };
    if width == 0 || height == 0 {
        return Err(size_err("empty frame".into()));
    }
    let multiple = 1u32 << arch.levels();
    let (pwidth, pheight) = (width.next_multiple_of(multiple), height.next_multiple_of(multiple));
    let max = device.limits().max_texture_dimension_2d;
    if pwidth > max || pheight > max {
        return Err(size_err(format!("exceeds the device's texture limit {max}")));
    }
    Ok((pwidth, pheight))
}

/// Every conv of `graph` as the plan takes it: its size at the padded frame, its sources,
/// its weights from `weights` (found by the PyTorch module name).
fn conv_specs<'a>(graph: &'a Graph, weights: &'a Weights, arch: &Arch, acts: &Activations, pwidth: u32, pheight: u32) -> Vec<ConvSpec<'a>> {
    graph
        .nodes
        .iter()
        .enumerate()
        .map(|(i, n)| ConvSpec {
            name: &n.name,
            width: pwidth >> n.level,
            height: pheight >> n.level,
            ca: n.a.channels,
            cb: n.b.map_or(0, |b| b.channels),
            cout: n.cout,
            weight: &weights.get(&format!("{}.weight", n.name)).expect("validated at load").data,
            bias: &weights.get(&format!("{}.bias", n.name)).expect("validated at load").data,
            read_a: n.a.read,
            read_b: n.b.map_or(Read::Direct, |b| b.read),
            leaky: n.leaky,
            slope: arch.negative_slope,
            b_is_hidden: n.b.is_some_and(|b| matches!(b.value, Value::HiddenPrev(_))),
            pooled: graph.pools.iter().any(|p| p.after == i),
            carves: [
                acts.carve(n.a.value),
                n.b.map_or(Carve::NONE, |b| acts.carve(b.value)),
                acts.carve(n.out),
                graph.pools.iter().position(|p| p.after == i).map_or(Carve::NONE, |k| acts.carve(Value::Pooled(k))),
            ],
        })
        .collect()
}

/// Each conv's tile, source access and weight memory, and where tuned its finalists.
struct Choices {
    tiles: Vec<Tile>,
    sources: Vec<SourceAccess>,
    memories: Vec<WeightMemory>,
    tuning: Vec<Vec<Finalist>>,
}

/// The choices `options` leave to the device, made: a fixed tile, the CPU drivers' rule per
/// level, or each conv's fastest finalist of timing the device class's candidates
/// ([`tune`]).
#[allow(clippy::too_many_arguments)]
fn choose(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    kernels: &mut Kernels,
    graph: &Graph,
    acts: &Activations,
    specs: &[ConvSpec],
    options: &Options,
    memory: WeightMemory,
) -> Result<Choices> {
    let device_type = device.adapter_info().device_type;
    let default_sources = kernels.source_access();
    let fixed_mma = matches!(options.tiles, TileChoice::Fixed(t) if t.method.is_mma());
    // A conv's weight memory under a tile: the caller's or a fixed Mma tile's choice, else
    // storage for an Mma tile and by level otherwise. Tuning times each candidate with it, so
    // that it times what the plan it picks will run. (The lanes module's tiles read the plan's
    // weight texture, and the plan gives them storage: kernels::TEXEL_WEIGHTS.)
    let memory_of = |tile: Tile, spec: &ConvSpec| -> WeightMemory {
        if options.weights.is_some() || fixed_mma {
            memory
        } else if tile.method.is_mma() {
            WeightMemory::Storage
        } else {
            WeightMemory::for_conv(device_type, spec.width, spec.height)
        }
    };
    // Matrix-unit tiles join tuning where they run in hardware, with their weights in a
    // storage buffer and room for their workgroup memory.
    let mma = kernels.matrix_units()
        && memory == WeightMemory::Storage
        && device.limits().max_compute_workgroup_storage_size >= MMA_WORKGROUP_BYTES;
    // CPU drivers with subgroups of 8 lanes or more tune among the lanes tiles.
    let cpu_lanes = device_type == wgpu::DeviceType::Cpu && Tile::cpu(device) == Tile::CPU_LANES;
    let base: &[Tile] = if cpu_lanes { &TUNE_TILES_CPU } else { &TUNE_TILES };
    let candidates = tuning_candidates(options.tiles, options.precision, mma, base);
    let timestamps = device.features().contains(wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES);
    let fixed = |t: Tile| (vec![t], vec![default_sources], Vec::new());
    let (tiles, sources, tuning) = match options.tiles {
        TileChoice::Fixed(t) => fixed(t),
        TileChoice::Auto if device_type == wgpu::DeviceType::Cpu => {
            let tiles = specs.iter().map(|s| Tile::cpu_for(device, s.width, s.height, blocks(s.ca) + blocks(s.cb))).collect();
            (tiles, vec![default_sources], Vec::new())
        }
        _ if timestamps && !candidates.is_empty() => {
            // Tuning times both source kinds unless the caller fixed one.
            let other = if default_sources == SourceAccess::Sampled { SourceAccess::Storage } else { SourceAccess::Sampled };
            let both = [default_sources, other];
            let accesses = if options.sources.is_some() || !SourceAccess::storage_fits(device) { &both[..1] } else { &both[..] };
            // Sources, destination and pooled value of every conv at parity 0.
            let views: Vec<NodeViews> = graph
                .nodes
                .iter()
                .enumerate()
                .map(|(i, n)| NodeViews {
                    a: acts.view(n.a.value, 0).clone(),
                    b: acts.view(n.b.map_or(n.a.value, |b| b.value), 0).clone(),
                    out: acts.view(n.out, 0).clone(),
                    pooled: acts.pooled_by(graph, i).cloned(),
                })
                .collect();
            let finalists = tune(device, queue, kernels, specs, &views, &candidates, accesses, &memory_of)?;
            let (tiles, sources) = finalists.iter().map(|f| (f[0].tile, f[0].sources)).unzip();
            (tiles, sources, finalists)
        }
        _ => fixed(Tile::default()),
    };
    let memories = specs.iter().enumerate().map(|(i, s)| memory_of(per_conv(&tiles, i), s)).collect();
    Ok(Choices { tiles, sources, memories, tuning })
}

/// The conv bind groups of both parities (the reset variant only changes the dynamic offset).
fn conv_groups(device: &wgpu::Device, kernels: &Kernels, graph: &Graph, acts: &Activations, convs: &ConvPlan) -> [Vec<wgpu::BindGroup>; 2] {
    std::array::from_fn(|parity| {
        graph
            .nodes
            .iter()
            .enumerate()
            .map(|(i, node)| {
                // A one-source conv binds its source a as b too (never read: its cin4_b is 0).
                let src_b = acts.view(node.b.map_or(node.a.value, |b| b.value), parity);
                let (a, out) = (acts.view(node.a.value, parity), acts.view(node.out, parity));
                convs.bind_group(device, kernels, i, a, src_b, out, acts.pooled_by(graph, i))
            })
            .collect()
    })
}

/// The pool passes' bind groups of both parities (a pool reads the state written this frame
/// and writes the cells of its pooled value, [`Carve`]).
fn pool_groups(device: &wgpu::Device, kernels: &Kernels, graph: &Graph, acts: &Activations) -> [Vec<wgpu::BindGroup>; 2] {
    let carves: Vec<wgpu::Buffer> = (0..graph.pools.len())
        .map(|k| create_init(device, "pool carve", bytemuck::bytes_of(&acts.carve(Value::Pooled(k))), wgpu::BufferUsages::UNIFORM))
        .collect();
    std::array::from_fn(|parity| {
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
                            resource: wgpu::BindingResource::TextureView(acts.view(Value::HiddenNew(p.hidden), parity)),
                        },
                        wgpu::BindGroupEntry {
                            binding: 1,
                            resource: wgpu::BindingResource::TextureView(acts.view(Value::Pooled(i), parity)),
                        },
                        wgpu::BindGroupEntry { binding: 2, resource: carves[i].as_entire_binding() },
                    ],
                })
            })
            .collect()
    })
}

/// prep.wgsl's layout for `arch`: where each input buffer's channels go, and the transfer.
fn prep_layout(arch: &Arch, graph: &Graph) -> PrepLayout {
    let mut offsets = [None; 5];
    let mut ch = 0u32;
    for b in &arch.inputs {
        offsets[InputBuffer::ALL.iter().position(|x| x == b).expect("known buffer")] = Some(ch);
        ch += b.channels() as u32;
    }
    PrepLayout {
        offsets,
        layers: blocks(graph.in_channels),
        demodulate: arch.demodulate,
        log1p: matches!(arch.transfer, Transfer::Log1p),
        albedo_eps: arch.albedo_eps,
    }
}

impl Denoiser {
    /// [`Self::new`] with every choice spelled out: storage precision, conv tiles, weight
    /// memory, source access and staging ([`Options`]). A frame past the device's limits, or
    /// GPU memory that runs out while building, is an error ([`Error::FrameSize`],
    /// [`Error::Gpu`]), never a panic.
    pub fn with_options(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        weights: &Weights,
        width: u32,
        height: u32,
        options: Options,
    ) -> Result<Self> {
        let what = format!("building the denoiser for {width}x{height}");
        catching_gpu_errors(device, &what, || Self::build(device, queue, weights, width, height, options))
    }

    fn build(device: &wgpu::Device, queue: &wgpu::Queue, weights: &Weights, width: u32, height: u32, options: Options) -> Result<Self> {
        let Options { precision, tiles, weights: chosen_memory, sources, staging, motion, accumulate, max_memory, frame_tiles } = options;
        let device_type = device.adapter_info().device_type;
        let arch = weights.arch.clone();
        let limits = device.limits();
        let memory_plan = MemoryPlan::new(&arch, width, height, precision, max_memory, frame_tiles, motion, &limits)?;
        if memory_plan.tiles.is_some() && motion {
            return Err(Error::Tiled("frames in tiles are not reprojected: build without Options::motion"));
        }
        // The network runs at the padded frame, or at the tiles' extent.
        let (pwidth, pheight) = match &memory_plan.tiles {
            None => padded_size(device, &arch, width, height)?,
            Some(t) => t.extent,
        };
        let graph = Graph::new(&arch);
        // Mma tiles read storage weights: a fixed one picks them where the caller left it open.
        let fixed_mma = matches!(tiles, TileChoice::Fixed(t) if t.method.is_mma());
        let memory = chosen_memory.unwrap_or(if fixed_mma { WeightMemory::Storage } else { WeightMemory::for_device_type(device_type) });
        let mut kernels = Kernels::with_sources(device, precision, memory, sources.unwrap_or(SourceAccess::for_device(device)));
        // The padded levels halve exactly, so the convs may read their zero padding from
        // outside the textures where the device reads zero there (before tuning makes any).
        kernels.pad_from_bounds();
        let acts = Activations::new(device, &graph, pwidth, pheight, precision, motion);
        let specs = conv_specs(&graph, weights, &arch, &acts, pwidth, pheight);
        let choices = choose(device, queue, &mut kernels, &graph, &acts, &specs, &options, memory)?;
        // On CPU drivers the F(4x4) convs write their outputs into a buffer that the frame copies
        // into their textures (Kernels::stage_outputs; record_with records the copies). Tuning,
        // above, timed the convs unstaged: a copy costs every candidate the same.
        if staging.unwrap_or(device_type == wgpu::DeviceType::Cpu) {
            kernels.stage_outputs();
        }
        // The plan's weight buffer depends on the frame (each level's tiles and weight memory).
        let convs = ConvPlan::with_choices(device, queue, &mut kernels, &specs, &choices.tiles, &choices.sources, &choices.memories)
            .map_err(|e| match e {
                Error::GpuBuffer { .. } => Error::FrameSize { width, height, reason: e.to_string() },
                e => e,
            })?;
        debug_assert_eq!(acts.bytes, activation_bytes(&graph, pwidth, pheight, precision, motion));
        let host_state = memory_plan.host_state > 0;
        let tiles = memory_plan.tiles.map(|plan| Tiles::new(device, plan, &graph, &arch, precision, host_state)).transpose()?;
        let layout = prep_layout(&arch, &graph);
        let guide = Guide::of(&layout);
        let motion = motion.then(|| Motion::new(device, &mut kernels, &graph, &acts, &convs, guide, (width, height, pwidth, pheight)));
        let accumulation = (accumulate && motion.is_some()).then(|| Accumulation::new(device, width, height));
        let conv_outputs: [Vec<(wgpu::Texture, Vec<wgpu::Origin3d>)>; 2] =
            std::array::from_fn(|parity| graph.nodes.iter().map(|n| acts.written(n.out, parity, blocks(n.cout))).collect());
        let output_view = acts.view(graph.output, 0).clone();
        let prep = kernels.prep_pipeline(device, &layout);
        let prep_params = PrepParams { width, height, pwidth, pheight };
        let output_params = OutputParams::new(&arch, (0, 0), (width, height), width);
        let stats_usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC;
        Ok(Self {
            id: NEXT_ID.fetch_add(1, Ordering::Relaxed),
            device: device.clone(),
            queue: queue.clone(),
            conv_groups: conv_groups(device, &kernels, &graph, &acts, &convs),
            pool_groups: pool_groups(device, &kernels, &graph, &acts),
            conv_outputs,
            prep,
            prep_params: create_init(device, "prep params", bytemuck::bytes_of(&prep_params), wgpu::BufferUsages::UNIFORM),
            output_params: create_init(device, "output params", bytemuck::bytes_of(&output_params), wgpu::BufferUsages::UNIFORM),
            dummy: create_init(device, "absent buffer", &[0u8; 16], wgpu::BufferUsages::STORAGE),
            stats: create_init(device, "frame stats", &[0u8; 16], stats_usage),
            bytes: acts.bytes
                + convs.bytes()
                + motion.as_ref().map_or(0, |m| m.bytes)
                + accumulation.as_ref().map_or(0, |a| a.bytes)
                + tiles.as_ref().map_or(0, |t| t.bytes),
            tiles,
            motion,
            input_view: acts.view(Value::Input, 0).clone(),
            input_at: acts.input(),
            output_view,
            textures: acts.textures,
            hidden_textures: acts.hidden_textures,
            arch,
            graph,
            width,
            height,
            pwidth,
            pheight,
            kernels,
            convs,
            precision,
            host: None,
            profiler: None,
            tuning: choices.tuning,
            parity: 0,
            reset_pending: true,
            accumulation,
        })
    }
}

/// Bytes of the activation and hidden-state textures a [`Denoiser`] allocates for `graph` at
/// the padded size `pwidth` x `pheight`: the arenas of the input, the temporaries and the
/// pooled values ([`Graph::place`]), and one texture per recurrent block (two with `motion`).
/// Weights and uniforms are not included. Needs no device, so memory at any size can be
/// reported (`rae-cli info --size`).
pub fn activation_bytes(graph: &Graph, pwidth: u32, pheight: u32, precision: Precision, motion: bool) -> u64 {
    let tex = |level: usize, layers: u64| (pwidth >> level) as u64 * (pheight >> level) as u64 * layers * precision.texel_bytes();
    let copies = if motion { 2 } else { 1 };
    let hidden: u64 = graph.hidden.iter().map(|&(c, level)| copies * tex(level, blocks(c) as u64)).sum();
    let arenas: u64 = graph.place().arena_layers.iter().map(|&l| tex(0, l as u64)).sum();
    arenas + hidden
}

pub(super) fn create_init(device: &wgpu::Device, label: &str, contents: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
    use wgpu::util::DeviceExt;
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
}

/// Runs `f` with wgpu's validation and out-of-memory errors caught in error scopes on this
/// thread, instead of going to the device's uncaptured-error handler (which panics by default):
/// a buffer past the device's limits, or GPU memory that runs out, becomes [`Error::Gpu`].
#[cfg(not(target_arch = "wasm32"))]
pub(crate) fn catching_gpu_errors<T>(device: &wgpu::Device, what: &str, f: impl FnOnce() -> Result<T>) -> Result<T> {
    let oom = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let result = f();
    let validation = pollster::block_on(validation.pop());
    let oom = pollster::block_on(oom.pop());
    match (oom, validation) {
        (Some(e), _) => Err(Error::Gpu(format!("{what}: out of GPU memory: {e}"))),
        (None, Some(e)) => Err(Error::Gpu(format!("{what}: {e}"))),
        (None, None) => result,
    }
}

/// In a browser an error scope's verdict comes only when the page's event loop runs, so `f`
/// runs without scopes: the caller pushes its own around the call and awaits them
/// (`crates/rae-web` does), or errors reach the device's uncaptured-error handler.
#[cfg(target_arch = "wasm32")]
pub(crate) fn catching_gpu_errors<T>(_device: &wgpu::Device, _what: &str, f: impl FnOnce() -> Result<T>) -> Result<T> {
    f()
}

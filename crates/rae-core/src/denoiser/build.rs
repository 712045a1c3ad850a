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

impl Denoiser {
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
        let base: &[Tile] = if lanes { &TUNE_TILES_CPU } else { &TUNE_TILES };
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

pub(super) fn create_init(device: &wgpu::Device, label: &str, contents: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
    use wgpu::util::DeviceExt;
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
}

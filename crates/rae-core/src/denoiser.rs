//! The per-(model, width, height) runtime: every GPU resource built once, then one command
//! encoder and one submit per frame.
//!
//! # Buffers and their lifetimes
//! - **Input** (packed network input) and **temporaries** live for one frame. Temporaries are
//!   texture arrays shared by lifetime ([`Graph::allocate_temps`]): two values whose live
//!   ranges do not overlap at a resolution use the same texture.
//! - **Hidden state**: each recurrent block owns two textures, `hidden[k][0]` and
//!   `hidden[k][1]`, and they ping-pong. On a frame of parity `p`, block `k` reads last frame's
//!   state from `hidden[k][p]` and writes the new one (its output, which the next block pools
//!   and the decoder reads as a skip) into `hidden[k][1 - p]`; the next frame has parity
//!   `1 - p`. Nothing is copied. Bind groups for both parities are built up front.
//! - **Reset** (first frame, scene cut) does not clear anything: for that frame the recurrent
//!   convs run with a uniform block that reads zero channels from the hidden state, which is
//!   exactly a zero hidden state (the skipped terms are the last summed), so frame 0 after
//!   `reset()` is bit-identical to frame 0 of a fresh denoiser.
//! - **Weights** sit in one rgba32float texture (texture loads are vectorised on lavapipe,
//!   storage-buffer loads are not), bias and taps of every conv at fixed offsets.
//!
//! Frames are `width x height`; the network runs at the size padded to a multiple of
//! `2^levels` (the prep kernel replicates edge pixels into the padding) and the output kernel
//! crops back.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use crate::error::{Error, Result};
use crate::frame::{FrameInputs, FrameTimings};
use crate::graph::{Graph, Value};
use crate::kernels::{self, ConvParams, ConvVariant, Kernels, OutputParams, PrepParams, WORKGROUP, blocks};
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

/// Buffers of the host-slice path, made on its first use.
struct HostIo {
    inputs: Vec<(InputBuffer, wgpu::Buffer)>,
    output: wgpu::Buffer,
    readback: wgpu::Buffer,
    binding: IoBinding,
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
    conv_pipelines: Vec<wgpu::ComputePipeline>,
    conv_dispatch: Vec<(u32, u32, u32)>,
    /// `[reset][parity][node]`.
    conv_groups: [[Vec<wgpu::BindGroup>; 2]; 2],
    prep_params: wgpu::Buffer,
    output_params: wgpu::Buffer,
    input_texture: wgpu::Texture,
    output_view: wgpu::TextureView,
    dummy: wgpu::Buffer,
    textures: Vec<wgpu::Texture>,
    bytes: u64,
    host: Option<HostIo>,
    parity: usize,
    reset_pending: bool,
}

fn texture(device: &wgpu::Device, label: &str, w: u32, h: u32, layers: u32) -> (wgpu::Texture, wgpu::TextureView) {
    let t = device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: layers },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: kernels::ACTIVATION_FORMAT,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let v = t.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    });
    (t, v)
}

impl Denoiser {
    /// Build everything for `weights` at `width` x `height` on a device: pipelines, textures,
    /// weights, uniforms and the bind groups of both hidden-state parities.
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, weights: &Weights, width: u32, height: u32) -> Result<Self> {
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
        let mut kernels = Kernels::new(device);
        let mut textures = Vec::new();
        let mut bytes = 0u64;
        let mut make = |label: &str, level: usize, channels: usize| {
            let (w, h, l) = (pwidth >> level, pheight >> level, blocks(channels));
            bytes += w as u64 * h as u64 * l as u64 * 16;
            let (t, v) = texture(device, label, w, h, l);
            textures.push(t.clone());
            (t, v)
        };

        // Activations: input, hidden pairs, temporaries by lifetime.
        let (input_texture, input_view) = make("input", 0, graph.in_channels);
        let hidden: Vec<[wgpu::TextureView; 2]> = graph
            .hidden
            .iter()
            .map(|&(c, level)| [make("hidden", level, c).1, make("hidden", level, c).1])
            .collect();
        let (assign, slots) = graph.allocate_temps();
        let slot_views: Vec<wgpu::TextureView> = slots.iter().map(|&(level, c)| make("temp", level, c).1).collect();
        let (_, dummy_view) = texture(device, "unused source", 1, 1, 1);
        let view = |v: Value, parity: usize| -> &wgpu::TextureView {
            match v {
                Value::Input => &input_view,
                Value::HiddenPrev(k) => &hidden[k][parity],
                Value::HiddenNew(k) => &hidden[k][1 - parity],
                Value::Temp(t) => &slot_views[assign[t]],
            }
        };
        let Value::Temp(out_temp) = graph.output else { unreachable!("the output is a temporary") };
        let output_view = slot_views[assign[out_temp]].clone();

        // Weights: one texture, every conv at its offsets.
        let (packed, offsets) = kernels::pack_all(&graph.nodes, weights);
        let weight_texture = kernels::weight_texture(device, queue, &packed);
        let weight_view = weight_texture.create_view(&Default::default());
        bytes += weight_texture.size().width as u64 * weight_texture.size().height as u64 * 16;

        // Conv uniforms: two slots per node (normal, reset), at the device's offset alignment.
        let stride = (std::mem::size_of::<ConvParams>() as u64).next_multiple_of(limits.min_uniform_buffer_offset_alignment as u64);
        let mut uniform = vec![0u8; (stride * 2 * graph.nodes.len() as u64) as usize];
        for (i, node) in graph.nodes.iter().enumerate() {
            let (w, h) = (pwidth >> node.level, pheight >> node.level);
            let cin4_b = node.b.map_or(0, |b| blocks(b.channels));
            for reset in 0..2 {
                let reads_hidden = node.b.is_some_and(|b| matches!(b.value, Value::HiddenPrev(_)));
                let p = ConvParams {
                    width: w,
                    height: h,
                    cin4_a: blocks(node.a.channels),
                    cin4_b: if reset == 1 && reads_hidden { 0 } else { cin4_b },
                    cin4_total: blocks(node.a.channels) + cin4_b,
                    cout4: blocks(node.cout),
                    b_offset: offsets[i].0,
                    t_offset: offsets[i].1,
                    slope: arch.negative_slope,
                    _pad: [0; 3],
                };
                let at = (stride * (2 * i + reset) as u64) as usize;
                uniform[at..at + std::mem::size_of::<ConvParams>()].copy_from_slice(bytemuck::bytes_of(&p));
            }
        }
        let conv_uniform = create_init(device, "conv params", &uniform, wgpu::BufferUsages::UNIFORM);

        let conv_pipelines: Vec<_> = graph.nodes.iter().map(|n| kernels.conv(device, ConvVariant::of(n))).collect();
        let conv_dispatch =
            graph.nodes.iter().map(|n| kernels::conv_workgroups(pwidth >> n.level, pheight >> n.level, n.cout)).collect();
        let conv_groups: [[Vec<wgpu::BindGroup>; 2]; 2] = std::array::from_fn(|reset| {
            std::array::from_fn(|parity| {
                graph
                    .nodes
                    .iter()
                    .enumerate()
                    .map(|(i, node)| {
                        let src_b = node.b.map_or(&dummy_view, |b| view(b.value, parity));
                        device.create_bind_group(&wgpu::BindGroupDescriptor {
                            label: Some(&node.name),
                            layout: &kernels.conv_layout,
                            entries: &[
                                wgpu::BindGroupEntry {
                                    binding: 0,
                                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                                        buffer: &conv_uniform,
                                        offset: stride * (2 * i + reset) as u64,
                                        size: wgpu::BufferSize::new(std::mem::size_of::<ConvParams>() as u64),
                                    }),
                                },
                                wgpu::BindGroupEntry {
                                    binding: 1,
                                    resource: wgpu::BindingResource::TextureView(view(node.a.value, parity)),
                                },
                                wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::TextureView(src_b) },
                                wgpu::BindGroupEntry { binding: 3, resource: wgpu::BindingResource::TextureView(&weight_view) },
                                wgpu::BindGroupEntry {
                                    binding: 4,
                                    resource: wgpu::BindingResource::TextureView(view(node.out, parity)),
                                },
                            ],
                        })
                    })
                    .collect()
            })
        });

        // Prep and output uniforms.
        let mut offsets5 = [u32::MAX; 5];
        let mut ch = 0u32;
        for b in &arch.inputs {
            offsets5[InputBuffer::ALL.iter().position(|x| x == b).expect("known buffer")] = ch;
            ch += b.channels() as u32;
        }
        let transfer = match arch.transfer {
            Transfer::None => 0,
            Transfer::Log1p => 1,
        };
        let prep = PrepParams {
            width,
            height,
            pwidth,
            pheight,
            offsets: offsets5,
            layers: blocks(graph.in_channels),
            demodulate: arch.demodulate as u32,
            transfer,
            albedo_eps: arch.albedo_eps,
            _pad: [0; 3],
        };
        let out = OutputParams { width, height, demodulate: arch.demodulate as u32, transfer, albedo_eps: arch.albedo_eps, _pad: [0; 3] };
        let prep_params = create_init(device, "prep params", bytemuck::bytes_of(&prep), wgpu::BufferUsages::UNIFORM);
        let output_params = create_init(device, "output params", bytemuck::bytes_of(&out), wgpu::BufferUsages::UNIFORM);
        let dummy = create_init(device, "absent buffer", &[0u8; 16], wgpu::BufferUsages::STORAGE);

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
            conv_pipelines,
            conv_dispatch,
            conv_groups,
            prep_params,
            output_params,
            input_texture,
            output_view,
            dummy,
            textures,
            bytes,
            host: None,
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

    /// Bytes of GPU memory held for activations, hidden state and weights (host I/O excluded).
    pub fn gpu_bytes(&self) -> u64 {
        self.bytes
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
            let buf = io.get(b).ok_or_else(|| Error::MissingInput {
                buffer: b.name(),
                needed: needed.iter().map(|b| b.name()).collect(),
            })?;
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
                    resource: wgpu::BindingResource::TextureView(&self.input_texture.create_view(
                        &wgpu::TextureViewDescriptor {
                            dimension: Some(wgpu::TextureViewDimension::D2Array),
                            ..Default::default()
                        },
                    )),
                },
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
            ],
        });
        Ok(IoBinding { owner: self.id, prep, output })
    }

    /// Record one frame into the caller's encoder: read the buffers bound in `io`, write its
    /// output buffer. Frames must be submitted in the order they are recorded (the hidden state
    /// advances at record time).
    pub fn record(&mut self, encoder: &mut wgpu::CommandEncoder, io: &IoBinding) -> Result<()> {
        if io.owner != self.id {
            return Err(Error::GpuBuffer { buffer: "io", reason: "binding was made by another Denoiser".into() });
        }
        let (reset, parity) = (self.reset_pending as usize, self.parity);
        {
            let mut pass =
                encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("rae frame"), timestamp_writes: None });
            pass.set_pipeline(&self.kernels.prep);
            pass.set_bind_group(0, &io.prep, &[]);
            pass.dispatch_workgroups(self.pwidth.div_ceil(WORKGROUP), self.pheight.div_ceil(WORKGROUP), 1);
            for (i, pipeline) in self.conv_pipelines.iter().enumerate() {
                let (x, y, z) = self.conv_dispatch[i];
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, &self.conv_groups[reset][parity][i], &[]);
                pass.dispatch_workgroups(x, y, z);
            }
            pass.set_pipeline(&self.kernels.output);
            pass.set_bind_group(0, &io.output, &[]);
            pass.dispatch_workgroups(self.width.div_ceil(WORKGROUP), self.height.div_ceil(WORKGROUP), 1);
        }
        self.parity ^= 1;
        self.reset_pending = false;
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
            return Err(Error::InputSize { buffer: "output", found: out.len(), expected: n, width: self.width, height: self.height, channels: 3 });
        }
        if self.host.is_none() {
            self.host = Some(self.make_host_io()?);
        }
        let t0 = Instant::now();
        let host = self.host.take().expect("made above");
        for (b, buf) in &host.inputs {
            self.queue.write_buffer(buf, 0, bytemuck::cast_slice(frame.get(*b).expect("validated")));
        }
        let mut encoder = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("rae frame") });
        let recorded = self.record(&mut encoder, &host.binding);
        encoder.copy_buffer_to_buffer(&host.output, 0, &host.readback, 0, host.output.size());
        let t1 = Instant::now();
        self.queue.submit(Some(encoder.finish()));
        let waited = self.device.poll(wgpu::PollType::wait_indefinitely());
        let t2 = Instant::now();
        let result = recorded.and(waited.map(|_| ()).map_err(|e| Error::Gpu(e.to_string()))).and_then(|_| {
            read_buffer(&self.device, &host.readback, out)
        });
        let t3 = Instant::now();
        self.host = Some(host);
        result.map(|_| FrameTimings { upload: t1 - t0, gpu: t2 - t1, download: t3 - t2 })
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
        Ok(HostIo { inputs, output, readback, binding })
    }

    /// The packed network input of the last frame, channel-major (`channels x ph x pw`), for
    /// checking the prep kernel.
    pub fn read_input(&self) -> Result<Vec<f32>> {
        let all = read_texture(&self.device, &self.queue, &self.input_texture)?;
        let (w, h) = (self.pwidth as usize, self.pheight as usize);
        let c = self.graph.in_channels;
        Ok((0..c * h * w).map(|i| {
            let (ch, p) = (i / (h * w), i % (h * w));
            all[((ch / 4) * h * w + p) * 4 + ch % 4]
        }).collect())
    }

    /// Textures held (for memory reports and tests).
    pub fn texture_count(&self) -> usize {
        self.textures.len()
    }
}

fn create_init(device: &wgpu::Device, label: &str, contents: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
    use wgpu::util::DeviceExt;
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
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

/// Read a whole rgba32float texture array back: `layers x h x w x 4` f32.
pub fn read_texture(device: &wgpu::Device, queue: &wgpu::Queue, texture: &wgpu::Texture) -> Result<Vec<f32>> {
    let size = texture.size();
    let (w, h, l) = (size.width, size.height, size.depth_or_array_layers);
    let row = (w * 16).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
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

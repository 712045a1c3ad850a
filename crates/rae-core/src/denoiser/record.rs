//! Recording a frame into a command encoder: the caller's GPU buffers ([`GpuFrameIo`]), the
//! frame's passes, and the timestamps that time them.

use super::*;

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
    /// Motion, two f32 per pixel in rae's convention ([`FrameInputs::motion`]): only for a
    /// denoiser built with [`Options::motion`]; frames recorded with this binding reproject the
    /// hidden state with it.
    pub motion: Option<&'a wgpu::Buffer>,
    /// Denoised radiance, RGB (written).
    pub output: &'a wgpu::Buffer,
}

impl<'a> GpuFrameIo<'a> {
    /// The caller's buffers given as one per input buffer (color among them), with motion
    /// and the output.
    pub fn from_inputs(inputs: &'a [(InputBuffer, wgpu::Buffer)], motion: Option<&'a wgpu::Buffer>, output: &'a wgpu::Buffer) -> Self {
        let get = |b: InputBuffer| inputs.iter().find(|(x, _)| *x == b).map(|(_, buf)| buf);
        GpuFrameIo {
            color: get(InputBuffer::Color).expect("color is always an input"),
            albedo: get(InputBuffer::Albedo),
            normal: get(InputBuffer::Normal),
            depth: get(InputBuffer::Depth),
            roughness: get(InputBuffer::Roughness),
            motion,
            output,
        }
    }

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

/// Why a tiled denoiser refuses the caller's GPU buffers: each tile stages its own inputs.
const HOST_FRAMES_ONLY: &str = "the frame runs in tiles, which take host frames (denoise_into), not GPU buffers";

/// Bind groups that connect a set of caller buffers to one [`Denoiser`]; make it once per set
/// of buffers with [`Denoiser::bind_io`] and reuse it every frame.
pub struct IoBinding {
    pub(super) owner: u64,
    pub(super) prep: wgpu::BindGroup,
    pub(super) output: wgpu::BindGroup,
    /// motion.wgsl's `motion_in` over the caller's motion buffer, if it has one.
    pub(super) motion: Option<wgpu::BindGroup>,
    /// The output's accumulation over the caller's buffers ([`Options::accumulate`]).
    pub(super) accumulate: Option<AccumulateIo>,
}

impl Denoiser {
    /// Connect caller buffers (see [`GpuFrameIo`]); checks presence, sizes and usages. A
    /// denoiser whose frames run in tiles takes host frames only ([`Error::Tiled`]).
    pub fn bind_io(&self, io: &GpuFrameIo) -> Result<IoBinding> {
        if self.tiles.is_some() {
            return Err(Error::Tiled(HOST_FRAMES_ONLY));
        }
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
        let (prep, output) = self.io_groups(io, &self.prep_params, &self.output_params);
        let input = &self.input_view;
        let motion = match (io.motion, &self.motion) {
            (None, _) => None,
            (Some(_), None) => return Err(Error::Motion("the denoiser was built without motion (Options::motion)".into())),
            (Some(buf), Some(m)) => {
                check("motion", buf, 2)?;
                let layout = &self.kernels.motion_kernels().expect("made with the denoiser's motion").in_layout;
                Some(self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("motion in"),
                    layout,
                    entries: &[
                        wgpu::BindGroupEntry { binding: 0, resource: m.params.as_entire_binding() },
                        wgpu::BindGroupEntry { binding: 1, resource: buf.as_entire_binding() },
                        wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::TextureView(&m.level0) },
                        wgpu::BindGroupEntry { binding: 8, resource: wgpu::BindingResource::TextureView(input) },
                        wgpu::BindGroupEntry { binding: 9, resource: wgpu::BindingResource::TextureView(&m.guide) },
                    ],
                }))
            }
        };
        let accumulate = self.accumulation.as_ref().map(|a| {
            let (_, output) = self.io_groups(&GpuFrameIo { output: &a.current, ..*io }, &self.prep_params, &self.output_params);
            AccumulateIo { output, groups: a.groups(&self.device, io.motion.unwrap_or(&self.dummy), io.output) }
        });
        Ok(IoBinding { owner: self.id, prep, output, motion, accumulate })
    }

    /// The prep and output bind groups over `io`'s buffers with these uniforms.
    pub(super) fn io_groups(
        &self,
        io: &GpuFrameIo,
        prep_params: &wgpu::Buffer,
        output_params: &wgpu::Buffer,
    ) -> (wgpu::BindGroup, wgpu::BindGroup) {
        let needed = self.arch.required_buffers();
        let input = &self.input_view;
        let pick = |b: InputBuffer| if needed.contains(&b) { io.get(b).expect("checked") } else { &self.dummy };
        let prep = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("prep"),
            layout: &self.kernels.prep_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: prep_params.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: pick(InputBuffer::Color).as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: pick(InputBuffer::Albedo).as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: pick(InputBuffer::Normal).as_entire_binding() },
                wgpu::BindGroupEntry { binding: 4, resource: pick(InputBuffer::Depth).as_entire_binding() },
                wgpu::BindGroupEntry { binding: 5, resource: pick(InputBuffer::Roughness).as_entire_binding() },
                wgpu::BindGroupEntry { binding: 6, resource: wgpu::BindingResource::TextureView(input) },
                wgpu::BindGroupEntry { binding: 7, resource: self.stats.as_entire_binding() },
            ],
        });
        let output = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("output"),
            layout: &self.kernels.output_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: output_params.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(&self.output_view) },
                wgpu::BindGroupEntry { binding: 2, resource: pick(InputBuffer::Albedo).as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: io.output.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 4, resource: self.stats.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 5, resource: pick(InputBuffer::Color).as_entire_binding() },
                wgpu::BindGroupEntry { binding: 6, resource: pick(InputBuffer::Normal).as_entire_binding() },
                wgpu::BindGroupEntry { binding: 7, resource: pick(InputBuffer::Depth).as_entire_binding() },
            ],
        });
        (prep, output)
    }

    /// Record one frame into the caller's encoder: read the buffers bound in `io`, write its
    /// output buffer; with a motion buffer in `io`, reproject the hidden state with it first.
    /// Frames must be submitted in the order they are recorded (the hidden state advances at
    /// record time).
    pub fn record(&mut self, encoder: &mut wgpu::CommandEncoder, io: &IoBinding) -> Result<()> {
        if self.tiles.is_some() {
            return Err(Error::Tiled(HOST_FRAMES_ONLY));
        }
        let warp = io.motion.is_some();
        self.record_with(encoder, io, None, warp)
    }

    /// [`Self::record`], writing a timestamp before the frame and after each stage into `queries`
    /// (prep, every conv, output: [`Graph::nodes`]` + 3` queries), reprojecting the hidden state
    /// with `io`'s motion where `warp` (the motion passes count with prep).
    pub(super) fn record_with(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        io: &IoBinding,
        queries: Option<&wgpu::QuerySet>,
        warp: bool,
    ) -> Result<()> {
        if io.owner != self.id {
            return Err(Error::GpuBuffer { buffer: "io", reason: "binding was made by another Denoiser".into() });
        }
        let (reset, parity) = (self.reset_pending, self.parity);
        // A frame with history reprojects it where it has motion; a reset frame reads none.
        let motion = match (&self.motion, &io.motion) {
            (Some(m), Some(g)) if warp && !reset => Some((m, g)),
            _ => None,
        };
        // With accumulation the output pass writes the network's radiance for the accumulation
        // pass, which has history where the hidden state is reprojected.
        let (output, accumulate) = match (&self.accumulation, &io.accumulate) {
            (Some(a), Some(g)) => (&g.output, Some((a, &g.groups[motion.is_some() as usize][parity]))),
            _ => (&io.output, None),
        };
        encoder.clear_buffer(&self.stats, 0, None);
        self.record_passes(encoder, &io.prep, (output, accumulate), (self.width, self.height), queries, motion, parity, reset);
        self.parity ^= 1;
        self.reset_pending = false;
        Ok(())
    }

    /// The frame's passes (prep, reprojection, convs and pools, output, the output's
    /// accumulation where given) with these bind groups, the output kernel over `out_size`, on
    /// hidden-state parity `parity`; changes no state.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn record_passes(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        prep: &wgpu::BindGroup,
        (output, accumulate): (&wgpu::BindGroup, Option<(&Accumulation, &wgpu::BindGroup)>),
        out_size: (u32, u32),
        queries: Option<&wgpu::QuerySet>,
        motion: Option<(&Motion, &wgpu::BindGroup)>,
        parity: usize,
        reset: bool,
    ) {
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
                pass.set_bind_group(0, prep, &[]);
                pass.dispatch_workgroups(self.pwidth.div_ceil(WORKGROUP), self.pheight.div_ceil(WORKGROUP), 1);
                if let Some((m, g)) = motion {
                    m.record(&mut pass, self.kernels.motion_kernels().expect("made with the denoiser's motion"), g, parity);
                }
                // The guide of every frame, for the next frame's history test (after this
                // frame's test has read the previous one).
                if let Some(m) = &self.motion {
                    m.record_guide(&mut pass, self.kernels.motion_kernels().expect("made with the denoiser's motion"));
                }
                stamp(&mut pass, 1);
            }
            let mut staged = None;
            while next < n {
                let i = next;
                next += 1;
                let warped = motion.and_then(|(m, _)| m.conv_groups[parity][i].as_ref());
                self.convs.record(&mut pass, i, reset, warped.unwrap_or(&self.conv_groups[parity][i]));
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
                let (texture, cells) = &self.conv_outputs[parity][i];
                self.convs.copy_staged(encoder, i, texture, cells);
                // A staged conv pools its own output (F(4x4) tiles always can).
                debug_assert!(self.graph.pools.iter().all(|p| p.after != i) || self.convs.pools(i));
                let _ = pools.next_if(|(p, _)| p.after == i);
                pending_stamp = Some(2 + i as u32);
                continue;
            }
            pass.set_pipeline(&self.kernels.output);
            pass.set_bind_group(0, output, &[]);
            pass.dispatch_workgroups(out_size.0.div_ceil(WORKGROUP), out_size.1.div_ceil(WORKGROUP), 1);
            if let Some((a, group)) = accumulate {
                a.record(&mut pass, group);
            }
            stamp(&mut pass, 2 + self.graph.nodes.len() as u32);
            break;
        }
    }

    /// Dispatch every pipeline of a frame once, last stage first, with one workgroup each, and
    /// wait: a helper that compiles pipelines for another denoiser's first frame
    /// ([`crate::gpu::CompileHelper`]; CPU drivers compile at a pipeline's first dispatch, and
    /// one workgroup costs no arithmetic to speak of at any frame size). What it writes is
    /// meaningless, so the hidden state is reset after it.
    pub fn compile_backwards(&mut self) -> Result<()> {
        self.ensure_host_io()?;
        let host = self.host.as_ref().expect("made above");
        let parity = self.parity;
        let mut encoder = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("rae compile") });
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("rae compile"), timestamp_writes: None });
            if let (Some(a), Some(g)) = (&self.accumulation, &host.binding.accumulate) {
                a.record_one(&mut pass, &g.groups[0][parity]);
            }
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
            if let (Some(m), Some(g)) = (&self.motion, &host.binding.motion) {
                let kernels = self.kernels.motion_kernels().expect("made with the denoiser's motion");
                m.record(&mut pass, kernels, g, parity);
                m.record_guide(&mut pass, kernels);
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
/// prep (`docs/perf/lavapipe-2026-11-24-s19.log`). The spare's write flushes the scene holding `index` at
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

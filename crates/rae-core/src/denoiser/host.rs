//! Frames from and to host memory: upload, one submit, readback ([`Denoiser::denoise`]), the
//! profiled frame, and reading textures and buffers back for tests and tools.

use super::*;

/// Buffers of the host-slice path, made on its first use and kept: a frame creates no buffer.
///
/// `upload` is a persistent staging buffer (MAP_WRITE) holding every input back to back. It is
/// mapped between frames: a frame writes the host slices into it, unmaps it, and the frame's
/// encoder copies it into the input buffers; after the submit it is mapped again in the same
/// poll that maps `readback`. (`queue.write_buffer` would stage through a fresh allocation in
/// wgpu on every frame.)
pub(super) struct HostIo {
    inputs: Vec<(InputBuffer, wgpu::Buffer)>,
    /// Offset of each input in `upload`, in the order of `inputs`.
    offsets: Vec<u64>,
    /// The motion buffer and its offset in `upload`, for a denoiser built with motion.
    motion: Option<(wgpu::Buffer, u64)>,
    /// Offset in `upload` of a tiled frame's output bound, copied into the stats buffer.
    stats_at: u64,
    upload: wgpu::Buffer,
    /// Whether `upload` is mapped now (wgpu has no query for it).
    upload_mapped: std::sync::atomic::AtomicBool,
    output: wgpu::Buffer,
    readback: wgpu::Buffer,
    pub(super) binding: IoBinding,
    /// Each tile's prep and output bind groups (tiled frames), row by row.
    tile_groups: Vec<(wgpu::BindGroup, wgpu::BindGroup)>,
}

impl HostIo {
    pub(super) fn bytes(&self) -> u64 {
        self.inputs.iter().map(|(_, b)| b.size()).sum::<u64>()
            + self.motion.as_ref().map_or(0, |(b, _)| b.size())
            + self.upload.size()
            + self.output.size()
            + self.readback.size()
    }
}

/// Timestamp queries and their buffers for [`Denoiser::denoise_profiled`], made on first use.
pub(super) struct Profiler {
    queries: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    readback: wgpu::Buffer,
    count: u32,
}

impl Denoiser {
    /// Denoise one frame from host slices; returns RGB radiance (`width * height * 3`).
    pub fn denoise(&mut self, frame: &FrameInputs) -> Result<Vec<f32>> {
        let mut out = vec![0.0; self.width as usize * self.height as usize * 3];
        self.denoise_into(frame, &mut out)?;
        Ok(out)
    }

    /// Denoise one frame from host slices into `out` (`width * height * 3`), with timings.
    pub fn denoise_into(&mut self, frame: &FrameInputs, out: &mut [f32]) -> Result<FrameTimings> {
        self.validate(frame)?;
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
        self.ensure_host_io()?;
        if self.tiles.is_some() {
            return self.denoise_tiles(frame, out);
        }
        let t0 = Instant::now();
        let host = self.host.take().expect("made above");
        let mut encoder = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("rae frame") });
        let uploaded = self.upload(&host, frame, &mut encoder);
        let recorded = uploaded.and_then(|_| self.record_with(&mut encoder, &host.binding, None, frame.motion.is_some()));
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

    /// [`Self::denoise_into`] for a frame in tiles: per tile, its extent's inputs uploaded, the
    /// old state copied in, the network run, the new state written back and its interior read
    /// back into `out` (one submit per tile: the transfer buffers are a tile's).
    fn denoise_tiles(&mut self, frame: &FrameInputs, out: &mut [f32]) -> Result<FrameTimings> {
        let mut timings = FrameTimings::default();
        let host = self.host.take().expect("made by denoise_into");
        let mut tiles = self.tiles.take().expect("a tiled denoiser");
        let bound = crate::cpu::prepared_color_max(&self.arch, frame);
        let reset = self.reset_pending;
        let mut result = Ok(());
        // The network's state textures: it reads parity 0 and writes parity 1 on every tile.
        let prev = Network { textures: &self.hidden_textures, side: 0 };
        let new = Network { textures: &self.hidden_textures, side: 1 };
        for i in 0..tiles.at.len() {
            let t = tiles.at[i];
            let t0 = Instant::now();
            let mut encoder = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("rae tile") });
            if let Err(e) = self.upload_tile(&host, frame, &t, bound, &mut encoder) {
                result = Err(e);
                break;
            }
            if !reset && let Err(e) = tiles.copy_in(&self.device, &mut encoder, &self.graph, &t, &prev) {
                result = Err(e);
                break;
            }
            let (prep, output) = &host.tile_groups[i];
            self.record_passes(&mut encoder, prep, (output, None), t.interior, None, None, 0, reset);
            tiles.record_write_back(&mut encoder, &self.graph, &t, &new, !reset);
            let bytes = t.interior.0 as u64 * t.interior.1 as u64 * 12;
            encoder.copy_buffer_to_buffer(&host.output, 0, &host.readback, 0, bytes);
            let t1 = Instant::now();
            self.queue.submit(Some(encoder.finish()));
            let waited = self.device.poll(wgpu::PollType::wait_indefinitely());
            let t2 = Instant::now();
            let width = self.width as usize;
            let (iw, ih) = (t.interior.0 as usize, t.interior.1 as usize);
            let deliver = |data: &[f32]| {
                for y in 0..ih {
                    let at = ((t.iy0 as usize + y) * width + t.ix0 as usize) * 3;
                    out[at..at + iw * 3].copy_from_slice(&data[y * iw * 3..(y + 1) * iw * 3]);
                }
            };
            let finished = waited
                .map(|_| ())
                .map_err(|e| Error::Gpu(e.to_string()))
                .and_then(|_| finish_host_io(&self.device, &host, deliver))
                .and_then(|_| tiles.finish_tile(&self.device, &self.graph, &t, !reset));
            let t3 = Instant::now();
            timings.upload += t1 - t0;
            timings.gpu += t2 - t1;
            timings.download += t3 - t2;
            if let Err(e) = finished {
                result = Err(e);
                break;
            }
        }
        self.tiles = Some(tiles);
        self.host = Some(host);
        // A frame that fails part way leaves the frame's state part old, part new: the next
        // frame starts a sequence.
        self.reset_pending = result.is_err();
        result.map(|_| timings)
    }

    /// Copy tile `t`'s extent of the frame's host slices (the part inside the frame, rows
    /// packed tightly) and the frame's output bound into the mapped staging buffer, unmap it
    /// and record its copies into the input buffers and the stats.
    fn upload_tile(&self, host: &HostIo, frame: &FrameInputs, t: &TileAt, bound: f32, encoder: &mut wgpu::CommandEncoder) -> Result<()> {
        self.map_upload(host)?;
        let (vw, vh) = (t.valid.0 as usize, t.valid.1 as usize);
        let width = self.width as usize;
        {
            let mut view = host.upload.get_mapped_range_mut(..).map_err(|e| Error::Gpu(format!("staging buffer: {e:?}")))?;
            for ((b, _), &off) in host.inputs.iter().zip(&host.offsets) {
                let c = b.channels();
                let src = frame.get(*b).expect("validated");
                let row = vw * c;
                for y in 0..vh {
                    let at = ((t.y0 as usize + y) * width + t.x0 as usize) * c;
                    let to = off as usize + y * row * 4;
                    view.slice(to..to + row * 4).copy_from_slice(bytemuck::cast_slice(&src[at..at + row]));
                }
            }
            let at = host.stats_at as usize;
            view.slice(at..at + 16).copy_from_slice(bytemuck::bytes_of(&[bound.to_bits(), 0, 0, 0]));
        }
        host.upload.unmap();
        host.upload_mapped.store(false, Ordering::Relaxed);
        for ((b, buf), &off) in host.inputs.iter().zip(&host.offsets) {
            encoder.copy_buffer_to_buffer(&host.upload, off, buf, 0, (vw * vh * b.channels() * 4) as u64);
        }
        encoder.copy_buffer_to_buffer(&host.upload, host.stats_at, &self.stats, 0, 16);
        Ok(())
    }

    /// Map the staging buffer if a failed frame left it unmapped (a frame ends with it mapped).
    fn map_upload(&self, host: &HostIo) -> Result<()> {
        if !host.upload_mapped.load(Ordering::Relaxed) {
            map_and_wait(&self.device, &host.upload, wgpu::MapMode::Write)?;
            host.upload_mapped.store(true, Ordering::Relaxed);
        }
        Ok(())
    }

    /// Copy the frame's host slices into the mapped staging buffer, unmap it and record its
    /// copies into the input buffers.
    fn upload(&self, host: &HostIo, frame: &FrameInputs, encoder: &mut wgpu::CommandEncoder) -> Result<()> {
        self.map_upload(host)?;
        {
            let mut view = host.upload.get_mapped_range_mut(..).map_err(|e| Error::Gpu(format!("staging buffer: {e:?}")))?;
            for ((b, buf), &off) in host.inputs.iter().zip(&host.offsets) {
                let src: &[u8] = bytemuck::cast_slice(frame.get(*b).expect("validated"));
                view.slice(off as usize..off as usize + src.len()).copy_from_slice(src);
                debug_assert_eq!(src.len() as u64, buf.size());
            }
            if let (Some((buf, off)), Some(m)) = (&host.motion, frame.motion) {
                let src: &[u8] = bytemuck::cast_slice(m);
                view.slice(*off as usize..*off as usize + src.len()).copy_from_slice(src);
                debug_assert_eq!(src.len() as u64, buf.size());
            }
        }
        host.upload.unmap();
        host.upload_mapped.store(false, Ordering::Relaxed);
        for ((_, buf), &off) in host.inputs.iter().zip(&host.offsets) {
            encoder.copy_buffer_to_buffer(&host.upload, off, buf, 0, buf.size());
        }
        if let (Some((buf, off)), Some(_)) = (&host.motion, frame.motion) {
            encoder.copy_buffer_to_buffer(&host.upload, *off, buf, 0, buf.size());
        }
        Ok(())
    }

    /// Check a host frame: the model's buffers present at the frame size, and motion only where
    /// the denoiser was built for it.
    fn validate(&self, frame: &FrameInputs) -> Result<()> {
        frame.validate(&self.arch.required_buffers(), self.width, self.height)?;
        if frame.motion.is_some() && self.motion.is_none() {
            return Err(Error::Motion("the frame has motion, but the denoiser was built without it (Options::motion)".into()));
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
        if self.tiles.is_some() {
            return Err(Error::Tiled("per-stage times are taken on whole frames"));
        }
        self.validate(frame)?;
        self.ensure_host_io()?;
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
        let recorded = uploaded.and_then(|_| self.record_with(&mut encoder, &host.binding, Some(&prof.queries), frame.motion.is_some()));
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

    /// Makes the host transfer buffers at the first frame that needs them; wgpu's validation
    /// and out-of-memory errors while allocating them are an [`Error::Gpu`].
    pub(super) fn ensure_host_io(&mut self) -> Result<()> {
        if self.host.is_none() {
            let host = super::build::catching_gpu_errors(&self.device, "allocating the host transfer buffers", || self.make_host_io())?;
            self.host = Some(host);
        }
        Ok(())
    }

    fn make_host_io(&self) -> Result<HostIo> {
        // A frame's buffers, or a tile's: its extent's inputs and its interior's output.
        let (pixels, out_pixels) = match &self.tiles {
            None => (self.width as u64 * self.height as u64, self.width as u64 * self.height as u64),
            Some(t) => {
                let (iw, ih) = t.plan.max_interior();
                (self.pwidth as u64 * self.pheight as u64, iw as u64 * ih as u64)
            }
        };
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
        // A tiled frame's output bound (the largest prepared color of the whole frame), which
        // each tile's prep then only raises: the same bound as the frame run whole.
        let stats_at = staged;
        staged += 16;
        let motion = self.motion.as_ref().map(|_| {
            let at = staged;
            staged += pixels * 8;
            (buffer("motion", pixels * 8, wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST), at)
        });
        let upload = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("upload staging"),
            size: staged,
            usage: wgpu::BufferUsages::MAP_WRITE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: true,
        });
        let output = buffer("output", out_pixels * 12, wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC);
        let readback = buffer("readback", out_pixels * 12, wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST);
        let io = GpuFrameIo::from_inputs(&inputs, motion.as_ref().map(|(b, _)| b), &output);
        let (binding, tile_groups) = match &self.tiles {
            None => (self.bind_io(&io)?, Vec::new()),
            Some(t) => {
                let groups: Vec<_> = t.prep_params.iter().zip(&t.output_params).map(|(p, o)| self.io_groups(&io, p, o)).collect();
                let (prep, output) = groups[0].clone();
                (IoBinding { owner: self.id, prep, output, motion: None, accumulate: None }, groups)
            }
        };
        Ok(HostIo {
            inputs,
            offsets,
            stats_at,
            motion,
            upload,
            upload_mapped: std::sync::atomic::AtomicBool::new(true),
            output,
            readback,
            binding,
            tile_groups,
        })
    }

    /// The packed network input of the last frame, channel-major (`channels x ph x pw`), for
    /// checking the prep kernel. The frame's convs write over the input's arena cells once its
    /// one reader has run, so prep runs again on the last frame's uploaded buffers first.
    pub fn read_input(&self) -> Result<Vec<f32>> {
        let host = self.host.as_ref().ok_or_else(|| Error::Gpu("read_input: no frame has been denoised".into()))?;
        let mut encoder = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("rae prep again") });
        {
            let mut pass =
                encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("rae prep again"), timestamp_writes: None });
            pass.set_pipeline(&self.prep);
            pass.set_bind_group(0, &host.binding.prep, &[]);
            pass.dispatch_workgroups(self.pwidth.div_ceil(WORKGROUP), self.pheight.div_ceil(WORKGROUP), 1);
        }
        self.queue.submit(Some(encoder.finish()));
        let (arena, place) = &self.input_at;
        let all = read_texture(&self.device, &self.queue, arena)?;
        let (w, h) = (self.pwidth as usize, self.pheight as usize);
        let (c, first) = (self.graph.in_channels, place.first as usize);
        Ok((0..c * h * w)
            .map(|i| {
                let (ch, p) = (i / (h * w), i % (h * w));
                all[((first + ch / 4) * h * w + p) * 4 + ch % 4]
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
}

/// After a host-path frame's submit: map the staging buffer for the next frame's writes and the
/// readback for this frame's output in one poll, then copy the output into `out`.
pub(super) fn finish_host_frame(device: &wgpu::Device, host: &HostIo, out: &mut [f32]) -> Result<()> {
    let n = out.len();
    finish_host_io(device, host, |data| out.copy_from_slice(&data[..n]))
}

/// Map the staging buffer for the next upload and the readback for `deliver`, in one poll.
fn finish_host_io(device: &wgpu::Device, host: &HostIo, deliver: impl FnOnce(&[f32])) -> Result<()> {
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
        deliver(bytemuck::cast_slice::<u8, f32>(&view));
    }
    host.readback.unmap();
    Ok(())
}

/// Map all of `buffer` and wait for the GPU until it is mapped.
pub(super) fn map_and_wait(device: &wgpu::Device, buffer: &wgpu::Buffer, mode: wgpu::MapMode) -> Result<()> {
    let (tx, rx) = std::sync::mpsc::channel();
    buffer.map_async(mode, .., move |r| {
        let _ = tx.send(r);
    });
    device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| Error::Gpu(e.to_string()))?;
    rx.recv().map_err(|e| Error::Gpu(e.to_string()))?.map_err(|e| Error::Gpu(e.to_string()))
}

/// Map a MAP_READ buffer and copy its f32s into `out`.
pub(super) fn read_buffer(device: &wgpu::Device, buffer: &wgpu::Buffer, out: &mut [f32]) -> Result<()> {
    map_and_wait(device, buffer, wgpu::MapMode::Read)?;
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

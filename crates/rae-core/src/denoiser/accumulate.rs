//! The output's temporal accumulation on the GPU (shaders/accumulate.wgsl; [`crate::accumulate`]
//! is its CPU reference): what a [`Denoiser`] built with [`Options::accumulate`] holds for it.
//!
//! The output pass writes the network's radiance into `current` instead of the caller's
//! output; the accumulation pass then blends it with the previous frame's accumulated output
//! along the frame's motion and writes the result into the caller's output and into the next
//! frame's history. The two history buffers alternate with the hidden state's parity: frame
//! parity `p` reads `history[p]` and writes `history[1 - p]`. A frame without history (the
//! first, a reset, one without motion) passes `current` through and starts the history.

use super::*;
use crate::kernels::AccumulateKernel;

/// accumulate.wgsl's uniform block.
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct AccumulateParams {
    width: u32,
    height: u32,
    limit: f32,
    history: u32,
}

/// The accumulation's resources: made once, at build.
pub(super) struct Accumulation {
    kernel: AccumulateKernel,
    /// `[without history, with history]`.
    params: [wgpu::Buffer; 2],
    /// The network's radiance, which the output pass writes.
    pub(super) current: wgpu::Buffer,
    /// The accumulated output of the last two frames.
    history: [wgpu::Buffer; 2],
    size: (u32, u32),
    /// Bytes of the buffers.
    pub(super) bytes: u64,
}

/// The accumulation's bind groups over one set of caller buffers ([`IoBinding`]).
pub(super) struct AccumulateIo {
    /// The output pass writing into [`Accumulation::current`].
    pub(super) output: wgpu::BindGroup,
    /// `[history][parity]`: the accumulation pass.
    pub(super) groups: [[wgpu::BindGroup; 2]; 2],
}

/// Bytes the accumulation holds at a frame of `width` x `height`: three RGB f32 frames.
pub fn accumulate_bytes(width: u32, height: u32) -> u64 {
    3 * width as u64 * height as u64 * 12 + 2 * 16
}

impl Accumulation {
    /// The accumulation's buffers and pipeline for frames of `width` x `height`.
    pub(super) fn new(device: &wgpu::Device, width: u32, height: u32) -> Self {
        let frame = |label| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: width as u64 * height as u64 * 12,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            })
        };
        let limit = crate::frame::MOTION_ABSURD * width.max(height) as f32;
        let params = [0, 1].map(|history| {
            let p = AccumulateParams { width, height, limit, history };
            create_init(device, "accumulate params", bytemuck::bytes_of(&p), wgpu::BufferUsages::UNIFORM)
        });
        Accumulation {
            kernel: AccumulateKernel::new(device),
            params,
            current: frame("accumulate current"),
            history: [frame("accumulate history"), frame("accumulate history")],
            size: (width, height),
            bytes: accumulate_bytes(width, height),
        }
    }

    /// The accumulation pass's bind groups over the caller's `motion` (any buffer where the
    /// caller has none: frames without motion have no history) and `output`.
    pub(super) fn groups(&self, device: &wgpu::Device, motion: &wgpu::Buffer, output: &wgpu::Buffer) -> [[wgpu::BindGroup; 2]; 2] {
        std::array::from_fn(|history| {
            std::array::from_fn(|parity| {
                let entries = [
                    self.params[history].as_entire_binding(),
                    self.current.as_entire_binding(),
                    self.history[parity].as_entire_binding(),
                    motion.as_entire_binding(),
                    output.as_entire_binding(),
                    self.history[1 - parity].as_entire_binding(),
                ];
                let entries: Vec<wgpu::BindGroupEntry> =
                    entries.into_iter().enumerate().map(|(i, resource)| wgpu::BindGroupEntry { binding: i as u32, resource }).collect();
                device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("accumulate"),
                    layout: &self.kernel.layout,
                    entries: &entries,
                })
            })
        })
    }

    /// Record the accumulation pass with `group` into `pass`.
    pub(super) fn record(&self, pass: &mut wgpu::ComputePass, group: &wgpu::BindGroup) {
        pass.set_pipeline(&self.kernel.pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.dispatch_workgroups(self.size.0.div_ceil(WORKGROUP), self.size.1.div_ceil(WORKGROUP), 1);
    }

    /// One workgroup of the pass: compiles its pipeline on a CPU driver
    /// ([`Denoiser::compile_backwards`]).
    pub(super) fn record_one(&self, pass: &mut wgpu::ComputePass, group: &wgpu::BindGroup) {
        pass.set_pipeline(&self.kernel.pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.dispatch_workgroups(1, 1, 1);
    }
}

//! Reprojection of the hidden state with motion vectors (shaders/motion.wgsl): what a
//! [`Denoiser`] built with [`Options::motion`] holds for it, and the passes of a frame.
//!
//! On a frame with motion and history, before any conv: the frame's motion goes into a pyramid
//! of one rgba32float texture per level (mean motion in that level's pixels, fraction of valid
//! pixels), then each recurrent block's previous state is fetched at `x + motion` of its level
//! into the texture the block writes its new state into later in the frame (free until then),
//! and the block's recurrent conv reads it from there ([`Motion::conv_groups`]). Without motion
//! (or on a reset frame) none of this runs and the convs read the previous state as it is.
//!
//! The validity of each pixel's history is its motion's times the history test against the
//! previous frame's guide (normal and prepared depth, one rgba32float texture at the padded
//! size, for models that read either): `guide_store` keeps every frame's guide, with or without
//! motion, so the frame after any frame can reproject.

use super::*;

fn view(v: &wgpu::TextureView) -> wgpu::BindingResource<'_> {
    wgpu::BindingResource::TextureView(v)
}

/// The motion resources of a [`Denoiser`]: made once, at build.
pub(super) struct Motion {
    /// motion.wgsl's uniform block.
    pub(super) params: wgpu::Buffer,
    /// Level 0 of the pyramid, which `motion_in` writes.
    pub(super) level0: wgpu::TextureView,
    /// Each level's size (padded size >> k), k = 0 ..= levels.
    sizes: Vec<(u32, u32)>,
    /// `motion_down` from level k to k + 1.
    down: Vec<wgpu::BindGroup>,
    /// `[parity][block]`: block k's previous state warped into its next slot.
    warp: [Vec<wgpu::BindGroup>; 2],
    /// Each recurrent block's level and channel blocks, in the order of `warp`.
    blocks: Vec<(usize, u32)>,
    /// `[parity][node]`: the bind group of a conv that reads a hidden state, reading it warped
    /// (`None` for the convs that read none).
    pub(super) conv_groups: [Vec<Option<wgpu::BindGroup>>; 2],
    /// The previous frame's guide, which `motion_in` reads (1 x 1 for a model without one).
    pub(super) guide: wgpu::TextureView,
    /// `guide_store`'s bind group, for a model with a guide.
    guide_store: Option<wgpu::BindGroup>,
    /// Bytes of the pyramid, the guide and the parameters.
    pub(super) bytes: u64,
}

/// Bytes of the motion pyramid, the guide (`guided`: the model reads normal or depth) and the
/// parameters for `levels` levels below a padded frame of `pwidth` x `pheight`: what
/// [`Options::motion`] adds to a [`Denoiser`] (needs no device).
pub fn motion_bytes(pwidth: u32, pheight: u32, levels: usize, guided: bool) -> u64 {
    let level = |k: usize| (pwidth >> k) as u64 * (pheight >> k) as u64 * 16;
    (0..=levels).map(level).sum::<u64>() + if guided { level(0) } else { 16 } + 16
}

impl Motion {
    /// The motion resources for `graph` at the padded size, bound to its activations.
    pub(super) fn new(
        device: &wgpu::Device,
        kernels: &mut Kernels,
        graph: &Graph,
        acts: &Activations,
        convs: &ConvPlan,
        guide: Guide,
        size: (u32, u32, u32, u32),
    ) -> Motion {
        let (width, height, pwidth, pheight) = size;
        let levels = graph.hidden.iter().map(|&(_, level)| level).max().unwrap_or(0);
        let sizes: Vec<(u32, u32)> = (0..=levels).map(|k| (pwidth >> k, pheight >> k)).collect();
        let texture = |label, (w, h): (u32, u32)| {
            let t = device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba32Float,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::STORAGE_BINDING,
                view_formats: &[],
            });
            t.create_view(&Default::default())
        };
        let views: Vec<wgpu::TextureView> = sizes.iter().map(|&s| texture("motion", s)).collect();
        let guide_view = texture("guide", if guide.any() { sizes[0] } else { (1, 1) });
        let limit = crate::frame::MOTION_ABSURD * width.max(height) as f32;
        let params = MotionParams { width, height, limit, _pad: 0 };
        let params = create_init(device, "motion params", bytemuck::bytes_of(&params), wgpu::BufferUsages::UNIFORM);
        let k = kernels.motion(device, guide);
        let group = |layout: &wgpu::BindGroupLayout, entries: &[(u32, wgpu::BindingResource)]| {
            let entries: Vec<wgpu::BindGroupEntry> =
                entries.iter().map(|(binding, resource)| wgpu::BindGroupEntry { binding: *binding, resource: resource.clone() }).collect();
            device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some("motion"), layout, entries: &entries })
        };
        let down = (0..levels).map(|l| group(&k.down_layout, &[(3, view(&views[l])), (4, view(&views[l + 1]))])).collect();
        let blocks: Vec<(usize, u32)> = graph.hidden.iter().map(|&(c, level)| (level, blocks(c))).collect();
        let warp = std::array::from_fn(|parity| {
            (0..graph.hidden.len())
                .map(|b| {
                    let (prev, next) = (acts.view(Value::HiddenPrev(b), parity), acts.view(Value::HiddenNew(b), parity));
                    group(&k.warp_layout, &[(5, view(&views[blocks[b].0])), (6, view(prev)), (7, view(next))])
                })
                .collect()
        });
        let guide_store = guide.any().then(|| group(&k.guide_layout, &[(8, view(acts.view(Value::Input, 0))), (10, view(&guide_view))]));
        let conv_groups = std::array::from_fn(|parity| {
            graph
                .nodes
                .iter()
                .enumerate()
                .map(|(i, node)| {
                    let Some(Source { value: Value::HiddenPrev(b), .. }) = node.b else { return None };
                    let (a, out) = (acts.view(node.a.value, parity), acts.view(node.out, parity));
                    let warped = acts.view(Value::HiddenNew(b), parity);
                    Some(convs.bind_group(device, kernels, i, a, warped, out, acts.pooled_by(graph, i)))
                })
                .collect()
        });
        let bytes = motion_bytes(pwidth, pheight, levels, guide.any());
        Motion { params, level0: views[0].clone(), sizes, down, warp, blocks, conv_groups, guide: guide_view, guide_store, bytes }
    }

    /// Record `guide_store` (every frame, after [`Self::record`] where that runs).
    pub(super) fn record_guide(&self, pass: &mut wgpu::ComputePass, kernels: &MotionKernels) {
        if let Some(g) = &self.guide_store {
            pass.set_pipeline(&kernels.guide_store);
            pass.set_bind_group(0, g, &[]);
            pass.dispatch_workgroups(self.sizes[0].0.div_ceil(WORKGROUP), self.sizes[0].1.div_ceil(WORKGROUP), 1);
        }
    }

    /// Record the pyramid from the frame's motion (`io`: `motion_in`'s bind group) and every
    /// block's warp into `pass`.
    pub(super) fn record(&self, pass: &mut wgpu::ComputePass, kernels: &MotionKernels, io: &wgpu::BindGroup, parity: usize) {
        let groups = |(w, h): (u32, u32)| (w.div_ceil(WORKGROUP), h.div_ceil(WORKGROUP));
        let (x, y) = groups(self.sizes[0]);
        pass.set_pipeline(&kernels.motion_in);
        pass.set_bind_group(0, io, &[]);
        pass.dispatch_workgroups(x, y, 1);
        pass.set_pipeline(&kernels.motion_down);
        for (l, g) in self.down.iter().enumerate() {
            let (x, y) = groups(self.sizes[l + 1]);
            pass.set_bind_group(0, g, &[]);
            pass.dispatch_workgroups(x, y, 1);
        }
        pass.set_pipeline(&kernels.warp);
        for (g, &(level, layers)) in self.warp[parity].iter().zip(&self.blocks) {
            let (x, y) = groups(self.sizes[level]);
            pass.set_bind_group(0, g, &[]);
            pass.dispatch_workgroups(x, y, layers);
        }
    }
}

//! The WGSL kernels: one table of sources, their bind-group layouts, pipelines specialised by
//! override constants, the uniform parameter blocks, and the weight layout the conv reads.

use std::collections::HashMap;

use bytemuck::{Pod, Zeroable};

use crate::graph::{ConvNode, Read};
use crate::weights::Weights;

/// Every shader of rae, by name; the only place WGSL enters the crate.
pub const SHADERS: &[(&str, &str)] = &[
    ("conv3x3", include_str!("../../../shaders/conv3x3.wgsl")),
    ("prep", include_str!("../../../shaders/prep.wgsl")),
    ("output", include_str!("../../../shaders/output.wgsl")),
];

/// Output rows per conv invocation (`ROWS` in conv3x3.wgsl).
pub const CONV_ROWS: u32 = 4;
/// Width of the weight texture in vec4s (`WEIGHT_ROW` in conv3x3.wgsl).
pub const WEIGHT_ROW: u32 = 4096;
/// Workgroup size in x and y of every kernel.
pub const WORKGROUP: u32 = 8;
/// Texture format of activations: a layer holds 4 channels.
pub const ACTIVATION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// Source text of a shader from [`SHADERS`].
pub fn shader_source(name: &str) -> &'static str {
    SHADERS.iter().find(|(n, _)| *n == name).map(|(_, s)| *s).expect("shader is in the table")
}

/// Channel blocks (texture layers) needed for `channels`.
pub fn blocks(channels: usize) -> u32 {
    channels.div_ceil(4) as u32
}

/// Uniform block of conv3x3.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct ConvParams {
    /// Output width.
    pub width: u32,
    /// Output height.
    pub height: u32,
    /// Blocks read from source a.
    pub cin4_a: u32,
    /// Blocks read from source b (0 when absent or when a reset hidden state is skipped).
    pub cin4_b: u32,
    /// Input blocks in the weight layout.
    pub cin4_total: u32,
    /// Output blocks stored.
    pub cout4: u32,
    /// Offset of the bias, in vec4s.
    pub b_offset: u32,
    /// Offset of the taps, in vec4s.
    pub t_offset: u32,
    /// LeakyReLU slope.
    pub slope: f32,
    /// Padding to 48 bytes.
    pub _pad: [u32; 3],
}

/// Uniform block of prep.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct PrepParams {
    /// Frame width.
    pub width: u32,
    /// Frame height.
    pub height: u32,
    /// Padded width.
    pub pwidth: u32,
    /// Padded height.
    pub pheight: u32,
    /// Channel offsets of color, albedo, normal, depth, roughness (`u32::MAX`: not packed).
    pub offsets: [u32; 5],
    /// Layers written.
    pub layers: u32,
    /// 1: demodulate.
    pub demodulate: u32,
    /// 0: none, 1: log1p.
    pub transfer: u32,
    /// Demodulation epsilon.
    pub albedo_eps: f32,
    /// Padding to 64 bytes.
    pub _pad: [u32; 3],
}

/// Uniform block of output.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct OutputParams {
    /// Frame width.
    pub width: u32,
    /// Frame height.
    pub height: u32,
    /// 1: remodulate.
    pub demodulate: u32,
    /// 0: none, 1: log1p.
    pub transfer: u32,
    /// Demodulation epsilon.
    pub albedo_eps: f32,
    /// Padding to 32 bytes.
    pub _pad: [u32; 3],
}

fn uniform_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn texture_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2Array,
            multisampled: false,
        },
        count: None,
    }
}

fn weight_texture_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

fn storage_texture_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::StorageTexture {
            access: wgpu::StorageTextureAccess::WriteOnly,
            format: ACTIVATION_FORMAT,
            view_dimension: wgpu::TextureViewDimension::D2Array,
        },
        count: None,
    }
}

/// Key of a specialised conv pipeline.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ConvVariant {
    /// Read mode of source a.
    pub read_a: Read,
    /// Read mode of source b (Direct when there is none).
    pub read_b: Read,
    /// LeakyReLU or linear.
    pub leaky: bool,
}

impl ConvVariant {
    /// The variant a node needs.
    pub fn of(node: &ConvNode) -> Self {
        Self { read_a: node.a.read, read_b: node.b.map_or(Read::Direct, |b| b.read), leaky: node.leaky }
    }
}

/// Shader modules, layouts and pipelines of one device; conv pipelines are cached by variant.
pub struct Kernels {
    /// Layout of conv3x3.wgsl's group 0.
    pub conv_layout: wgpu::BindGroupLayout,
    /// Layout of prep.wgsl's group 0.
    pub prep_layout: wgpu::BindGroupLayout,
    /// Layout of output.wgsl's group 0.
    pub output_layout: wgpu::BindGroupLayout,
    /// The input-preparation pipeline.
    pub prep: wgpu::ComputePipeline,
    /// The output pipeline.
    pub output: wgpu::ComputePipeline,
    conv_module: wgpu::ShaderModule,
    conv_pipeline_layout: wgpu::PipelineLayout,
    conv: HashMap<ConvVariant, wgpu::ComputePipeline>,
}

impl Kernels {
    /// Compile the modules and the fixed pipelines.
    pub fn new(device: &wgpu::Device) -> Self {
        let module = |name: &str| {
            device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(name),
                source: wgpu::ShaderSource::Wgsl(shader_source(name).into()),
            })
        };
        let layout = |label, entries: &[wgpu::BindGroupLayoutEntry]| {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries })
        };
        let conv_layout = layout(
            "conv3x3",
            &[uniform_entry(0), texture_entry(1), texture_entry(2), weight_texture_entry(3), storage_texture_entry(4)],
        );
        let prep_layout = layout(
            "prep",
            &[
                uniform_entry(0),
                storage_entry(1, true),
                storage_entry(2, true),
                storage_entry(3, true),
                storage_entry(4, true),
                storage_entry(5, true),
                storage_texture_entry(6),
            ],
        );
        let output_layout =
            layout("output", &[uniform_entry(0), texture_entry(1), storage_entry(2, true), storage_entry(3, false)]);
        let pipeline_layout = |bgl: &wgpu::BindGroupLayout| {
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: None,
                bind_group_layouts: &[Some(bgl)],
                immediate_size: 0,
            })
        };
        let pipeline = |label, layout: &wgpu::PipelineLayout, module: &wgpu::ShaderModule, constants: &[(&str, f64)]| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(label),
                layout: Some(layout),
                module,
                entry_point: Some("main"),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants,
                    zero_initialize_workgroup_memory: false,
                },
                cache: None,
            })
        };
        let prep = pipeline("prep", &pipeline_layout(&prep_layout), &module("prep"), &[]);
        let output = pipeline("output", &pipeline_layout(&output_layout), &module("output"), &[]);
        Self {
            conv_pipeline_layout: pipeline_layout(&conv_layout),
            conv_module: module("conv3x3"),
            conv_layout,
            prep_layout,
            output_layout,
            prep,
            output,
            conv: HashMap::new(),
        }
    }

    /// The conv pipeline for a variant, created on first use.
    pub fn conv(&mut self, device: &wgpu::Device, v: ConvVariant) -> wgpu::ComputePipeline {
        let (module, layout) = (&self.conv_module, &self.conv_pipeline_layout);
        self.conv
            .entry(v)
            .or_insert_with(|| {
                let constants = [
                    ("MODE_A", v.read_a as u32 as f64),
                    ("MODE_B", v.read_b as u32 as f64),
                    ("LEAKY", if v.leaky { 1.0 } else { 0.0 }),
                ];
                device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some("conv3x3"),
                    layout: Some(layout),
                    module,
                    entry_point: Some("main"),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants: &constants,
                        zero_initialize_workgroup_memory: false,
                    },
                    cache: None,
                })
            })
            .clone()
    }
}

/// Workgroups of a conv dispatch at `width` x `height` with `cout` output channels.
pub fn conv_workgroups(width: u32, height: u32, cout: usize) -> (u32, u32, u32) {
    (
        width.div_ceil(WORKGROUP),
        height.div_ceil(CONV_ROWS).div_ceil(WORKGROUP),
        blocks(cout),
    )
}

/// A conv's bias and taps in the kernel's layout, appended to `out`; returns (bias, taps)
/// offsets in vec4s.
///
/// Bias: one vec4 per output block. Taps:
/// `[out block][in block][ky*3+kx][in lane]` -> vec4 over the block's 4 output channels. Input
/// blocks follow the sources: source a's channels padded to a multiple of 4, then source b's, so
/// the kernel reads each source's texture layers without a concat. Padding weights are zero, so
/// padding channels (always written as zero) contribute nothing.
pub fn pack_conv(weight: &[f32], bias: &[f32], cout: usize, ca: usize, cb: usize, out: &mut Vec<[f32; 4]>) -> (u32, u32) {
    let cin = ca + cb;
    debug_assert_eq!(weight.len(), cout * cin * 9);
    let (ba, bb) = (blocks(ca) as usize, blocks(cb) as usize);
    let cout4 = blocks(cout) as usize;
    let b_offset = out.len() as u32;
    for ob in 0..cout4 {
        out.push(std::array::from_fn(|l| bias.get(4 * ob + l).copied().unwrap_or(0.0)));
    }
    let t_offset = out.len() as u32;
    // Input channel of (input block, lane), or None for padding.
    let channel = |ib: usize, lane: usize| -> Option<usize> {
        if ib < ba {
            let c = 4 * ib + lane;
            (c < ca).then_some(c)
        } else {
            let c = 4 * (ib - ba) + lane;
            (c < cb).then_some(ca + c)
        }
    };
    for ob in 0..cout4 {
        for ib in 0..ba + bb {
            for tap in 0..9 {
                for lane in 0..4 {
                    out.push(std::array::from_fn(|l| {
                        let o = 4 * ob + l;
                        match channel(ib, lane) {
                            Some(i) if o < cout => weight[(o * cin + i) * 9 + tap],
                            _ => 0.0,
                        }
                    }));
                }
            }
        }
    }
    (b_offset, t_offset)
}

/// Pack every conv of `nodes` from `weights` into one buffer's contents; returns the data and
/// each node's (bias, taps) offsets.
pub fn pack_all(nodes: &[ConvNode], weights: &Weights) -> (Vec<[f32; 4]>, Vec<(u32, u32)>) {
    let mut data = Vec::new();
    let offsets = nodes
        .iter()
        .map(|n| {
            let w = weights.get(&format!("{}.weight", n.name)).expect("validated at load");
            let b = weights.get(&format!("{}.bias", n.name)).expect("validated at load");
            pack_conv(&w.data, &b.data, n.cout, n.a.channels, n.b.map_or(0, |b| b.channels), &mut data)
        })
        .collect();
    (data, offsets)
}

/// Upload packed weights as the rgba32float texture conv3x3.wgsl reads, [`WEIGHT_ROW`] wide.
pub fn weight_texture(device: &wgpu::Device, queue: &wgpu::Queue, packed: &[[f32; 4]]) -> wgpu::Texture {
    use wgpu::util::DeviceExt;
    let rows = (packed.len() as u32).div_ceil(WEIGHT_ROW).max(1);
    let mut data = packed.to_vec();
    data.resize((rows * WEIGHT_ROW) as usize, [0.0; 4]);
    device.create_texture_with_data(
        queue,
        &wgpu::TextureDescriptor {
            label: Some("weights"),
            size: wgpu::Extent3d { width: WEIGHT_ROW, height: rows, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: ACTIVATION_FORMAT,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        bytemuck::cast_slice(&data),
    )
}

//! Bind-group layouts, the uniform parameter blocks, and [`Kernels`]: one device's shader
//! modules and its conv pipelines, cached by [`ConvVariant`] and created side by side.

use std::collections::HashMap;

use bytemuck::{Pod, Zeroable};

use super::*;
use crate::graph::Read;

/// A WGSL module from source text.
fn shader_module(device: &wgpu::Device, label: &str, source: String) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor { label: Some(label), source: wgpu::ShaderSource::Wgsl(source.into()) })
}

/// Uniform block of conv3x3.wgsl: one per (dispatch, reset).
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
    /// First output block of the dispatch's first group (workgroup z = 0).
    pub ob0: u32,
    /// Output blocks of the conv (groups past it store nothing).
    pub cout4: u32,
    /// LeakyReLU slope.
    pub slope: f32,
    /// vec4s between the weight chunks of consecutive groups in one binding (workgroup z).
    pub group_stride: u32,
    /// Winograd lanes tiles ([`Method::is_winograd_lanes`]): the weight-texture texel where the
    /// dispatch's first group's chunk starts (0 for the others, which bind their chunk by offset).
    pub weight_texel: u32,
    /// 1 where the conv writes its output max-pooled too (conv3x3.wgsl's `pools`, where its
    /// pipeline has the pooled store: [`ConvVariant::pool`]); 0 else.
    pub pool_out: u32,
    /// Padding to the uniform's 16-byte size.
    pub _pad: u32,
    /// Where source a's cells are, where carved ([`ConvVariant::carve_a`]).
    pub carve_a: Carve,
    /// Where source b's cells are, where carved.
    pub carve_b: Carve,
    /// Where the output's cells are, where carved.
    pub carve_dst: Carve,
    /// Where the pooled output's cells are (always carved: a level below the output's).
    pub carve_pool: Carve,
}

/// Uniform block of prep.wgsl: the sizes (the model's layout is [`PrepLayout`], overrides).
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
}

/// How a model packs its input (prep.wgsl's override constants): fixed per model, so each
/// [`crate::Denoiser`] builds its own prep pipeline ([`Kernels::prep_pipeline`]) and the kernel
/// knows at compile time which buffer feeds each channel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PrepLayout {
    /// First channel of color, albedo, normal, depth, roughness in the packed input (`None`:
    /// not packed).
    pub offsets: [Option<u32>; 5],
    /// Channel blocks written.
    pub layers: u32,
    /// Color is divided by (albedo + `albedo_eps`).
    pub demodulate: bool,
    /// Color goes through log1p.
    pub log1p: bool,
    /// Demodulation epsilon.
    pub albedo_eps: f32,
}

impl PrepLayout {
    /// The pipeline constants that specialise prep.wgsl to this layout.
    fn constants(&self, store_max: f32) -> Vec<(&'static str, f64)> {
        let names = ["OFF_COLOR", "OFF_ALBEDO", "OFF_NORMAL", "OFF_DEPTH", "OFF_ROUGHNESS"];
        let mut c: Vec<(&'static str, f64)> = names.iter().zip(self.offsets).map(|(&n, o)| (n, o.unwrap_or(u32::MAX) as f64)).collect();
        c.extend([
            ("LAYERS", self.layers as f64),
            ("DEMODULATE", if self.demodulate { 1.0 } else { 0.0 }),
            ("TRANSFER", if self.log1p { 1.0 } else { 0.0 }),
            ("ALBEDO_EPS", self.albedo_eps as f64),
            ("STORE_MAX", store_max as f64),
        ]);
        c
    }
}

/// Uniform block of output.wgsl: the rectangle of the network's output written (the frame, or
/// a frame tile's interior), how the input buffers are laid out, and the model's output stage.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct OutputParams {
    /// First column read from the network output.
    pub x0: u32,
    /// First row read from the network output.
    pub y0: u32,
    /// Width written (the output buffer's row length).
    pub width: u32,
    /// Height written.
    pub height: u32,
    /// Row length of the input buffers, whose pixel `(x, y)` is the network's `(x, y)`.
    pub in_stride: u32,
    /// 1: remodulate.
    pub demodulate: u32,
    /// 0: none, 1: log1p.
    pub transfer: u32,
    /// Demodulation epsilon.
    pub albedo_eps: f32,
    /// Which buffers tell a miss ([`crate::Arch::miss_by`]): bit 0 depth, bit 1 normal.
    pub miss_by: u32,
    /// Padding to the uniform's 16-byte size.
    pub _pad: [u32; 3],
}

impl OutputParams {
    /// `arch`'s output stage over the `width x height` rectangle at `(x0, y0)` of the network's
    /// output, its input buffers `in_stride` pixels a row.
    pub fn new(arch: &crate::Arch, (x0, y0): (u32, u32), (width, height): (u32, u32), in_stride: u32) -> Self {
        let (by_depth, by_normal) = arch.miss_by();
        Self {
            x0,
            y0,
            width,
            height,
            in_stride,
            demodulate: arch.demodulate as u32,
            transfer: match arch.transfer {
                crate::model::Transfer::None => 0,
                crate::model::Transfer::Log1p => 1,
            },
            albedo_eps: arch.albedo_eps,
            miss_by: by_depth as u32 | (by_normal as u32) << 1,
            _pad: [0; 3],
        }
    }
}

/// Uniform block of motion.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct MotionParams {
    /// Frame width.
    pub width: u32,
    /// Frame height.
    pub height: u32,
    /// The largest valid |motion| component, in pixels.
    pub limit: f32,
    /// Padding to 16 bytes.
    pub _pad: u32,
}

/// The layouts and pipelines of motion.wgsl, the reprojection of the hidden state
/// ([`Kernels::motion`]): made only for denoisers that take motion.
pub struct MotionKernels {
    /// Layout of `motion_in`: parameters, the frame's motion buffer, level 0, the packed input,
    /// the previous frame's guide.
    pub in_layout: wgpu::BindGroupLayout,
    /// Layout of `guide_store`: the packed input, the guide written.
    pub guide_layout: wgpu::BindGroupLayout,
    /// Layout of `motion_down`: a level, the next.
    pub down_layout: wgpu::BindGroupLayout,
    /// Layout of `warp`: a level's motion, the previous state, the warped state.
    pub warp_layout: wgpu::BindGroupLayout,
    /// The frame's motion into level 0.
    pub motion_in: wgpu::ComputePipeline,
    /// Level k + 1 from level k.
    pub motion_down: wgpu::ComputePipeline,
    /// A block's previous state, reprojected.
    pub warp: wgpu::ComputePipeline,
    /// This frame's guide, kept for the next frame's history test.
    pub guide_store: wgpu::ComputePipeline,
}

/// accumulate.wgsl's pipeline: the output's temporal accumulation (made once per
/// [`crate::Denoiser`] built with [`crate::Options::accumulate`]).
pub struct AccumulateKernel {
    /// Layout of its group 0: parameters, the network's radiance, the previous accumulated
    /// output, the frame's motion, the caller's output, the next history.
    pub layout: wgpu::BindGroupLayout,
    /// The pipeline.
    pub pipeline: wgpu::ComputePipeline,
}

impl AccumulateKernel {
    /// Compile accumulate.wgsl on `device`.
    pub fn new(device: &wgpu::Device) -> Self {
        let entries = [
            uniform_entry(0),
            storage_entry(1, true),
            storage_entry(2, true),
            storage_entry(3, true),
            storage_entry(4, false),
            storage_entry(5, false),
        ];
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some("accumulate"), entries: &entries });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: None,
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("accumulate"),
            layout: Some(&pipeline_layout),
            module: &shader_module(device, "accumulate", shader_source("accumulate").to_string()),
            entry_point: Some("main"),
            compilation_options: Default::default(),
            cache: None,
        });
        AccumulateKernel { layout, pipeline }
    }
}

/// Where a model's guide of the history test is in its packed input (motion.wgsl's overrides):
/// the first channel of normal and of depth, `None` where it reads none.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Guide {
    /// First channel of the normal.
    pub normal: Option<u32>,
    /// The depth channel.
    pub depth: Option<u32>,
}

impl Guide {
    /// The guide of a model whose input is packed as `layout` says.
    pub fn of(layout: &PrepLayout) -> Guide {
        Guide { normal: layout.offsets[2], depth: layout.offsets[3] }
    }

    /// Whether the model reads any guide buffer (else every history passes the test).
    pub fn any(&self) -> bool {
        self.normal.is_some() || self.depth.is_some()
    }
}

impl MotionKernels {
    fn new(device: &wgpu::Device, precision: Precision, guide: Guide) -> Self {
        let compute = wgpu::ShaderStages::COMPUTE;
        let entry = |binding, ty| wgpu::BindGroupLayoutEntry { binding, visibility: compute, ty, count: None };
        let sampled = |dim| wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: dim,
            multisampled: false,
        };
        let written =
            |format, dim| wgpu::BindingType::StorageTexture { access: wgpu::StorageTextureAccess::WriteOnly, format, view_dimension: dim };
        let layout = |label, entries: &[wgpu::BindGroupLayoutEntry]| {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries })
        };
        let d2 = wgpu::TextureViewDimension::D2;
        let f32x4 = wgpu::TextureFormat::Rgba32Float;
        let array = wgpu::TextureViewDimension::D2Array;
        let in_layout = layout(
            "motion in",
            &[uniform_entry(0), storage_entry(1, true), entry(2, written(f32x4, d2)), entry(8, sampled(array)), entry(9, sampled(d2))],
        );
        let guide_layout = layout("guide store", &[entry(8, sampled(array)), entry(10, written(f32x4, d2))]);
        let down_layout = layout("motion down", &[entry(3, sampled(d2)), entry(4, written(f32x4, d2))]);
        let warp_layout = layout("warp", &[entry(5, sampled(d2)), entry(6, sampled(array)), entry(7, written(precision.format(), array))]);
        let source = shader_source("motion").to_string();
        let source = if precision == Precision::F16 { rewrite(source, "motion.wgsl", &WARP_F16) } else { source };
        let module = shader_module(device, "motion", source);
        let off = |o: Option<u32>| o.unwrap_or(u32::MAX) as f64;
        let constants = [("OFF_NORMAL", off(guide.normal)), ("OFF_DEPTH", off(guide.depth))];
        let pipeline = |layout: &wgpu::BindGroupLayout, entry: &str| {
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: None,
                bind_group_layouts: &[Some(layout)],
                immediate_size: 0,
            });
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: wgpu::PipelineCompilationOptions { constants: &constants, zero_initialize_workgroup_memory: false },
                cache: None,
            })
        };
        MotionKernels {
            motion_in: pipeline(&in_layout, "motion_in"),
            motion_down: pipeline(&down_layout, "motion_down"),
            warp: pipeline(&warp_layout, "warp"),
            guide_store: pipeline(&guide_layout, "guide_store"),
            in_layout,
            guide_layout,
            down_layout,
            warp_layout,
        }
    }
}

fn uniform_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Uniform, has_dynamic_offset: false, min_binding_size: None },
        count: None,
    }
}

fn dynamic_entry(binding: u32, ty: wgpu::BufferBindingType, size: u64) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: true, min_binding_size: wgpu::BufferSize::new(size) },
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

/// The layout entry of a plan's weight texture (rgba32float, 2D), read as the sources are.
fn weight_texture_entry(binding: u32, sources: SourceAccess) -> wgpu::BindGroupLayoutEntry {
    let ty = match sources {
        SourceAccess::Sampled => wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        SourceAccess::Storage => wgpu::BindingType::StorageTexture {
            access: wgpu::StorageTextureAccess::ReadOnly,
            format: wgpu::TextureFormat::Rgba32Float,
            view_dimension: wgpu::TextureViewDimension::D2,
        },
    };
    wgpu::BindGroupLayoutEntry { binding, visibility: wgpu::ShaderStages::COMPUTE, ty, count: None }
}

/// The layout entry of a conv source read as `sources` says.
fn source_entry(binding: u32, sources: SourceAccess, format: wgpu::TextureFormat) -> wgpu::BindGroupLayoutEntry {
    match sources {
        SourceAccess::Sampled => texture_entry(binding),
        SourceAccess::Storage => wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::StorageTexture {
                access: wgpu::StorageTextureAccess::ReadOnly,
                format,
                view_dimension: wgpu::TextureViewDimension::D2Array,
            },
            count: None,
        },
    }
}

fn storage_texture_entry(binding: u32, format: wgpu::TextureFormat) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::StorageTexture {
            access: wgpu::StorageTextureAccess::WriteOnly,
            format,
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
    /// The conv has a source b (a one-source kernel compiles without its fetches).
    pub source_b: bool,
    /// LeakyReLU or linear.
    pub leaky: bool,
    /// Output blocks per invocation ([`blocks_per_invocation`]).
    pub ob: u32,
    /// Output rows per invocation ([`rows_per_invocation`]).
    pub rows: u32,
    /// Output columns per invocation (1 or 2).
    pub cols: u32,
    /// Workgroup width (the height makes 64).
    pub group_x: u32,
    /// How the kernel computes the tile: its entry point.
    pub method: Method,
    /// Parts of the input blocks (split-K; 1: none).
    pub split: u32,
    /// The pipeline of split-K's second pass (entry point `reduce`) rather than the conv's.
    pub reduce: bool,
    /// How the conv reads its sources (the module and bind-group layout it is made with).
    pub sources: SourceAccess,
    /// The pipeline has the pooled store (conv3x3.wgsl's POOL_OUT): every conv whose tile can
    /// pool its output, whether it does is its parameters' `pool_out` ([`ConvPlan::pools`]).
    ///
    /// So a conv that pools and one that does not share a pipeline. Lavapipe compiles a
    /// pipeline with LLVM at its first dispatch, once per pipeline and static state of the
    /// textures bound (format, array or not, power-of-two sizes; a conv that does not pool binds
    /// its output at the pooled binding for that, [`ConvPlan::bind_group`]): 6 to 7 s for an
    /// F(4x4) one on this project's machine. The sample's first frame into an empty shader cache
    /// compiles 11 conv pipelines instead of 14 (`docs/perf/lavapipe-2026-11-25-s24.log`); the pooled store
    /// costs a uniform branch per store where it is not taken.
    pub pool: bool,
    /// Where it reads its weights (the module and bind-group layout it is made with; Mma tiles
    /// read storage weights).
    pub memory: WeightMemory,
    /// It writes its output into the plan's buffer rather than its texture
    /// (conv3x3_wino4.wgsl's OUT_BUFFER), for the frame to copy ([`ConvPlan::staged`]).
    pub staged: bool,
    /// Source a is carved into cells of an arena below its resolution ([`Carve`]): its fetches
    /// test the level's bounds (outside a cell lies another, not zero). Every load and store
    /// finds its cell from the parameters' carves, whatever the variant.
    pub carve_a: bool,
    /// Source b is carved.
    pub carve_b: bool,
}

impl ConvVariant {
    /// Whether the variant runs in the module with conv3x3_rows.wgsl and conv3x3_wino.wgsl:
    /// `accumulate_rows` (two-column lanes tiles) or `winograd_lanes`.
    fn runs_rows(&self) -> bool {
        (self.method == Method::Lanes && self.cols > 1 && !self.reduce) || self.method.is_winograd_lanes()
    }
}

/// Every pair of source access and weight memory a conv can have, in [`conv_slot`] order.
const CONV_SLOTS: [(SourceAccess, WeightMemory); 4] = [
    (SourceAccess::Sampled, WeightMemory::Uniform),
    (SourceAccess::Sampled, WeightMemory::Storage),
    (SourceAccess::Storage, WeightMemory::Uniform),
    (SourceAccess::Storage, WeightMemory::Storage),
];

/// Where a conv's layouts and modules are kept in [`Kernels`].
fn conv_slot(access: SourceAccess, memory: WeightMemory) -> usize {
    access as usize * 2 + memory as usize
}

/// The conv modules of one [`SourceAccess`] and [`WeightMemory`], each made when a pipeline
/// first needs it.
#[derive(Default)]
struct ConvModules {
    /// conv3x3.wgsl as rewritten for the precision, memory, device and access.
    main: Option<wgpu::ShaderModule>,
    /// The conv module with conv3x3_rows.wgsl (two-column lanes tiles, [`ROWS_STUB`]), for
    /// convs of one source.
    rows: Option<wgpu::ShaderModule>,
    /// The same for convs of two sources: its F(4x4) step in a loop per source
    /// ([`TWO_SOURCE_LOOPS`]).
    rows_b: Option<wgpu::ShaderModule>,
    /// conv3x3_mma.wgsl ([`mma_source`]) as rewritten for the precision and access.
    mma: Option<wgpu::ShaderModule>,
}

/// Shader modules, layouts and pipelines of one device; conv pipelines are cached by variant.
///
/// A conv reads its sources and its weights as its variant says ([`ConvVariant::sources`],
/// [`ConvVariant::memory`]), so one `Kernels` serves plans that mix sampled and storage-texture
/// sources (tuning picks per conv, [`crate::Denoiser`]) and uniform and storage weights (by
/// level on CPU drivers, [`WeightMemory::for_conv`]) conv by conv; each pair of the two has
/// its own bind-group layout, and its modules are made only when a pipeline of that pair is.
pub struct Kernels {
    /// Layout of prep.wgsl's group 0.
    pub prep_layout: wgpu::BindGroupLayout,
    /// Layout of output.wgsl's group 0.
    pub output_layout: wgpu::BindGroupLayout,
    /// Layout of pool.wgsl's group 0.
    pub pool_layout: wgpu::BindGroupLayout,
    /// The 2x2 max-pool pipeline (a pass per encoder block, [`crate::graph::Pool`], where the
    /// block's last conv does not pool its own output, [`ConvPlan::pools`]).
    pub pool: wgpu::ComputePipeline,
    /// prep.wgsl, specialised per model by [`Kernels::prep_pipeline`].
    prep_module: wgpu::ShaderModule,
    /// The pipeline layout over [`Kernels::prep_layout`].
    prep_pipeline_layout: wgpu::PipelineLayout,
    /// The output pipeline.
    pub output: wgpu::ComputePipeline,
    /// Layouts of the conv's group 0, at [`conv_slot`] of the source access and weight memory.
    conv_layouts: [wgpu::BindGroupLayout; 4],
    /// Pipeline layouts over [`Kernels::conv_layouts`], likewise.
    conv_pipeline_layouts: [wgpu::PipelineLayout; 4],
    /// The conv modules, likewise.
    modules: [ConvModules; 4],
    /// The device runs Mma tiles in matrix units ([`matrix_units_supported`]).
    matrix_units: bool,
    /// The device has subgroup operations (else [`WITHOUT_SUBGROUPS`] rewrites conv3x3.wgsl).
    subgroups: bool,
    conv: HashMap<ConvVariant, wgpu::ComputePipeline>,
    /// motion.wgsl's pipelines, made on first use ([`Kernels::motion`]).
    motion: Option<MotionKernels>,
    precision: Precision,
    pub(super) memory: WeightMemory,
    /// The access of plans that do not choose per conv ([`ConvPlan::new`]).
    pub(super) sources: SourceAccess,
    /// Plans made from here stage the outputs they can ([`Kernels::stage_outputs`]).
    pub(super) staging: bool,
    /// The device reads zero outside a texture ([`out_of_bounds_reads_zero`]).
    reads_zero: bool,
    /// What a conv that does not pool binds at its pooled output (binding 6), where the device
    /// refuses one texture bound twice as a writable storage texture in a dispatch (a browser's
    /// WebGPU): a 1 x 1 texture it never writes ([`Kernels::pool_binding`]).
    pool_sink: Option<wgpu::TextureView>,
    /// The conv pipelines read their zero padding from outside the textures
    /// ([`Kernels::pad_from_bounds`]).
    oob_zero: bool,
    /// The lanes module stores staged outputs in 64-bit words ([`wide_staged_stores`], unless
    /// [`Kernels::stage_in_32_bit_words`]).
    wide_stores: bool,
    /// The Winograd lanes kernels gather for 8-lane subgroups ([`narrow_gathers`], or
    /// [`Kernels::gather_in_8_lanes`]).
    gathers8: bool,
}

impl Kernels {
    /// Compile the modules and the fixed pipelines for activations stored in `precision`, conv
    /// weights read from `memory` and conv sources read as suits the device
    /// ([`SourceAccess::for_device_type`]).
    ///
    /// The storage texel format, a binding's address space and a texture's type are the things
    /// WGSL cannot take as override constants, so for f16 the kernels' `rgba32float` storage
    /// declarations are rewritten to `rgba16float`, for storage weights the conv's one uniform
    /// weight declaration ([`UNIFORM_WEIGHTS`]) to [`STORAGE_WEIGHTS`], and for storage-texture
    /// sources the conv's `Source` alias and `load` ([`STORAGE_SOURCES`]); everything else (the
    /// clamp to the f16 range) is an override.
    pub fn new(device: &wgpu::Device, precision: Precision, memory: WeightMemory) -> Self {
        Self::with_sources(device, precision, memory, SourceAccess::for_device(device))
    }

    /// [`Kernels::new`] with the conv's sources read as `sources` says (rewritten by
    /// [`STORAGE_SOURCES`] for storage textures, before the f16 rewrite).
    pub fn with_sources(device: &wgpu::Device, precision: Precision, memory: WeightMemory, sources: SourceAccess) -> Self {
        let layout = |label, entries: &[wgpu::BindGroupLayoutEntry]| {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries })
        };
        let conv_layout = |access: SourceAccess, memory: WeightMemory| {
            // Every slot's layout is made here; where the device binds too few storage textures
            // for storage sources (SourceAccess::storage_fits), their slots get the sampled
            // layout, which no plan picks storage sources to use there.
            let access = if SourceAccess::storage_fits(device) { access } else { SourceAccess::Sampled };
            layout(
                "conv3x3",
                &[
                    dynamic_entry(0, wgpu::BufferBindingType::Uniform, std::mem::size_of::<ConvParams>() as u64),
                    source_entry(1, access, precision.format()),
                    source_entry(2, access, precision.format()),
                    match memory {
                        WeightMemory::Uniform => dynamic_entry(3, wgpu::BufferBindingType::Uniform, WEIGHT_CHUNK_BYTES),
                        WeightMemory::Storage => dynamic_entry(3, wgpu::BufferBindingType::Storage { read_only: true }, 16),
                    },
                    storage_texture_entry(4, precision.format()),
                    storage_entry(5, false),
                    storage_texture_entry(6, precision.format()),
                    weight_texture_entry(7, access),
                ],
            )
        };
        let prep_layout = layout(
            "prep",
            &[
                uniform_entry(0),
                storage_entry(1, true),
                storage_entry(2, true),
                storage_entry(3, true),
                storage_entry(4, true),
                storage_entry(5, true),
                storage_texture_entry(6, precision.format()),
                storage_entry(7, false),
            ],
        );
        let output_layout = layout(
            "output",
            &[
                uniform_entry(0),
                texture_entry(1),
                storage_entry(2, true),
                storage_entry(3, false),
                storage_entry(4, true),
                storage_entry(5, true),
                storage_entry(6, true),
                storage_entry(7, true),
            ],
        );
        let pipeline_layout = |bgl: &wgpu::BindGroupLayout| {
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: None,
                bind_group_layouts: &[Some(bgl)],
                immediate_size: 0,
            })
        };
        // prep, output and pool: f16 storage is their only rewrite (and prep's without subgroups).
        let subgroups = device.features().contains(wgpu::Features::SUBGROUP);
        let module = |name: &str| {
            let mut src = conv_module_source(name);
            if name == "prep" && !subgroups {
                src = rewrite(src, "prep.wgsl", &PREP_WITHOUT_SUBGROUPS);
            }
            shader_module(device, name, if precision == Precision::F16 { src.replace("rgba32float", "rgba16float") } else { src })
        };
        let pipeline = |label, layout: &wgpu::PipelineLayout, module: &wgpu::ShaderModule, constants: &[(&str, f64)]| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(label),
                layout: Some(layout),
                module,
                entry_point: Some("main"),
                compilation_options: wgpu::PipelineCompilationOptions { constants, zero_initialize_workgroup_memory: false },
                cache: None,
            })
        };
        let output = pipeline("output", &pipeline_layout(&output_layout), &module("output"), &[]);
        let pool_layout = layout("pool", &[texture_entry(0), storage_texture_entry(1, precision.format()), uniform_entry(2)]);
        let pool = pipeline("pool", &pipeline_layout(&pool_layout), &module("pool"), &[]);
        let conv_layouts = CONV_SLOTS.map(|(access, memory)| conv_layout(access, memory));
        Self {
            conv_pipeline_layouts: std::array::from_fn(|i| pipeline_layout(&conv_layouts[i])),
            conv_layouts,
            modules: Default::default(),
            matrix_units: matrix_units_supported(device),
            subgroups,
            prep_pipeline_layout: pipeline_layout(&prep_layout),
            prep_module: module("prep"),
            prep_layout,
            output_layout,
            pool_layout,
            pool,
            output,
            conv: HashMap::new(),
            motion: None,
            precision,
            memory,
            sources,
            staging: false,
            reads_zero: out_of_bounds_reads_zero(device),
            pool_sink: (device.adapter_info().backend == wgpu::Backend::BrowserWebGpu).then(|| {
                let desc = wgpu::TextureDescriptor {
                    label: Some("pool sink"),
                    size: wgpu::Extent3d { width: 1, height: 1, depth_or_array_layers: 1 },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: precision.format(),
                    usage: wgpu::TextureUsages::STORAGE_BINDING,
                    view_formats: &[],
                };
                let view = wgpu::TextureViewDescriptor { dimension: Some(wgpu::TextureViewDimension::D2Array), ..Default::default() };
                device.create_texture(&desc).create_view(&view)
            }),
            oob_zero: false,
            wide_stores: wide_staged_stores(device),
            gathers8: narrow_gathers(device),
        }
    }

    /// Gather the Winograd lanes kernels' weights in loads of 8 lanes (conv3x3_gather8.wgsl) even
    /// where the subgroups have 16 or more: for holding the two to each other on one device
    /// (tests/engine/kernels.rs). Call it before any conv pipeline is made.
    pub fn gather_in_8_lanes(&mut self) {
        assert!(self.conv.is_empty(), "gather_in_8_lanes after conv pipelines were made");
        self.gathers8 = true;
    }

    /// Store staged outputs in 32-bit words even where [`wide_staged_stores`] holds: the path of
    /// devices without 64-bit integers, for holding the two to each other on one device
    /// (tests/engine/kernels.rs). Call it before any conv pipeline is made.
    pub fn stage_in_32_bit_words(&mut self) {
        assert!(self.conv.is_empty(), "stage_in_32_bit_words after conv pipelines were made");
        self.wide_stores = false;
    }

    /// What a conv that does not pool binds at its pooled output: its own output, so that its
    /// pipeline's textures have the static state of a pooling conv's (lavapipe compiles one
    /// pipeline for both, [`ConvVariant::pool`]), or where the device refuses a texture bound
    /// twice as a writable storage texture in one dispatch (a browser's WebGPU), a 1 x 1
    /// texture of its own that it never writes.
    pub fn pool_binding<'a>(&'a self, output: &'a wgpu::TextureView) -> &'a wgpu::TextureView {
        self.pool_sink.as_ref().unwrap_or(output)
    }

    /// Have the conv pipelines read their zero padding from outside the source textures,
    /// without testing each pixel, where the device reads zero there
    /// ([`out_of_bounds_reads_zero`], conv_common.wgsl's OOB_ZERO): one load per fetch instead
    /// of a branch around it (lavapipe: the L0 convs in 0.93-0.98x the time, about 3% of the
    /// 256x256 frame, and the direct16x4 pipeline compiles in 0.4x; `docs/perf/lavapipe-2026-12-02-s28.log`).
    ///
    /// Only for plans whose sources have exactly the sizes their read modes imply: a pooled
    /// source twice the level's, an upsampled one half, a pooled-and-upsampled one the level's,
    /// each level even where a mode halves or doubles it, as the [`crate::Denoiser`]'s padded
    /// levels are. Then every pixel outside the level reads texels outside its source; at odd
    /// sizes an upsampled read at the right edge would land inside. A source carved into an
    /// arena's cells ([`ConvVariant::carve_a`]) keeps its test: beside its cell lies another.
    /// Call it before any conv pipeline is made (they are made once per variant).
    pub fn pad_from_bounds(&mut self) {
        assert!(self.conv.is_empty(), "pad_from_bounds after conv pipelines were made");
        self.oob_zero = self.reads_zero;
    }

    /// Have the plans made from here on stage the outputs of their F(4x4) convs where a copy
    /// can take them: the conv writes its output into the plan's buffer and the frame copies it
    /// into the texture (on a CPU driver, with f32 activations, at levels a multiple of 16
    /// wide, up to [`STAGING_BYTES`]; [`ConvPlan::staged`]).
    ///
    /// Lavapipe stores an rgba32float texel with four loops over the subgroup's lanes, one per
    /// 32-bit word, each spilling the vectors it picks a lane from; a vec4 store into a buffer is
    /// one such loop, and `copy_buffer_to_texture` is a memcpy on the queue thread (0.04-0.10x
    /// the texel stores it replaces; `docs/perf/lavapipe-2026-12-01-s25.log`, `docs/perf/lavapipe-2026-12-02-s28.log`). Only a caller that
    /// records the copies may ask for it ([`crate::Denoiser`]): [`ConvPlan::record`] alone leaves
    /// a staged conv's texture unwritten.
    pub fn stage_outputs(&mut self) {
        self.staging = self.precision == Precision::F32;
    }

    /// A conv kernel's text (`src`, from `file`) with the rewrites both conv modules take: the
    /// source access ([`STORAGE_SOURCES`]) and f16 storage.
    fn conv_kernel_text(&self, file: &str, src: String, access: SourceAccess) -> String {
        let src = if access == SourceAccess::Storage { rewrite(src, file, &STORAGE_SOURCES) } else { src };
        if self.precision == Precision::F16 { src.replace("rgba32float", "rgba16float") } else { src }
    }

    /// conv3x3.wgsl as this device, precision, weight memory and source access run it (the
    /// rewrites of [`Kernels::new`]).
    fn conv_text(&self, access: SourceAccess, memory: WeightMemory) -> String {
        let mut src = self.conv_kernel_text("conv3x3.wgsl", conv_module_source("conv3x3"), access);
        if !self.subgroups {
            src = rewrite(src, "conv3x3.wgsl", &WITHOUT_SUBGROUPS);
        }
        if memory == WeightMemory::Storage {
            src = rewrite(src, "conv3x3.wgsl", &[(UNIFORM_WEIGHTS, STORAGE_WEIGHTS)]);
        }
        src
    }

    /// conv3x3_mma.wgsl as this device, precision and source access run it.
    fn mma_text(&self, access: SourceAccess) -> String {
        self.conv_kernel_text("conv3x3_mma.wgsl", mma_source(self.matrix_units), access)
    }

    /// motion.wgsl's layouts and pipelines, if [`Kernels::motion`] has made them.
    pub fn motion_kernels(&self) -> Option<&MotionKernels> {
        self.motion.as_ref()
    }

    /// motion.wgsl's layouts and pipelines for a model with `guide`, made on the first call.
    pub fn motion(&mut self, device: &wgpu::Device, guide: Guide) -> &MotionKernels {
        let precision = self.precision;
        self.motion.get_or_insert_with(|| MotionKernels::new(device, precision, guide))
    }

    /// The input-preparation pipeline for a model whose input is packed as `layout` says
    /// (prep.wgsl specialised by override constants; one per [`crate::Denoiser`]).
    pub fn prep_pipeline(&self, device: &wgpu::Device, layout: &PrepLayout) -> wgpu::ComputePipeline {
        let constants = layout.constants(self.precision.store_max());
        device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("prep"),
            layout: Some(&self.prep_pipeline_layout),
            module: &self.prep_module,
            entry_point: Some("main"),
            compilation_options: wgpu::PipelineCompilationOptions { constants: &constants, zero_initialize_workgroup_memory: false },
            cache: None,
        })
    }

    /// Layout of the conv's group 0 for sources read as `access` says and weights in `memory`.
    pub fn conv_layout(&self, access: SourceAccess, memory: WeightMemory) -> &wgpu::BindGroupLayout {
        &self.conv_layouts[conv_slot(access, memory)]
    }

    /// How many conv pipelines are made (one per variant; [`Kernels::prepare`]).
    pub fn conv_pipelines(&self) -> usize {
        self.conv.len()
    }

    /// Where the convs of a plan that does not choose per conv read their weights.
    pub fn weight_memory(&self) -> WeightMemory {
        self.memory
    }

    /// How the convs of a plan that does not choose per conv read their sources.
    pub fn source_access(&self) -> SourceAccess {
        self.sources
    }

    /// Whether Mma tiles run in the device's matrix units (else emulated).
    pub fn matrix_units(&self) -> bool {
        self.matrix_units
    }

    /// The conv pipeline for a variant, created on first use.
    pub fn conv(&mut self, device: &wgpu::Device, v: ConvVariant) -> wgpu::ComputePipeline {
        self.prepare(device, &[v]);
        self.conv[&v].clone()
    }

    /// Create the pipelines of `variants` that are not cached yet, on one thread per core.
    ///
    /// A pipeline's creation is mostly the driver's front end (lavapipe translates and
    /// optimises the SPIR-V before its shader cache is consulted; that is most of a denoiser's
    /// build, `docs/perf/lavapipe-2026-11-23-s10.log`), and Vulkan lets pipelines of one device be created
    /// concurrently, so a plan's variants are made side by side rather than in turn.
    pub fn prepare(&mut self, device: &wgpu::Device, variants: &[ConvVariant]) {
        let mut missing: Vec<ConvVariant> = Vec::new();
        for v in variants {
            if !self.conv.contains_key(v) && !missing.contains(v) {
                missing.push(*v);
            }
        }
        if missing.is_empty() {
            return;
        }
        // The modules the missing variants run, per source access and weight memory:
        // conv3x3.wgsl, the module with conv3x3_rows.wgsl for two-column lanes tiles
        // ([`ROWS_STUB`]), conv3x3_mma.wgsl (storage weights only).
        for (access, memory) in CONV_SLOTS {
            let of_slot = || missing.iter().filter(|v| v.sources == access && v.memory == memory);
            let m = &self.modules[conv_slot(access, memory)];
            let (need_main, need_rows, need_rows_b, need_mma) = (
                m.main.is_none() && of_slot().any(|v| !v.method.is_mma() && !v.runs_rows()),
                m.rows.is_none() && of_slot().any(|v| v.runs_rows() && !v.source_b),
                m.rows_b.is_none() && of_slot().any(|v| v.runs_rows() && v.source_b),
                m.mma.is_none() && of_slot().any(|v| v.method.is_mma()),
            );
            let text = if need_main || need_rows || need_rows_b { self.conv_text(access, memory) } else { String::new() };
            let mma = need_mma.then(|| shader_module(device, "conv3x3_mma", self.mma_text(access)));
            let lanes = |two_sources: bool| {
                let label = if two_sources { "conv3x3 (lanes tiles, two sources)" } else { "conv3x3 (lanes tiles)" };
                shader_module(
                    device,
                    label,
                    lanes_module_source(&text, access, LanesModule { wide_stores: self.wide_stores, two_sources, gathers8: self.gathers8 }),
                )
            };
            let rows = need_rows.then(|| lanes(false));
            let rows_b = need_rows_b.then(|| lanes(true));
            let main = need_main.then(|| shader_module(device, "conv3x3", text));
            let m = &mut self.modules[conv_slot(access, memory)];
            m.main = m.main.take().or(main);
            m.rows = m.rows.take().or(rows);
            m.rows_b = m.rows_b.take().or(rows_b);
            m.mma = m.mma.take().or(mma);
        }
        let made = self.create_convs(device, &missing);
        self.conv.extend(made);
    }

    /// Create the conv pipelines of `missing`, on as many threads as there are cores (the
    /// driver compiles them as they are created on some platforms), in order.
    #[cfg(not(target_arch = "wasm32"))]
    fn create_convs(&self, device: &wgpu::Device, missing: &[ConvVariant]) -> Vec<(ConvVariant, wgpu::ComputePipeline)> {
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get()).min(missing.len());
        if threads <= 1 {
            return missing.iter().map(|&v| (v, self.create_conv(device, v))).collect();
        }
        // Thread t makes variants t, t + threads, ...; the results are gathered in order.
        std::thread::scope(|scope| {
            let workers: Vec<_> = (0..threads)
                .map(|t| {
                    scope.spawn(move || {
                        missing.iter().skip(t).step_by(threads).map(|&v| (v, self.create_conv(device, v))).collect::<Vec<_>>()
                    })
                })
                .collect();
            workers.into_iter().flat_map(|w| w.join().expect("a pipeline-creating thread panicked")).collect()
        })
    }

    /// Create the conv pipelines of `missing` in order (a browser's WebGPU objects stay on
    /// their thread).
    #[cfg(target_arch = "wasm32")]
    fn create_convs(&self, device: &wgpu::Device, missing: &[ConvVariant]) -> Vec<(ConvVariant, wgpu::ComputePipeline)> {
        missing.iter().map(|&v| (v, self.create_conv(device, v))).collect()
    }

    /// Create one conv pipeline (its module made by [`Kernels::prepare`]).
    fn create_conv(&self, device: &wgpu::Device, v: ConvVariant) -> wgpu::ComputePipeline {
        let modules = &self.modules[conv_slot(v.sources, v.memory)];
        // conv_common.wgsl's overrides, then the kernel's own.
        let mut constants = vec![
            // conv_common.wgsl's read-mode bits: the mode, CARVED, FROM_B.
            ("MODE_A", (v.read_a as u32 | (v.carve_a as u32) << 2) as f64),
            ("MODE_B", (v.read_b as u32 | (v.carve_b as u32) << 2 | 8) as f64),
            ("SOURCE_B", if v.source_b { 1.0 } else { 0.0 }),
            ("LEAKY", if v.leaky { 1.0 } else { 0.0 }),
            ("STORE_MAX", self.precision.store_max() as f64),
            // The Mma tiles (GPUs; emulated elsewhere) keep their tests.
            ("OOB_ZERO", (self.oob_zero && !v.method.is_mma()) as u32 as f64),
        ];
        let (label, module, entry) = if v.method.is_mma() {
            // Split tiles split the activations too where they are f32 (f16 ones are exact).
            let split = v.method.is_mma_split();
            let pixels = if split { MMA_SPLIT_PIXELS } else { MMA_PIXELS };
            constants.extend([
                ("NT", v.ob as f64),
                ("MT", (pixels / 16) as f64),
                ("SPLIT", split as u32 as f64),
                ("SPLIT_A", (split && self.precision == Precision::F32) as u32 as f64),
            ]);
            let entry = match (self.matrix_units, split) {
                (true, _) => v.method.entry_point(),
                (false, false) => "mma_emulated",
                (false, true) => "mma_split_emulated",
            };
            ("conv3x3_mma", modules.mma.as_ref().expect("made by prepare"), entry)
        } else {
            constants.extend([
                ("OB", v.ob as f64),
                ("ROWS", v.rows as f64),
                ("TW", v.cols as f64),
                ("WG_X", v.group_x as f64),
                ("WG_Y", (64 / v.group_x) as f64),
                ("SPLIT", v.split as f64),
                ("LANES", if v.method == Method::Lanes { 1.0 } else { 0.0 }),
                ("POOL_OUT", v.pool as u32 as f64),
            ]);
            if v.runs_rows() {
                constants.push(("WEIGHT_TEXELS_WIDTH", WEIGHT_TEXELS_WIDTH as f64));
                constants.push(("OUT_BUFFER", v.staged as u32 as f64));
            }
            let module = match (v.runs_rows(), v.source_b) {
                (true, false) => modules.rows.as_ref(),
                (true, true) => modules.rows_b.as_ref(),
                _ => modules.main.as_ref(),
            }
            .expect("made by prepare");
            ("conv3x3", module, if v.reduce { "reduce" } else { v.method.entry_point() })
        };
        device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(label),
            layout: Some(&self.conv_pipeline_layouts[conv_slot(v.sources, v.memory)]),
            module,
            entry_point: Some(entry),
            compilation_options: wgpu::PipelineCompilationOptions { constants: &constants, zero_initialize_workgroup_memory: false },
            cache: None,
        })
    }
}

//! What writing a conv-sized output costs on the device, three ways: a kernel that stores one
//! rgba32float texel per invocation with `textureStore` (how every conv writes its output), the
//! same kernel storing a vec4 into a storage buffer, and `copy_buffer_to_texture` of the same
//! bytes. Prints the median of interleaved rounds per size (wall time of 10 back-to-back
//! passes or copies in one submit, divided by 10).
//!
//! On lavapipe a store is a loop over the subgroup's lanes (a textureStore of rgba32float is
//! four, one per 32-bit word), so this is the floor under a conv's store, whatever it computes
//! (docs/PERF.md, session 25).
//!
//! cargo run --release -p rae-core --example store_cost -- [ROUNDS]

use std::time::Instant;

use rae_core::Gpu;

/// Writes a texel per invocation (x, y from global x, layer from z), to the texture or the buffer.
const SHADER: &str = r#"
@group(0) @binding(0) var<storage, read_write> out_buffer: array<vec4<f32>>;
@group(0) @binding(1) var out_texture: texture_storage_2d_array<rgba32float, write>;
override W: u32 = 1u;
override H: u32 = 1u;

@compute @workgroup_size(64)
fn to_texture(@builtin(global_invocation_id) g: vec3<u32>) {
    let x = g.x % W;
    let y = g.x / W;
    if y < H {
        textureStore(out_texture, vec2<u32>(x, y), g.z, vec4<f32>(f32(x), f32(y), f32(g.z), 1.0));
    }
}

@compute @workgroup_size(64)
fn to_buffer(@builtin(global_invocation_id) g: vec3<u32>) {
    let x = g.x % W;
    let y = g.x / W;
    if y < H {
        out_buffer[(g.z * H + y) * W + x] = vec4<f32>(f32(x), f32(y), f32(g.z), 1.0);
    }
}
"#;

/// Passes or copies per timed submit.
const REPEAT: u32 = 10;

/// The three ways of writing an output.
#[derive(Clone, Copy)]
enum Way {
    TextureStore,
    BufferStore,
    Copy,
}

/// A W x H x layers rgba32float texture array, a buffer of the same bytes, and a pipeline and
/// bind group per store kernel.
struct Case {
    size: (u32, u32, u32),
    buffer: wgpu::Buffer,
    texture: wgpu::Texture,
    texture_store: (wgpu::ComputePipeline, wgpu::BindGroup),
    buffer_store: (wgpu::ComputePipeline, wgpu::BindGroup),
}

impl Case {
    fn new(d: &wgpu::Device, module: &wgpu::ShaderModule, (w, h, layers): (u32, u32, u32)) -> Self {
        let buffer = d.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: u64::from(w * h * layers) * 16,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let texture = d.create_texture(&wgpu::TextureDescriptor {
            label: None,
            size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: layers },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba32Float,
            usage: wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::STORAGE_BINDING,
            view_formats: &[],
        });
        let view = texture
            .create_view(&wgpu::TextureViewDescriptor { dimension: Some(wgpu::TextureViewDimension::D2Array), ..Default::default() });
        let constants = [("W", f64::from(w)), ("H", f64::from(h))];
        // Each entry point's layout holds only the binding it uses.
        let kernel = |entry: &str, binding: u32, resource: wgpu::BindingResource| {
            let pipeline = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: None,
                module,
                entry_point: Some(entry),
                compilation_options: wgpu::PipelineCompilationOptions { constants: &constants, ..Default::default() },
                cache: None,
            });
            let group = d.create_bind_group(&wgpu::BindGroupDescriptor {
                label: None,
                layout: &pipeline.get_bind_group_layout(0),
                entries: &[wgpu::BindGroupEntry { binding, resource }],
            });
            (pipeline, group)
        };
        let texture_store = kernel("to_texture", 1, wgpu::BindingResource::TextureView(&view));
        let buffer_store = kernel("to_buffer", 0, buffer.as_entire_binding());
        Self { size: (w, h, layers), buffer, texture, texture_store, buffer_store }
    }

    /// Milliseconds per pass (or copy), from one submit of REPEAT of them.
    fn time(&self, gpu: &Gpu, way: Way) -> f64 {
        let (w, h, layers) = self.size;
        let mut e = gpu.device.create_command_encoder(&Default::default());
        for _ in 0..REPEAT {
            let (pipeline, group) = match way {
                Way::TextureStore => &self.texture_store,
                Way::BufferStore => &self.buffer_store,
                Way::Copy => {
                    e.copy_buffer_to_texture(
                        wgpu::TexelCopyBufferInfo {
                            buffer: &self.buffer,
                            layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(w * 16), rows_per_image: Some(h) },
                        },
                        self.texture.as_image_copy(),
                        wgpu::Extent3d { width: w, height: h, depth_or_array_layers: layers },
                    );
                    continue;
                }
            };
            let mut pass = e.begin_compute_pass(&Default::default());
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, group, &[]);
            pass.dispatch_workgroups((w * h).div_ceil(64), 1, layers);
        }
        let start = Instant::now();
        gpu.queue.submit([e.finish()]);
        gpu.device.poll(wgpu::PollType::wait_indefinitely()).expect("device lost");
        start.elapsed().as_secs_f64() * 1e3 / f64::from(REPEAT)
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // SAFETY: first thing in main, before any thread starts.
    unsafe { rae_core::gpu::prefer_wide_cpu_vectors() };
    let rounds: usize = std::env::args().nth(1).map_or(Ok(5), |s| s.parse())?;
    let gpu = Gpu::new()?;
    println!("adapter: {}; median of {rounds} interleaved rounds, ms per pass", gpu.describe());
    let module = gpu
        .device
        .create_shader_module(wgpu::ShaderModuleDescriptor { label: Some("store_cost"), source: wgpu::ShaderSource::Wgsl(SHADER.into()) });
    // The default network's L0 output (32 channels) at 64x64 and 256x256, and a 1080p layer.
    let sizes = [(64, 64, 8), (256, 256, 8), (1920, 1088, 1)];
    let ways = [Way::TextureStore, Way::BufferStore, Way::Copy];
    println!(
        "{:>14} {:>8} {:>14} {:>13} {:>9} {:>12} {:>11} {:>12}",
        "size", "MiB", "textureStore", "buffer store", "copy", "ns/texel", "buffer/tex", "copy/tex"
    );
    for size in sizes {
        let case = Case::new(&gpu.device, &module, size);
        // The first pass of each compiles its pipeline (lavapipe compiles at first dispatch).
        for way in ways {
            case.time(&gpu, way);
        }
        let mut ms = [Vec::new(), Vec::new(), Vec::new()];
        for _ in 0..rounds {
            for (i, way) in ways.into_iter().enumerate() {
                ms[i].push(case.time(&gpu, way));
            }
        }
        let [tex, buf, copy] = ms.map(median);
        let (w, h, layers) = size;
        let texels = f64::from(w * h * layers);
        println!(
            "{:>14} {:>8.1} {:>14.3} {:>13.3} {:>9.3} {:>12.1} {:>11.2} {:>12.3}",
            format!("{w}x{h}x{layers}"),
            texels * 16.0 / 1048576.0,
            tex,
            buf,
            copy,
            tex * 1e6 / texels,
            buf / tex,
            copy / tex
        );
    }
    Ok(())
}

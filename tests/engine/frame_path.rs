//! The frame's other kernels and paths: prep against the CPU, the whole pipeline on odd sizes,
//! zero padding read from outside the textures, and staged outputs.

use rae_core::cpu::{self, Chw};
use rae_core::denoiser::read_texture;
use rae_core::kernels::{self, ConvPlan, ConvSpec, Kernels, Tile, WeightMemory, blocks};
use rae_core::{Denoiser, FrameInputs, Weights};
use wgpu::util::DeviceExt;

use crate::kernels::*;
use crate::{Tolerance, fixture, gpu};

/// A frame of `w x h` with every buffer, smooth values plus the extremes the input policy
/// handles (NaN, +-Inf, negative, huge, albedo 0) and misses: the depths that say so (NaN,
/// +-Inf, negative, past 1e6, 0) and pixel 11's zero normal.
fn wild_frame(w: usize, h: usize) -> [Vec<f32>; 5] {
    let n = w * h;
    let mut color: Vec<f32> = noise(3 * n, 50).iter().map(|v| (v * 3.0).exp()).collect();
    let mut albedo: Vec<f32> = noise(3 * n, 51).iter().map(|v| 0.5 + 0.5 * v).collect();
    let mut normal = noise(3 * n, 52);
    let mut depth: Vec<f32> = noise(n, 53).iter().map(|v| 5.0 + 4.0 * v).collect();
    let mut rough: Vec<f32> = noise(n, 54).iter().map(|v| 0.5 + 0.6 * v).collect();
    let specials = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, -3.0, 1e9, 0.0];
    for (k, &s) in specials.iter().enumerate() {
        let i = 7 + 13 * k;
        color[i] = s;
        albedo[i + 1] = s;
        normal[i + 2] = s;
        depth[k * 5] = s;
        rough[k * 5 + 1] = s;
    }
    normal[33..36].fill(0.0);
    [color, albedo, normal, depth, rough]
}

fn frame_of(b: &[Vec<f32>; 5]) -> FrameInputs<'_> {
    FrameInputs { color: &b[0], albedo: Some(&b[1]), normal: Some(&b[2]), depth: Some(&b[3]), roughness: Some(&b[4]), motion: None }
}

#[test]
fn prep_matches_cpu_with_padding_and_extreme_values() {
    let g = gpu();
    for (name, w, h) in [("weights_full.safetensors", 45, 27), ("weights_paper_tiny.safetensors", 37, 21)] {
        let weights = Weights::load(fixture(name)).unwrap();
        let mut d = Denoiser::new(&g.device, &g.queue, &weights, w as u32, h as u32).unwrap();
        let buffers = wild_frame(w, h);
        let out = d.denoise(&frame_of(&buffers)).unwrap();
        assert!(out.iter().all(|v| v.is_finite() && *v >= 0.0), "{name}: output finite and non-negative");
        let (pw, ph) = d.padded_size();
        let want = cpu::prepare(&weights.arch, &frame_of(&buffers), w, h, pw as usize, ph as usize);
        crate::assert_close(Tolerance { rel: 1e-6 }, &format!("prep {name}"), &d.read_input().unwrap(), &want.data);
        // The frame's largest prepared color, reduced over every invocation, bounds the output:
        // this frame's, then frames whose brightest pixel is the first, one in the middle and
        // the last (every invocation's value has to reach the maximum).
        let (got, expected) = (d.read_color_max().unwrap(), cpu::color_max(&want));
        assert!(expected > 0.0 && (got - expected).abs() <= 1e-6 * expected, "{name}: color max {got}, CPU {expected}");
        let n = w * h;
        for pos in [0, n / 2 + 3, n - 1] {
            let mut b = wild_frame(w, h);
            b[0] = noise(3 * n, 55).iter().map(|v| (v * 2.0).exp()).collect();
            b[0][3 * pos..3 * pos + 3].copy_from_slice(&[1e6, 2e6, 1e6]);
            b[1][3 * pos..3 * pos + 3].copy_from_slice(&[0.5, 0.5, 0.5]);
            d.denoise(&frame_of(&b)).unwrap();
            let x = cpu::prepare(&weights.arch, &frame_of(&b), w, h, pw as usize, ph as usize);
            let (got, expected) = (d.read_color_max().unwrap(), cpu::color_max(&x));
            let bright = (0..3).map(|c| x.data[c * x.h * x.w + pw as usize * (pos / w) + pos % w]).fold(0.0f32, f32::max);
            assert!(bright == expected, "{name}: pixel {pos} is the brightest ({bright} against {expected})");
            assert!((got - expected).abs() <= 1e-6 * expected, "{name}: brightest pixel {pos}: color max {got}, CPU {expected}");
        }
    }
}

#[test]
fn whole_pipeline_matches_cpu_on_odd_sizes() {
    // Prep, every conv, output and cropping, over three frames (hidden state carried), at
    // sizes that need padding: 37x21 (to 40x24), 50x35 (to 64x64) and 45x27 (to 64x32), with misses.
    let g = gpu();
    for (name, w, h) in
        [("weights_paper_tiny.safetensors", 37, 21), ("weights_color_tiny.safetensors", 50, 35), ("weights_full.safetensors", 45, 27)]
    {
        let weights = Weights::load(fixture(name)).unwrap();
        let mut d = Denoiser::new(&g.device, &g.queue, &weights, w as u32, h as u32).unwrap();
        let (pw, ph) = d.padded_size();
        let mut cpu_net = cpu::CpuNetwork::new(&weights);
        for t in 0..3u64 {
            let mut b = wild_frame(w, h);
            b[0] = noise(3 * w * h, 60 + t).iter().map(|v| (v * 2.0).exp()).collect();
            let got = d.denoise(&frame_of(&b)).unwrap();
            assert_eq!(got.len(), w * h * 3, "output is cropped to the frame");
            let x = cpu::prepare(&weights.arch, &frame_of(&b), w, h, pw as usize, ph as usize);
            let y = cpu_net.forward(&x);
            let want = cpu::finish(&weights.arch, &y, cpu::color_max(&x), &frame_of(&b), w, h);
            crate::assert_close(Tolerance { rel: 1e-4 }, &format!("{name} frame {t}"), &got, &want);
            // At a miss the output is the input color (sanitised), exactly.
            let misses: Vec<usize> = (0..w * h).filter(|&i| cpu::is_miss(&weights.arch, &frame_of(&b), i)).collect();
            let (by_depth, by_normal) = weights.arch.miss_by();
            assert_eq!(misses.contains(&11), by_normal, "{name}: the zero normal is a miss where the model reads normals");
            assert_eq!(misses.contains(&5), by_depth, "{name}: +inf depth is a miss where the model reads depth");
            for i in misses {
                let c: Vec<f32> = b[0][3 * i..3 * i + 3].iter().map(|&v| cpu::sanitize(v, 0.0, 1e8, 1e8)).collect();
                assert_eq!(&got[3 * i..3 * i + 3], &c[..], "{name} frame {t}: miss {i} passes its color through");
            }
        }
    }
}

#[test]
fn out_of_bounds_reads_are_zero_where_the_kernels_rely_on_it() {
    // kernels::out_of_bounds_reads_zero lets the conv kernels read their zero padding without
    // testing each pixel (conv_common.wgsl's OOB_ZERO). Where it says so, a texel read outside
    // a 4 x 4 x 2 texture of sevens is zero, from a sampled and from a storage source, at each
    // side, diagonally and far out; inside it is seven either way.
    let g = gpu();
    let texture = g.device.create_texture_with_data(
        &g.queue,
        &wgpu::TextureDescriptor {
            label: None,
            size: wgpu::Extent3d { width: 4, height: 4, depth_or_array_layers: 2 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba32Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::STORAGE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        bytemuck::cast_slice(&[7.0f32; 4 * 4 * 2 * 4]),
    );
    let view = array_view(&texture);
    let points: [[i32; 2]; 8] = [[1, 2], [-1, 0], [0, -1], [4, 0], [0, 4], [-1, -1], [4, 4], [9, -7]];
    let coords: String = points.iter().map(|[x, y]| format!("vec2<i32>({x}, {y}), ")).collect();
    let source = format!(
        "@group(0) @binding(0) var sampled: texture_2d_array<f32>;
         @group(0) @binding(1) var stored: texture_storage_2d_array<rgba32float, read>;
         @group(0) @binding(2) var<storage, read_write> out: array<vec4<f32>>;
         const POINTS = array<vec2<i32>, {n}>({coords});
         @compute @workgroup_size(1)
         fn main() {{
             for (var i = 0u; i < {n}u; i++) {{
                 out[2u * i] = textureLoad(sampled, POINTS[i], 1, 0);
                 out[2u * i + 1u] = textureLoad(stored, POINTS[i], 1);
             }}
         }}",
        n = points.len()
    );
    let module =
        g.device.create_shader_module(wgpu::ShaderModuleDescriptor { label: None, source: wgpu::ShaderSource::Wgsl(source.into()) });
    let pipeline = g.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: None,
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let bytes = (points.len() * 2 * 16) as u64;
    let out = g.device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let read = g.device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let group = g.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&view) },
            wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(&view) },
            wgpu::BindGroupEntry { binding: 2, resource: out.as_entire_binding() },
        ],
    });
    let mut e = g.device.create_command_encoder(&Default::default());
    {
        let mut pass = e.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(1, 1, 1);
    }
    e.copy_buffer_to_buffer(&out, 0, &read, 0, bytes);
    g.queue.submit([e.finish()]);
    read.slice(..).map_async(wgpu::MapMode::Read, |r| r.expect("map"));
    g.device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
    let v: Vec<f32> = bytemuck::cast_slice(&read.slice(..).get_mapped_range().unwrap()).to_vec();
    let texel = |i: usize, kind: usize| &v[(2 * i + kind) * 4..(2 * i + kind) * 4 + 4];
    for kind in 0..2 {
        assert_eq!(texel(0, kind), [7.0; 4], "inside, {}", ["sampled", "storage"][kind]);
    }
    if !kernels::out_of_bounds_reads_zero(&g.device) {
        return;
    }
    for (i, p) in points.iter().enumerate().skip(1) {
        for kind in 0..2 {
            assert_eq!(texel(i, kind), [0.0; 4], "{p:?} outside, {} source", ["sampled", "storage"][kind]);
        }
    }
}

#[test]
fn staged_outputs_are_the_unstaged_ones_bit_for_bit() {
    // Kernels::stage_outputs: an F(4x4) conv on a level a multiple of 16 wide writes the plan's
    // buffer, and the copy into its texture (ConvPlan::copy_staged) gives the texels the texture
    // store gives, in 32-bit words and (kernels::wide_staged_stores) in 64-bit ones. A 48 x 19
    // level (the last tile row half outside), 9 outputs (a last block of one channel) in
    // groups of two blocks, and its pooled output, which stays a texel store. One source and a
    // short tile, for the three pipelines' compile (the goldens stage two-source convs).
    let g = gpu();
    let dev = &g.device;
    if !kernels::winograd_lanes_supported(dev) {
        return;
    }
    let (w, h, cout) = (48usize, 19usize, 9usize);
    let (a, b) = (tensor(13, h, w, 960), Chw::zeros(1, 1, 1));
    let weight = noise(cout * 13 * 9, 962);
    let bias = noise(cout, 963);
    let (ta, tb) = (upload(&a), upload(&b));
    // (staged, 32-bit words): unstaged, staged in words, staged in 64-bit words where the
    // device stores them so.
    let wide = kernels::wide_staged_stores(dev);
    let ways: Vec<(bool, bool)> =
        [(false, false), (true, true), (true, false)].into_iter().filter(|&(s, narrow)| !s || narrow || wide).collect();
    let outputs: Vec<(Vec<f32>, Vec<f32>)> = ways
        .iter()
        .map(|&(staged, narrow)| {
            let mut k = Kernels::new(dev, kernels::Precision::F32, WeightMemory::Storage);
            if staged {
                k.stage_outputs();
            }
            if narrow {
                k.stage_in_32_bit_words();
            }
            let spec = ConvSpec { pooled: true, ..one_source_spec("staged", w as u32, h as u32, a.c, &weight, &bias) };
            let tile = Tile::winograd4_lanes(4, 2).expect("an F(4x4) tile");
            let plan = ConvPlan::new(dev, &g.queue, &mut k, &[spec], &[tile]).unwrap();
            assert_eq!(plan.staged(0), staged, "staged {staged}");
            assert!(plan.pools(0));
            let (out, pooled) = (output_texture(w, h, cout), output_texture(w / 2, h / 2, cout));
            let group = plan.bind_group(dev, &k, 0, &array_view(&ta), &array_view(&tb), &array_view(&out), Some(&array_view(&pooled)));
            let mut enc = dev.create_command_encoder(&Default::default());
            {
                let mut pass = enc.begin_compute_pass(&Default::default());
                plan.record(&mut pass, 0, false, &group);
            }
            let layers: Vec<wgpu::Origin3d> = (0..blocks(cout)).map(|z| wgpu::Origin3d { x: 0, y: 0, z }).collect();
            plan.copy_staged(&mut enc, 0, &out, &layers);
            g.queue.submit(Some(enc.finish()));
            (read_texture(dev, &g.queue, &out).unwrap(), read_texture(dev, &g.queue, &pooled).unwrap())
        })
        .collect();
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert!(outputs[0].0.iter().any(|&v| v != 0.0), "the conv wrote its output");
    for (way, (out, pooled)) in ways.iter().zip(&outputs).skip(1) {
        assert_eq!(bits(out), bits(&outputs[0].0), "output staged, 32-bit words: {}", way.1);
        assert_eq!(bits(pooled), bits(&outputs[0].1), "pooled output staged, 32-bit words: {}", way.1);
    }
    let cpu = dev.adapter_info().device_type == wgpu::DeviceType::Cpu;
    assert_eq!(outputs.len(), if wide { 3 } else { 2 });
    assert_eq!(
        wide,
        cpu && dev.features().contains(wgpu::Features::SHADER_INT64),
        "64-bit staged stores on CPU drivers with 64-bit integers"
    );
}

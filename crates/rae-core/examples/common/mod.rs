//! What the conv examples (compile_cost, pad_cost, staged_cost) share: tile names on the command line,
//! the activation textures a conv is bound to, and timing two plans side by side.

// Each example uses some of these.
#![allow(dead_code)]

use rae_core::kernels::{self, Tile, blocks};

/// The tile a name on the command line stands for: wino4lanesRxB, winolanesRxB, lanesRxB (two
/// columns), winoRxB, directRxB, mmaC or mmasC (C channels).
pub fn parse_tile(s: &str) -> Tile {
    if let Some(c) = s.strip_prefix("mmas") {
        return Tile::mma_split(c.parse().unwrap()).expect("an mma split tile");
    }
    if let Some(c) = s.strip_prefix("mma") {
        return Tile::mma(c.parse().unwrap()).expect("an mma tile");
    }
    let (method, rest) =
        ["wino4lanes", "winolanes", "lanes", "wino", "direct"].iter().find_map(|m| s.strip_prefix(m).map(|r| (*m, r))).expect("tile kind");
    let (r, b) = rest.split_once('x').expect("RxB");
    let (r, b): (u32, u32) = (r.parse().unwrap(), b.parse().unwrap());
    match method {
        "wino4lanes" => Tile::winograd4_lanes(r, b),
        "winolanes" => Tile::winograd_lanes(r, b),
        "wino" => Tile::winograd(r, b),
        "direct" => Tile::new(r, b),
        _ => Tile::lanes(r, b, 2),
    }
    .expect("a tile the kernels have")
}

/// A `w` x `h` activation texture of `channels`, viewed as the array a conv binds.
pub fn activation_view(device: &wgpu::Device, w: u32, h: u32, channels: usize) -> wgpu::TextureView {
    let t = device.create_texture(&wgpu::TextureDescriptor {
        label: None,
        size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: blocks(channels) },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: kernels::ACTIVATION_FORMAT,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::STORAGE_BINDING,
        view_formats: &[],
    });
    t.create_view(&wgpu::TextureViewDescriptor { dimension: Some(wgpu::TextureViewDimension::D2Array), ..Default::default() })
}

/// Milliseconds per dispatch of conv 0 of `plan`, from one submit of `repeat` of them waited
/// on (lavapipe compiles a pipeline at its first dispatch: time each plan once first).
pub fn time_dispatches(g: &rae_core::Gpu, plan: &kernels::ConvPlan, group: &wgpu::BindGroup, repeat: usize) -> f64 {
    let mut enc = g.device.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        for _ in 0..repeat {
            plan.record(&mut pass, 0, false, group);
        }
    }
    let t = std::time::Instant::now();
    g.queue.submit(Some(enc.finish()));
    g.device.poll(wgpu::PollType::wait_indefinitely()).expect("poll");
    t.elapsed().as_secs_f64() * 1e3 / repeat as f64
}

/// `spec` under `tile` planned twice, `setup(i, kernels)` making plan i's difference (i = 0,
/// 1) on an f32 [`kernels::Kernels`] of storage weights, each bound to `a`, `b`, `out` and
/// `pooled`: the kernels, plan and bind group of each, for [`time_pair`].
pub fn plan_pair(
    g: &rae_core::Gpu,
    spec: kernels::ConvSpec,
    tile: Tile,
    [a, b, out]: [&wgpu::TextureView; 3],
    pooled: Option<&wgpu::TextureView>,
    setup: impl Fn(usize, &mut kernels::Kernels),
) -> Vec<(kernels::Kernels, kernels::ConvPlan, wgpu::BindGroup)> {
    (0..2)
        .map(|i| {
            let mut k = kernels::Kernels::new(&g.device, kernels::Precision::F32, kernels::WeightMemory::Storage);
            setup(i, &mut k);
            let plan = kernels::ConvPlan::new(&g.device, &g.queue, &mut k, &[spec], &[tile]).expect("plan");
            let group = plan.bind_group(&g.device, &k, 0, a, b, out, pooled);
            (k, plan, group)
        })
        .collect()
}

/// The two plans of [`plan_pair`] timed in `rounds` alternating rounds of a submit of `repeat`
/// dispatches each ([`time_dispatches`], [`alternate`]), after one submit each that compiles
/// their pipelines: each one's median time per dispatch and the median ratio plan 1 / plan 0.
pub fn time_pair(
    g: &rae_core::Gpu,
    plans: &[(kernels::Kernels, kernels::ConvPlan, wgpu::BindGroup)],
    rounds: usize,
    repeat: usize,
) -> (f64, f64, f64) {
    let time = |i: usize| time_dispatches(g, &plans[i].1, &plans[i].2, repeat);
    time(0);
    time(1);
    alternate(rounds, time)
}

/// Two things timed by `time(0)` and `time(1)`/// Two things timed by `time(0)` and `time(1)` in `rounds` rounds, which goes first alternating,
/// so that the machine's drift falls on both alike: the median of each one's times and of the
/// per-round ratios time(1) / time(0).
pub fn alternate(rounds: usize, mut time: impl FnMut(usize) -> f64) -> (f64, f64, f64) {
    let (mut first, mut second, mut ratio) = (Vec::new(), Vec::new(), Vec::new());
    for r in 0..rounds {
        let (x, y) = if r % 2 == 0 {
            let x = time(0);
            (x, time(1))
        } else {
            let y = time(1);
            (time(0), y)
        };
        ratio.push(y / x);
        first.push(x);
        second.push(y);
    }
    (median(first), median(second), median(ratio))
}

/// The median of some times.
pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The probe conv the examples time: `w` x `h`, cat(a, b) of `ca` + `cb` channels read
/// directly into `bias.len()` LeakyReLU outputs, max-pooled too where `pooled`.
pub fn probe_spec<'a>(w: u32, h: u32, ca: usize, cb: usize, weight: &'a [f32], bias: &'a [f32], pooled: bool) -> kernels::ConvSpec<'a> {
    kernels::ConvSpec {
        name: "probe",
        width: w,
        height: h,
        ca,
        cb,
        cout: bias.len(),
        weight,
        bias,
        read_a: rae_core::graph::Read::Direct,
        read_b: rae_core::graph::Read::Direct,
        leaky: true,
        slope: 0.1,
        b_is_hidden: false,
        pooled,
    }
}

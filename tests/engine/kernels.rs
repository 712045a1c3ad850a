//! Each kernel against the plain CPU implementation, on odd sizes spanning several workgroups.

use rae_core::cpu::{self, Chw};
use rae_core::denoiser::read_texture;
use rae_core::graph::Read;
use rae_core::kernels::{self, ConvPlan, ConvSpec, Kernels, SourceAccess, Tile, WeightMemory, blocks};
use rae_core::{Denoiser, FrameInputs, Weights};
use wgpu::util::DeviceExt;

use crate::{Tolerance, fixture, gpu};

/// Deterministic pseudo-random values in [-1, 1) (xorshift), so the test needs no RNG crate.
pub fn noise(n: usize, seed: u64) -> Vec<f32> {
    let mut s = seed.wrapping_mul(0x9E3779B97F4A7C15) | 1;
    (0..n)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 40) as f32 / (1u64 << 23) as f32 - 1.0
        })
        .collect()
}

fn upload(t: &Chw) -> wgpu::Texture {
    let g = gpu();
    let layers = blocks(t.c);
    let mut data = vec![0f32; layers as usize * t.h * t.w * 4];
    for c in 0..t.c {
        for p in 0..t.h * t.w {
            data[((c / 4) * t.h * t.w + p) * 4 + c % 4] = t.data[c * t.h * t.w + p];
        }
    }
    g.device.create_texture_with_data(
        &g.queue,
        &wgpu::TextureDescriptor {
            label: None,
            size: wgpu::Extent3d { width: t.w as u32, height: t.h as u32, depth_or_array_layers: layers },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: kernels::ACTIVATION_FORMAT,
            // Sampled on GPUs, read-only storage on CPU drivers (kernels::SourceAccess).
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::STORAGE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        bytemuck::cast_slice(&data),
    )
}

/// A conv's `w` x `h` output texture of `cout` channels: written by the conv, or by the copy
/// of a staged output ([`ConvPlan::copy_staged`]), and read back.
fn output_texture(w: usize, h: usize, cout: usize) -> wgpu::Texture {
    gpu().device.create_texture(&wgpu::TextureDescriptor {
        label: None,
        size: wgpu::Extent3d { width: w as u32, height: h as u32, depth_or_array_layers: blocks(cout) },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: kernels::ACTIVATION_FORMAT,
        usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    })
}

fn array_view(t: &wgpu::Texture) -> wgpu::TextureView {
    t.create_view(&wgpu::TextureViewDescriptor { dimension: Some(wgpu::TextureViewDimension::D2Array), ..Default::default() })
}

/// One conv3x3.wgsl dispatch over cat(read(a), read(b)) at `w x h`, its sources read as suits
/// the device.
#[allow(clippy::too_many_arguments)]
fn gpu_conv(
    a: (&Chw, Read),
    b: Option<(&Chw, Read)>,
    weight: &[f32],
    bias: &[f32],
    leaky: bool,
    w: usize,
    h: usize,
    tile: Tile,
    memory: WeightMemory,
) -> Chw {
    let sources = SourceAccess::for_device_type(gpu().device.adapter_info().device_type);
    gpu_conv_with(a, b, weight, bias, leaky, w, h, tile, memory, sources)
}

/// [`gpu_conv`] with the sources read as `sources` says: the conv's own choice in a plan
/// ([`ConvPlan::with_sources`]) on kernels whose default is the other kind, as a tuned
/// denoiser mixes them.
#[allow(clippy::too_many_arguments)]
fn gpu_conv_with(
    a: (&Chw, Read),
    b: Option<(&Chw, Read)>,
    weight: &[f32],
    bias: &[f32],
    leaky: bool,
    w: usize,
    h: usize,
    tile: Tile,
    memory: WeightMemory,
    sources: SourceAccess,
) -> Chw {
    gpu_conv_pooled(a, b, weight, bias, leaky, w, h, tile, memory, sources, false).0
}

/// [`gpu_conv_with`] for a conv whose output is read max-pooled ([`ConvSpec::pooled`]), with
/// the pooled value the conv wrote where its tile pools ([`ConvPlan::pools`]).
#[allow(clippy::too_many_arguments)]
fn gpu_conv_pooled(
    a: (&Chw, Read),
    b: Option<(&Chw, Read)>,
    weight: &[f32],
    bias: &[f32],
    leaky: bool,
    w: usize,
    h: usize,
    tile: Tile,
    memory: WeightMemory,
    sources: SourceAccess,
    pooled: bool,
) -> (Chw, Option<Chw>) {
    let g = gpu();
    let dev = &g.device;
    let cout = bias.len();
    let other = if sources == SourceAccess::Sampled { SourceAccess::Storage } else { SourceAccess::Sampled };
    let mut kernels = Kernels::with_sources(dev, kernels::Precision::F32, memory, other);
    let cb = b.map_or(0, |b| b.0.c);
    let spec = ConvSpec {
        name: "test",
        width: w as u32,
        height: h as u32,
        ca: a.0.c,
        cb,
        cout,
        weight,
        bias,
        read_a: a.1,
        read_b: b.map_or(Read::Direct, |b| b.1),
        leaky,
        slope: 0.1,
        b_is_hidden: false,
        pooled,
    };
    let plan = ConvPlan::with_sources(dev, &g.queue, &mut kernels, &[spec], &[tile], &[sources]).unwrap();
    assert_eq!(plan.sources(), [sources]);
    let ta = upload(a.0);
    let tb = upload(b.map_or(&Chw::zeros(1, 1, 1), |b| b.0));
    let out = output_texture(w, h, cout);
    let pool_out = plan.pools(0).then(|| output_texture(w / 2, h / 2, cout));
    let pool_view = pool_out.as_ref().map(array_view);
    let group = plan.bind_group(dev, &kernels, 0, &array_view(&ta), &array_view(&tb), &array_view(&out), pool_view.as_ref());
    let mut enc = dev.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        assert!(w > 8, "the test must span several workgroups in x");
        plan.record(&mut pass, 0, false, &group);
    }
    g.queue.submit(Some(enc.finish()));
    let read = |t: &wgpu::Texture, w: usize, h: usize| {
        let raw = read_texture(dev, &g.queue, t).unwrap();
        let mut o = Chw::zeros(cout, h, w);
        for c in 0..cout {
            for p in 0..h * w {
                o.data[c * h * w + p] = raw[((c / 4) * h * w + p) * 4 + c % 4];
            }
        }
        o
    };
    (read(&out, w, h), pool_out.map(|t| read(&t, w / 2, h / 2)))
}

/// A conv with the CPU drivers' tile ([`Tile::cpu`]: weights across lanes on lavapipe), the
/// goldens' tile, so the pipelines are shared.
fn check_conv(a: (Chw, Read), b: Option<(Chw, Read)>, cout: usize, leaky: bool, w: usize, h: usize, seed: u64) {
    check_conv_tile(a, b, cout, leaky, w, h, seed, Tile::cpu(&gpu().device), WeightMemory::Uniform);
}

#[allow(clippy::too_many_arguments)]
fn check_conv_tile(
    a: (Chw, Read),
    b: Option<(Chw, Read)>,
    cout: usize,
    leaky: bool,
    w: usize,
    h: usize,
    seed: u64,
    tile: Tile,
    memory: WeightMemory,
) {
    let cin = a.0.c + b.as_ref().map_or(0, |b| b.0.c);
    // The kernel sums 9 * cin products in f32, one fused multiply-add after another, against a
    // float64 reference: the rounding of the running sum grows like sqrt(terms) (a 2,250-term
    // sum of these values is off by up to ~3e-5), so the tolerance grows with it from 1e-5 at
    // 100 terms.
    // Winograd F(4x4, 3x3)'s transforms (coefficients up to 5 in B, 8 in A, 1/24 in G) round
    // more: 1.4x that bound on 120 input channels; it gets 4x.
    let winograd4 = if tile.method == kernels::Method::Winograd4Lanes { 4.0 } else { 1.0 };
    let rel = winograd4 * 1e-5 * ((9 * cin) as f32 / 100.0).sqrt().max(1.0);
    let weight: Vec<f32> = noise(cout * cin * 9, seed).iter().map(|v| v * 0.3).collect();
    let bias = noise(cout, seed + 1);
    let got = gpu_conv((&a.0, a.1), b.as_ref().map(|b| (&b.0, b.1)), &weight, &bias, leaky, w, h, tile, memory);
    let ra = cpu::read(&a.0, a.1, h, w);
    let x = match &b {
        Some((t, m)) => cpu::concat(&ra, &cpu::read(t, *m, h, w)),
        None => ra,
    };
    let want = cpu::conv3x3(&x, &weight, &bias, leaky.then_some(0.1));
    crate::assert_close(
        Tolerance { rel },
        &format!("conv {:?}/{:?} {w}x{h} tile {tile} {}", a.1, b.as_ref().map(|b| b.1), memory.name()),
        &got.data,
        &want.data,
    );
}

/// Case `i` of a tile's sweep, seeded with `seed`: even cases read a pooled and a direct source
/// into 11 LeakyReLU outputs on a 13 x 19 level, odd ones an upsampled and a pooled-upsampled
/// source into 11 linear outputs on a 22 x 12 level (partial tiles on both edges, lanes past
/// them).
fn check_conv_case(i: usize, seed: u64, tile: Tile, memory: WeightMemory) {
    if i.is_multiple_of(2) {
        check_conv_tile(
            (tensor(6, 38, 26, seed), Read::Pool),
            Some((tensor(5, 19, 13, seed + 1), Read::Direct)),
            11,
            true,
            13,
            19,
            seed + 2,
            tile,
            memory,
        );
    } else {
        check_conv_tile(
            (tensor(6, 6, 11, seed), Read::Upsample),
            Some((tensor(5, 12, 22, seed + 1), Read::PoolUpsample)),
            11,
            false,
            22,
            12,
            seed + 2,
            tile,
            memory,
        );
    }
}

fn tensor(c: usize, h: usize, w: usize, seed: u64) -> Chw {
    Chw { c, h, w, data: noise(c * h * w, seed) }
}

#[test]
fn conv_direct_single_source_matches_cpu() {
    // 45 rows: three 16-row tiles, the last partial.
    const { assert!(45 > 2 * kernels::CONV_ROWS) };
    check_conv((tensor(5, 45, 37, 1), Read::Direct), None, 9, true, 37, 45, 10);
}

/// A conv whose output is read pooled writes the pooled value itself with the CPU tile
/// (two columns, 8 rows: each invocation holds whole 2x2 windows), bit for bit the 2x2 max of
/// what it stores, as pool.wgsl's pass took it. 46 rows: the last tile holds 6 of its 8 (rows
/// past the edge pool nothing); 9 outputs: the last block's group has one block of two; the
/// LeakyReLU's negative side and a pooled source read in the same conv.
#[test]
fn conv_pools_its_output_where_its_tile_allows() {
    let g = gpu();
    if !kernels::lanes_supported(&g.device) {
        return;
    }
    let (a, b) = (tensor(5, 92, 76, 30), tensor(3, 46, 38, 31));
    let (weight, bias) = (noise(9 * 8 * 9, 32), noise(9, 33));
    let sources = SourceAccess::for_device_type(g.device.adapter_info().device_type);
    let run = |tile| {
        gpu_conv_pooled(
            (&a, Read::Pool),
            Some((&b, Read::Direct)),
            &weight,
            &bias,
            true,
            38,
            46,
            tile,
            WeightMemory::Uniform,
            sources,
            true,
        )
    };
    let (out, pooled) = run(Tile::lanes(8, 2, 2).unwrap());
    let pooled = pooled.expect("a two-column lanes tile of 8 rows pools its output");
    let want = cpu::read(&out, Read::Pool, 23, 19);
    let wrong: Vec<usize> = (0..want.data.len()).filter(|&i| pooled.data[i].to_bits() != want.data[i].to_bits()).collect();
    assert!(
        wrong.is_empty(),
        "{} of {} pooled values differ from the 2x2 max of the output, first at {:?}",
        wrong.len(),
        want.data.len(),
        wrong.first()
    );
    assert!(out.data.iter().any(|&v| v < 0.0), "the LeakyReLU's negative side is exercised");
    // One column: the pool pass stays; the conv's own output is the same.
    let (one_column, none) = run(Tile::lanes(8, 2, 1).unwrap());
    assert!(none.is_none(), "a one-column tile leaves pooling to the pass");
    assert_eq!(one_column.data, out.data);
}

#[test]
fn conv_pool_and_direct_concat_matches_cpu() {
    // cat(maxpool(a), b): a at twice the resolution, b as-is; 21 outputs = 2 tiles of blocks.
    check_conv((tensor(5, 90, 74, 2), Read::Pool), Some((tensor(7, 45, 37, 3), Read::Direct)), 21, false, 37, 45, 20);
}

#[test]
fn conv_upsample_and_pooled_skip_matches_cpu() {
    // The reference decoder: upsample(cat(prev, pool(skip))) = cat(up(prev), up(pool(skip))).
    check_conv((tensor(6, 23, 19, 4), Read::Upsample), Some((tensor(3, 46, 38, 5), Read::PoolUpsample)), 11, true, 38, 46, 30);
}

#[test]
fn conv_upsample_and_prepool_skip_matches_cpu() {
    // The paper's decoder: cat(up(prev), skip before pooling).
    check_conv((tensor(4, 23, 19, 6), Read::Upsample), Some((tensor(9, 45, 37, 7), Read::Direct)), 3, false, 37, 45, 40);
}

#[test]
fn conv_wide_input_uses_one_block_per_invocation_and_matches_cpu() {
    // 250 input channels (63 blocks): two output blocks' taps no longer fit a 64 KiB chunk.
    assert_eq!(kernels::blocks_per_invocation(63, 9), Some(1));
    assert_eq!(kernels::blocks_per_invocation(51, 9), Some(2), "the widest conv of the default network");
    assert_eq!(kernels::blocks_per_invocation(28, 9), Some(4), "4 blocks up to 112 input channels");
    assert_eq!(kernels::blocks_per_invocation(29, 9), Some(2));
    assert_eq!(kernels::blocks_per_invocation(114, 9), None);
    assert_eq!(kernels::blocks_per_invocation(63, 16), Some(1), "Winograd: 16 weights per pair");
    assert_eq!(kernels::blocks_per_invocation(64, 16), None);
    check_conv((tensor(130, 45, 37, 8), Read::Direct), Some((tensor(120, 45, 37, 9), Read::Direct)), 7, true, 37, 45, 50);
}

#[test]
fn conv_on_low_levels_uses_short_tiles_and_matches_cpu() {
    // Frames 1 to 9 pixels high run 2-, 4-, 8- and 16-row tiles; 40 outputs (10 blocks) with
    // 9 inputs put all 5 two-block groups in one dispatch (workgroup z).
    assert_eq!([1, 2, 3, 4, 5, 8, 9, 64].map(|h| kernels::rows_per_invocation(h, 16)), [2, 2, 4, 4, 8, 8, 16, 16]);
    assert_eq!([1, 3, 5, 9, 64].map(|h| kernels::rows_per_invocation(h, 4)), [2, 4, 4, 4, 4]);
    for (h, seed) in [(1, 60), (2, 61), (3, 62), (5, 63), (9, 64)] {
        check_conv((tensor(9, h, 11, seed), Read::Direct), None, 40, true, 11, h, seed + 100);
    }
    check_conv((tensor(6, 6, 22, 65), Read::Pool), Some((tensor(5, 3, 11, 66), Read::Direct)), 13, false, 11, 3, 165);
}

#[test]
fn conv_every_tile_shape_matches_cpu() {
    // Each row, block and column count and workgroup shape the kernel compiles, on a level 19
    // rows high and 13 wide (partial last tiles in both directions) with 3 output blocks (a
    // partial last group for 2-block tiles).
    let shapes = [
        (1, 1, 1, 8),
        (1, 2, 1, 8),
        (2, 2, 1, 8),
        (4, 1, 1, 8),
        (4, 2, 1, 8),
        (8, 2, 1, 8),
        (16, 1, 1, 8),
        (1, 2, 2, 8),
        (4, 1, 2, 8),
        (8, 2, 2, 8),
        (16, 1, 2, 8),
        (8, 1, 1, 32),
        (4, 2, 2, 16),
        (2, 1, 2, 64),
    ];
    for (i, (rows, blocks, cols, group)) in shapes.into_iter().enumerate() {
        let tile = Tile::with_cols(rows, blocks, cols).and_then(|t| t.with_group(group)).expect("a kernel tile");
        let seed = 70 + 3 * i as u64;
        check_conv_tile(
            (tensor(6, 38, 26, seed), Read::Pool),
            Some((tensor(5, 19, 13, seed + 1), Read::Direct)),
            11,
            true,
            13,
            19,
            seed + 2,
            tile,
            WeightMemory::Uniform,
        );
    }
    // Four blocks per invocation, on a conv of 6 output blocks (a partial second group) and on
    // one of 3 (one group, its fourth block computed and dropped).
    for (i, (rows, cout)) in [(4, 22), (16, 11)].into_iter().enumerate() {
        let tile = Tile::new(rows, 4).expect("a 4-block tile");
        let seed = 120 + 3 * i as u64;
        check_conv_tile(
            (tensor(6, 38, 26, seed), Read::Pool),
            Some((tensor(5, 19, 13, seed + 1), Read::Direct)),
            cout,
            true,
            13,
            19,
            seed + 2,
            tile,
            WeightMemory::Uniform,
        );
    }
    assert_eq!(Tile::new(3, 1), None);
    assert_eq!(Tile::new(16, 3), None);
    assert_eq!(Tile::with_cols(16, 4, 2), None, "4 blocks take the second column's accumulators");
    assert_eq!(Tile::with_cols(8, 1, 3), None);
    assert_eq!(Tile::default().with_group(128), None);
}

#[test]
fn conv_lanes_tiles_match_cpu() {
    // Weights loaded across the subgroup: 1, 2 and 4 blocks per invocation (one, two or three
    // loads per tap) in one or two columns, split-K, both weight memories and a wider
    // workgroup, on levels 13 and 22 wide (subgroups with lanes past the right edge, which load
    // for the others; an odd width leaves a second column outside) and 19 and 12 high; every
    // check_conv case runs 16 x 4 with lanes too where the device has them.
    let g = gpu();
    let lanes = |rows, blocks, cols| Tile::lanes(rows, blocks, cols).expect("a lanes tile");
    let cases = [
        (lanes(16, 1, 1), WeightMemory::Uniform),
        (lanes(8, 2, 1).with_group(32).unwrap(), WeightMemory::Storage),
        (lanes(4, 4, 1).with_split(2).unwrap(), WeightMemory::Uniform),
        // Two columns (short tiles: their unrolled body compiles slowly on lavapipe).
        (lanes(4, 4, 2), WeightMemory::Storage),
        (lanes(8, 2, 2).with_group(16).unwrap(), WeightMemory::Uniform),
        (lanes(2, 1, 2).with_split(3).unwrap(), WeightMemory::Uniform),
    ];
    if !kernels::lanes_supported(&g.device) {
        refused_without_8_lanes(cases[0].0);
        return;
    }
    for (i, (tile, memory)) in cases.into_iter().enumerate() {
        check_conv_case(i, 700 + 3 * i as u64, tile, memory);
    }
    // The same products summed in the same order as the direct tile: bit-identical.
    let (a, b) = (tensor(6, 38, 26, 710), tensor(5, 19, 13, 711));
    let (weight, bias) = (noise(11 * 11 * 9, 712), noise(11, 713));
    let run = |tile| gpu_conv((&a, Read::Pool), Some((&b, Read::Direct)), &weight, &bias, true, 13, 19, tile, WeightMemory::Uniform).data;
    assert_eq!(run(lanes(16, 1, 1)), run(Tile::new(16, 1).unwrap()), "lanes16x1 against 16x1");
    assert_eq!(run(lanes(4, 2, 2)), run(Tile::with_cols(4, 2, 2).unwrap()), "lanes4x2w2 against 4x2w2");
    assert_eq!(run(lanes(4, 4, 2)), run(lanes(4, 4, 1)), "two columns against one");
    assert_eq!(lanes(16, 4, 1).to_string(), "lanes16x4");
    assert_eq!(Some(Tile::CPU_LANES), Tile::lanes(8, 2, 2), "the CPU drivers' tile is one the kernel has");
    assert_eq!(Tile::CPU_LANES.to_string(), "lanes8x2w2");
    assert_eq!(lanes(8, 4, 2).to_string(), "lanes8x4w2");
    assert_eq!(Tile::with_cols(8, 2, 2).unwrap().with_lanes(), Tile::lanes(8, 2, 2));
    assert_eq!(Tile::lanes(16, 3, 1), None);
    assert_eq!(Tile::lanes(16, 4, 3), None);
    assert_eq!(Tile::lanes(16, 2, 2), None, "two-column lanes tiles have at most 8 rows");
    assert_eq!(Tile::with_cols(16, 2, 2).unwrap().with_lanes(), None);
    assert_eq!(Tile::with_cols(8, 2, 2).unwrap().with_group(32).unwrap().with_lanes().map(|t| t.group_x), Some(32));
    assert_eq!(Tile::winograd(2, 1).unwrap().with_lanes(), None);
}

#[test]
fn conv_winograd_tiles_match_cpu() {
    // Every Winograd tile (one or two stacked 2x2 output tiles, one or two output blocks), with
    // both weight memories and every read mode, on levels of odd width and height (partial tiles
    // on both edges); 11 outputs make a partial last group of 2-block tiles.
    let cases = [
        (2, 1, WeightMemory::Uniform, 8),
        (2, 2, WeightMemory::Storage, 32),
        (4, 1, WeightMemory::Storage, 16),
        (4, 2, WeightMemory::Uniform, 64),
    ];
    for (i, (rows, blocks, memory, group)) in cases.into_iter().enumerate() {
        let tile = Tile::winograd(rows, blocks).and_then(|t| t.with_group(group)).expect("a Winograd tile");
        assert_eq!((tile.cols, tile.taps()), (2, 16));
        check_conv_case(i, 200 + 3 * i as u64, tile, memory);
    }
    // One row: the level of a deep conv on a small frame.
    check_conv_tile((tensor(9, 1, 11, 230), Read::Direct), None, 8, true, 11, 1, 231, Tile::winograd(4, 2).unwrap(), WeightMemory::Storage);
    // The widest input a Winograd chunk holds (252 channels, 63 blocks, one output block).
    check_conv_tile(
        (tensor(128, 9, 13, 232), Read::Direct),
        Some((tensor(124, 9, 13, 233), Read::Direct)),
        5,
        true,
        13,
        9,
        234,
        Tile::winograd(2, 2).unwrap(),
        WeightMemory::Uniform,
    );
    assert_eq!(Tile::winograd(8, 1), None);
    assert_eq!(Tile::winograd(2, 3), None);
    assert_eq!(Tile::winograd(4, 1).unwrap().to_string(), "wino4x1");
}

#[test]
fn conv_winograd_lanes_tiles_match_cpu_and_the_winograd_tiles() {
    // Winograd with its weights across the subgroup: two stacked 2x2 tiles, one, two and four
    // blocks, both weight memories and every read mode, on levels 13 and 22 wide and 19
    // and 12 high (partial tiles on both edges, lanes past them loading for the others).
    let g = gpu();
    let wl = |rows, blocks| Tile::winograd_lanes(rows, blocks).expect("a Winograd lanes tile");
    if !kernels::winograd_lanes_supported(&g.device) {
        refused_without_8_lanes(wl(4, 2));
        return;
    }
    let cases = [
        (wl(4, 2), WeightMemory::Uniform),
        (wl(4, 1).with_group(32).unwrap(), WeightMemory::Storage),
        (wl(4, 4), WeightMemory::Storage),
        (wl(4, 2), WeightMemory::Storage),
        (wl(4, 4), WeightMemory::Uniform),
        (wl(4, 1), WeightMemory::Uniform),
    ];
    for (i, (tile, memory)) in cases.into_iter().enumerate() {
        assert_eq!((tile.cols, tile.taps()), (2, 16));
        check_conv_case(i, 800 + 3 * i as u64, tile, memory);
    }
    // One row: a deep level of a small frame.
    check_conv_tile((tensor(9, 1, 11, 830), Read::Direct), None, 8, true, 11, 1, 831, wl(4, 4), WeightMemory::Storage);
    // The same transforms and sums in the same order as `winograd`'s: bit-identical.
    let (a, b) = (tensor(6, 38, 26, 840), tensor(5, 19, 13, 841));
    let (weight, bias) = (noise(11 * 11 * 9, 842), noise(11, 843));
    let run = |tile| gpu_conv((&a, Read::Pool), Some((&b, Read::Direct)), &weight, &bias, true, 13, 19, tile, WeightMemory::Uniform).data;
    let wino = run(Tile::winograd(4, 2).unwrap());
    assert_eq!(run(wl(4, 2)), wino, "winolanes4x2 against wino4x2");
    assert_eq!(run(wl(4, 4)), wino, "winolanes4x4 against wino4x2");
    // Its pooled output is the 2x2 max of its output, bit for bit (the pool pass's).
    pools_as_the_pool_pass(wl(4, 4), 850);
    assert_eq!(wl(4, 2).to_string(), "winolanes4x2");
    assert_eq!(Tile::CPU_WINOGRAD, wl(4, 4), "the CPU drivers' Winograd tile is one the kernel has");
    assert_eq!(Tile::winograd_lanes(2, 1), None);
    assert_eq!(Tile::winograd_lanes(8, 1), None);
    assert_eq!(Tile::winograd_lanes(4, 3), None);
    assert_eq!(wl(4, 2).with_split(2), None);
}

#[test]
fn conv_winograd4_lanes_tiles_match_cpu_and_pool_their_output() {
    // Winograd F(4x4, 3x3) with its weights in the plan's weight texture, across the subgroup:
    // one 4x4 tile, one, two and four blocks, either weight memory (the texture serves both
    // layouts) and every read mode, on levels 13 and 22 wide (4-column tiles with 1
    // and 2 columns inside) and 19 and 12 high, against the float64 sum.
    let g = gpu();
    let w4 = |rows, blocks| Tile::winograd4_lanes(rows, blocks).expect("a Winograd F(4x4) lanes tile");
    if !kernels::winograd_lanes_supported(&g.device) {
        refused_without_8_lanes(w4(4, 4));
        return;
    }
    // Every output-block count (every broadcast of the gathers), each weight memory.
    let cases = [
        (w4(4, 4), WeightMemory::Storage),
        (w4(4, 1).with_group(32).unwrap(), WeightMemory::Uniform),
        (w4(4, 2), WeightMemory::Uniform),
        (w4(4, 4), WeightMemory::Uniform),
    ];
    for (i, (tile, memory)) in cases.into_iter().enumerate() {
        assert_eq!((tile.cols, tile.taps()), (4, 36));
        check_conv_case(i, 900 + 3 * i as u64, tile, memory);
    }
    // The CPU drivers' own F(4x4) tile (Tile::cpu_for) for the rest.
    let cpu = Tile::CPU_WINOGRAD4;
    // One row (a deep level of a small frame), and 30 input blocks with uniform weights, more
    // than a 64 KiB chunk holds of them: the texture has no chunk limit.
    check_conv_tile((tensor(9, 1, 11, 930), Read::Direct), None, 8, true, 11, 1, 931, cpu, WeightMemory::Storage);
    check_conv_tile(
        (tensor(60, 10, 9, 932), Read::Direct),
        Some((tensor(60, 10, 9, 933), Read::Direct)),
        13,
        false,
        9,
        10,
        934,
        cpu,
        WeightMemory::Uniform,
    );
    // Its pooled output is the 2x2 max of its output, bit for bit, with the last column of tiles
    // half outside the level.
    pools_as_the_pool_pass(cpu, 950);
    assert_eq!(w4(4, 2).to_string(), "wino4lanes4x2");
    assert_eq!(Tile::CPU_WINOGRAD4, w4(4, 4), "the CPU drivers' F(4x4) tile is one the kernel has");
    assert_eq!(Tile::winograd4_lanes(2, 1), None);
    assert_eq!(Tile::winograd4_lanes(8, 4), None);
    assert_eq!(Tile::winograd4_lanes(4, 3), None);
    assert_eq!(w4(4, 2).with_split(2), None);
}

/// The bits of `spec`'s output texels under each of `tiles` (one plan of `k` for them all),
/// reading `ta` and `tb`: for holding two ways of planning the same convs to each other bit
/// for bit.
fn outputs_per_tile(k: &mut Kernels, spec: ConvSpec, tiles: &[Tile], ta: &wgpu::Texture, tb: &wgpu::Texture) -> Vec<Vec<u32>> {
    let g = gpu();
    let dev = &g.device;
    let specs = vec![spec; tiles.len()];
    let plan = ConvPlan::new(dev, &g.queue, k, &specs, tiles).unwrap();
    (0..tiles.len())
        .map(|i| {
            let out = output_texture(spec.width as usize, spec.height as usize, spec.cout);
            let group = plan.bind_group(dev, k, i, &array_view(ta), &array_view(tb), &array_view(&out), None);
            let mut enc = dev.create_command_encoder(&Default::default());
            {
                let mut pass = enc.begin_compute_pass(&Default::default());
                plan.record(&mut pass, i, false, &group);
            }
            g.queue.submit(Some(enc.finish()));
            read_texture(dev, &g.queue, &out).unwrap().iter().map(|x| x.to_bits()).collect()
        })
        .collect()
}

#[test]
fn gathers_in_8_lanes_are_the_16_lane_ones_bit_for_bit() {
    // conv3x3_gather8.wgsl, the Winograd lanes kernels' gathers on 8-lane subgroups (lavapipe
    // without AVX-512), loads each gather of 16 vec4s in two loads of 8 and broadcasts every
    // vec4 from where it landed: the outputs are conv3x3_gather16.wgsl's bit for bit. Held where
    // the device's subgroups have 16 lanes or more and so run both (Kernels::gather_in_8_lanes);
    // on 8 lanes the sweeps above hold the 8-lane gathers to the CPU and to `winograd`. F(2x2)
    // with two and four blocks takes the ob2 and ob4 broadcasts, F(4x4) with one the ob1 ones.
    let g = gpu();
    let dev = &g.device;
    if kernels::narrow_gathers(dev) || !kernels::winograd_lanes_supported(dev) {
        return;
    }
    let (w, h, cout) = (22usize, 13usize, 11usize);
    let (a, b) = (tensor(7, h, w, 970), tensor(5, h, w, 971));
    let (weight, bias) = (noise(cout * 12 * 9, 972), noise(cout, 973));
    let (ta, tb) = (upload(&a), upload(&b));
    let tiles = [
        Tile::winograd_lanes(4, 2).expect("an F(2x2) tile"),
        Tile::winograd_lanes(4, 4).expect("an F(2x2) tile"),
        Tile::winograd4_lanes(4, 1).expect("an F(4x4) tile"),
    ];
    let spec = ConvSpec { cb: b.c, ..one_source_spec("gathers", w as u32, h as u32, a.c, &weight, &bias) };
    // Each tile's output texels, with the gathers in loads of 8 lanes or of 16.
    let run = |in_8_lanes: bool| -> Vec<Vec<u32>> {
        let mut k = Kernels::new(dev, kernels::Precision::F32, WeightMemory::Storage);
        if in_8_lanes {
            k.gather_in_8_lanes();
        }
        outputs_per_tile(&mut k, spec, &tiles, &ta, &tb)
    };
    let (wide, narrow) = (run(false), run(true));
    for ((tile, wide), narrow) in tiles.iter().zip(&wide).zip(&narrow) {
        assert!(wide.iter().any(|&v| v != 0), "{tile} wrote its output");
        assert_eq!(narrow, wide, "{tile}: 8-lane gathers against 16-lane ones");
    }
}

/// `tile` on a device without subgroups of 8 lanes or more: refused, with the reason.
fn refused_without_8_lanes(tile: Tile) {
    let g = gpu();
    let mut k = Kernels::new(&g.device, kernels::Precision::F32, WeightMemory::Storage);
    let (weight, bias) = (vec![0.0; 4 * 4 * 9], vec![0.0; 4]);
    let err =
        ConvPlan::new(&g.device, &g.queue, &mut k, &[one_source_spec("c", 16, 16, 4, &weight, &bias)], &[tile]).err().expect("refused");
    assert!(err.to_string().contains("subgroups of at least 8 lanes"), "{err}");
}

/// A conv with `tile` (one that pools its own output) reading a pooled and a direct source on a
/// 38 x 46 level (38 = 9 x 4 + 2: a 4-column tile half outside) into 9 LeakyReLU outputs: its
/// pooled output is the 2x2 max of its output, bit for bit (the pool pass's).
fn pools_as_the_pool_pass(tile: Tile, seed: u64) {
    let g = gpu();
    let (c, d) = (tensor(5, 92, 76, seed), tensor(3, 46, 38, seed + 1));
    let (weight, bias) = (noise(9 * 8 * 9, seed + 2), noise(9, seed + 3));
    let sources = SourceAccess::for_device_type(g.device.adapter_info().device_type);
    let (out, pooled) = gpu_conv_pooled(
        (&c, Read::Pool),
        Some((&d, Read::Direct)),
        &weight,
        &bias,
        true,
        38,
        46,
        tile,
        WeightMemory::Storage,
        sources,
        true,
    );
    let pooled = pooled.unwrap_or_else(|| panic!("{tile} pools its output"));
    let want = cpu::read(&out, Read::Pool, 23, 19);
    assert!(pooled.data.iter().zip(&want.data).all(|(p, w)| p.to_bits() == w.to_bits()), "{tile}: pooled values differ from the 2x2 max");
    assert!(out.data.iter().any(|&v| v < 0.0), "the LeakyReLU's negative side is exercised");
}

/// A LeakyReLU conv reading `ca` channels of one source directly (`bias.len()` outputs).
fn one_source_spec<'a>(name: &'a str, width: u32, height: u32, ca: usize, weight: &'a [f32], bias: &'a [f32]) -> ConvSpec<'a> {
    ConvSpec {
        name,
        width,
        height,
        ca,
        cb: 0,
        cout: bias.len(),
        weight,
        bias,
        read_a: Read::Direct,
        read_b: Read::Direct,
        leaky: true,
        slope: 0.1,
        b_is_hidden: false,
        pooled: false,
    }
}

#[test]
fn conv_split_k_matches_cpu() {
    // Input blocks split among 2, 3 and 4 parts, the split crossing from source a to b, with
    // both weight memories and every read mode; a second pass adds the parts. One output block:
    // the partial sums of 4 parts fill the budget of a lone full-resolution conv.
    let cases = [(4, 2, WeightMemory::Uniform), (8, 3, WeightMemory::Storage), (1, 4, WeightMemory::Storage)];
    for (i, (rows, split, memory)) in cases.into_iter().enumerate() {
        let tile = Tile::new(rows, 1).and_then(|t| t.with_split(split)).expect("a split tile");
        let seed = 500 + 3 * i as u64;
        if i % 2 == 0 {
            check_conv_tile(
                (tensor(10, 38, 26, seed), Read::Pool),
                Some((tensor(5, 19, 13, seed + 1), Read::Direct)),
                4,
                true,
                13,
                19,
                seed + 2,
                tile,
                memory,
            );
        } else {
            check_conv_tile(
                (tensor(10, 6, 11, seed), Read::Upsample),
                Some((tensor(5, 12, 22, seed + 1), Read::PoolUpsample)),
                3,
                false,
                22,
                12,
                seed + 2,
                tile,
                memory,
            );
        }
    }
    assert_eq!(Tile::winograd(2, 1).unwrap().with_split(2), None);
    assert_eq!(Tile::new(4, 1).unwrap().with_split(17), None);
    assert_eq!(Tile::new(4, 1).unwrap().with_group(32).unwrap().with_split(8).unwrap().to_string(), "4x1g32k8");
}

#[test]
fn split_k_is_capped_by_input_blocks_and_partial_memory() {
    // A full-resolution conv and one at 1/8 resolution, both asking for 16 parts: the deep one
    // gets one part per input block (5), the full-resolution one (3 output blocks) only what
    // fits 4 layers of partial sums (1), and the buffer is sized for the deep one.
    let g = gpu();
    let mut kernels = Kernels::new(&g.device, kernels::Precision::F32, WeightMemory::Storage);
    let (weight, bias) = (vec![0.0; 12 * 20 * 9], vec![0.0; 12]);
    let spec = |width, height| one_source_spec("d1.l2.0", width, height, 20, &weight, &bias);
    let tile = Tile::new(4, 1).unwrap().with_split(16).unwrap();
    let plan = ConvPlan::new(&g.device, &g.queue, &mut kernels, &[spec(64, 64), spec(8, 8)], &[tile]).unwrap();
    assert_eq!(plan.tiles().iter().map(|t| t.split).collect::<Vec<_>>(), [1, 5]);
    assert_eq!(kernels::PARTIAL_LAYERS, 4);
}

#[test]
fn four_block_tiles_shrink_to_the_conv() {
    // 16 x 4 asked of every conv: 4 blocks where 4 output blocks and their weights fit (64
    // inputs), 2 for 2 output blocks, 1 for one (the 3-channel output), 2 where 4 blocks' weights
    // overflow a chunk (120 inputs); storage weights have no chunk.
    let g = gpu();
    let tile = Tile::new(16, 4).unwrap();
    let blocks = |memory, ca: usize, cout: usize| {
        let mut kernels = Kernels::new(&g.device, kernels::Precision::F32, memory);
        let (weight, bias) = (vec![0.0; cout * ca * 9], vec![0.0; cout]);
        let plan = ConvPlan::new(&g.device, &g.queue, &mut kernels, &[one_source_spec("c", 16, 16, ca, &weight, &bias)], &[tile]).unwrap();
        plan.tiles()[0].blocks
    };
    assert_eq!(blocks(WeightMemory::Uniform, 64, 16), 4);
    assert_eq!(blocks(WeightMemory::Uniform, 64, 11), 4);
    assert_eq!(blocks(WeightMemory::Uniform, 64, 8), 2);
    assert_eq!(blocks(WeightMemory::Uniform, 64, 3), 1);
    assert_eq!(blocks(WeightMemory::Uniform, 120, 16), 2);
    assert_eq!(blocks(WeightMemory::Storage, 120, 16), 4);
}

#[test]
fn sampled_and_storage_sources_give_the_same_convs() {
    // The same texels whether the sources are sampled textures or read-only storage textures:
    // every read mode, one and two sources, a direct and a lanes tile; bit-identical.
    let (a, b) = (tensor(6, 38, 26, 900), tensor(5, 19, 13, 901));
    let (up, skip) = (tensor(6, 6, 11, 902), tensor(5, 12, 22, 903));
    let (weight, bias) = (noise(11 * 11 * 9, 904), noise(11, 905));
    let lanes = Tile::lanes(4, 2, 1).filter(|_| kernels::lanes_supported(&gpu().device));
    for tile in [Some(Tile::new(4, 1).unwrap()), lanes].into_iter().flatten() {
        let run = |sources| {
            let pooled = gpu_conv_with(
                (&a, Read::Pool),
                Some((&b, Read::Direct)),
                &weight,
                &bias,
                true,
                13,
                19,
                tile,
                WeightMemory::Uniform,
                sources,
            );
            let upsampled = gpu_conv_with(
                (&up, Read::Upsample),
                Some((&skip, Read::PoolUpsample)),
                &weight,
                &bias,
                false,
                22,
                12,
                tile,
                WeightMemory::Uniform,
                sources,
            );
            (pooled.data, upsampled.data)
        };
        assert_eq!(run(SourceAccess::Sampled), run(SourceAccess::Storage), "{tile}");
    }
    assert_eq!(SourceAccess::for_device_type(wgpu::DeviceType::Cpu), SourceAccess::Storage);
    assert_eq!(SourceAccess::for_device_type(wgpu::DeviceType::DiscreteGpu), SourceAccess::Sampled);
}

#[test]
fn plans_make_each_pipeline_once() {
    // Three convs of two variants (a 4-row level takes a 4-row tile), made side by side: two
    // pipelines, one per variant, and none more for a second plan of the same convs or for a
    // split conv's reduce pass beside its conv.
    let g = gpu();
    let mut kernels = Kernels::new(&g.device, kernels::Precision::F32, WeightMemory::Uniform);
    let (weight, bias) = (vec![0.0; 8 * 8 * 9], vec![0.0; 8]);
    let specs = [
        one_source_spec("a", 16, 16, 8, &weight, &bias),
        one_source_spec("b", 16, 16, 8, &weight, &bias),
        one_source_spec("c", 16, 4, 8, &weight, &bias),
    ];
    let tile = Tile::new(16, 2).unwrap();
    ConvPlan::new(&g.device, &g.queue, &mut kernels, &specs, &[tile]).unwrap();
    assert_eq!(kernels.conv_pipelines(), 2);
    ConvPlan::new(&g.device, &g.queue, &mut kernels, &specs, &[tile]).unwrap();
    assert_eq!(kernels.conv_pipelines(), 2);
    ConvPlan::new(&g.device, &g.queue, &mut kernels, &specs[..1], &[tile.with_split(2).unwrap()]).unwrap();
    assert_eq!(kernels.conv_pipelines(), 4, "the split conv and its reduce pass");
    // Sources chosen per conv: the first conv's variant again, the other two as storage-texture
    // readers (one new pipeline each, in the other kind's layout).
    let (sampled, storage) = (SourceAccess::Sampled, SourceAccess::Storage);
    let default = kernels.source_access();
    let mixed = [default, if default == sampled { storage } else { sampled }];
    let plan =
        kernels::ConvPlan::with_sources(&g.device, &g.queue, &mut kernels, &specs, &[tile], &[mixed[0], mixed[1], mixed[1]]).unwrap();
    assert_eq!(plan.sources(), [mixed[0], mixed[1], mixed[1]]);
    assert_eq!(kernels.conv_pipelines(), 6);
    // Weights chosen per conv as well: the first conv in uniform chunks (its pipeline again),
    // the other two in storage (one new pipeline each, in the storage-weights layout).
    let (uniform, storage) = (WeightMemory::Uniform, WeightMemory::Storage);
    let plan =
        ConvPlan::with_choices(&g.device, &g.queue, &mut kernels, &specs, &[tile], &[mixed[0]], &[uniform, storage, storage]).unwrap();
    assert_eq!(plan.memories(), [uniform, storage, storage]);
    assert_eq!(kernels.conv_pipelines(), 8);
}

#[test]
fn convs_that_pool_share_the_pipeline_of_those_that_do_not() {
    // A tile that can pool its output has the pooled store in every conv's pipeline, and each
    // conv's parameters ask for it or not: a pooling conv and a plain one of the same shape make
    // one pipeline. (Each then gives the CPU's output: the sweeps above run plain convs on these
    // tiles, whose pooled binding is their own output, so a stray pooled store would show.)
    let g = gpu();
    let tiles = [Tile::CPU_LANES, Tile::CPU_WINOGRAD, Tile::CPU_WINOGRAD4];
    let (weight, bias) = (noise(8 * 8 * 9, 960), noise(8, 961));
    for tile in tiles {
        let supported = match tile.method {
            kernels::Method::Lanes => kernels::lanes_supported(&g.device),
            _ => kernels::winograd_lanes_supported(&g.device),
        };
        if !supported {
            continue;
        }
        let mut kernels = Kernels::new(&g.device, kernels::Precision::F32, WeightMemory::Storage);
        let plain = one_source_spec("plain", 32, 32, 8, &weight, &bias);
        let pooled = ConvSpec { name: "pooled", pooled: true, ..one_source_spec("pooled", 32, 32, 8, &weight, &bias) };
        let plan = ConvPlan::new(&g.device, &g.queue, &mut kernels, &[pooled, plain], &[tile]).unwrap();
        assert!(plan.pools(0) && !plan.pools(1), "{tile}: the first conv pools, the second does not");
        assert_eq!(kernels.conv_pipelines(), 1, "{tile}: one pipeline for both");
    }
}

#[test]
fn winograd_weight_transform_reproduces_the_direct_convolution() {
    // G g G^T on the host: for a 4x4 input patch d, A^T [(G g G^T) * (B^T d B)] A
    // equals the 2x2 direct correlation of d with g.
    let g: Vec<f32> = noise(9, 300);
    let d: Vec<f64> = noise(16, 301).iter().map(|&v| v as f64).collect();
    let u = kernels::winograd_taps(&g);
    let bt = [[1.0, 0.0, -1.0, 0.0], [0.0, 1.0, 1.0, 0.0], [0.0, -1.0, 1.0, 0.0], [0.0, 1.0, 0.0, -1.0]];
    let at = [[1.0, 1.0, 1.0, 0.0], [0.0, 1.0, -1.0, -1.0]];
    let v = |i: usize, j: usize| -> f64 {
        (0..4).flat_map(|r| (0..4).map(move |c| (r, c))).map(|(r, c)| bt[i][r] * d[r * 4 + c] * bt[j][c]).sum()
    };
    for y in 0..2 {
        for x in 0..2 {
            let wino: f64 = (0..16).map(|p| at[y][p / 4] * u[p] as f64 * v(p / 4, p % 4) * at[x][p % 4]).sum();
            let direct: f64 = (0..9).map(|t| g[t] as f64 * d[(y + t / 3) * 4 + x + t % 3]).sum();
            assert!((wino - direct).abs() < 1e-6 * (1.0 + direct.abs()), "output ({x}, {y}): {wino} vs {direct}");
        }
    }
}

#[test]
fn winograd4_weight_transform_reproduces_the_direct_convolution() {
    // The same for F(4x4, 3x3): a 6x6 patch, the kernel's B^T and A^T (conv3x3_wino4.wgsl),
    // 4x4 outputs. The transformed weights are rounded to f32 and A^T has 8s, so it holds to 1e-5.
    let g: Vec<f32> = noise(9, 310);
    let d: Vec<f64> = noise(36, 311).iter().map(|&v| v as f64).collect();
    let u = kernels::winograd4_taps(&g);
    let bt = [
        [4.0, 0.0, -5.0, 0.0, 1.0, 0.0],
        [0.0, -4.0, -4.0, 1.0, 1.0, 0.0],
        [0.0, 4.0, -4.0, -1.0, 1.0, 0.0],
        [0.0, -2.0, -1.0, 2.0, 1.0, 0.0],
        [0.0, 2.0, -1.0, -2.0, 1.0, 0.0],
        [0.0, 4.0, 0.0, -5.0, 0.0, 1.0],
    ];
    let at = [
        [1.0, 1.0, 1.0, 1.0, 1.0, 0.0],
        [0.0, 1.0, -1.0, 2.0, -2.0, 0.0],
        [0.0, 1.0, 1.0, 4.0, 4.0, 0.0],
        [0.0, 1.0, -1.0, 8.0, -8.0, 1.0],
    ];
    let v = |i: usize, j: usize| -> f64 {
        (0..6).flat_map(|r| (0..6).map(move |c| (r, c))).map(|(r, c)| bt[i][r] * d[r * 6 + c] * bt[j][c]).sum()
    };
    for y in 0..4 {
        for x in 0..4 {
            let wino: f64 = (0..36).map(|p| at[y][p / 6] * u[p] as f64 * v(p / 6, p % 6) * at[x][p % 6]).sum();
            let direct: f64 = (0..9).map(|t| g[t] as f64 * d[(y + t / 3) * 6 + x + t % 3]).sum();
            assert!((wino - direct).abs() < 1e-5 * (1.0 + direct.abs()), "output ({x}, {y}): {wino} vs {direct}");
        }
    }
}

#[test]
fn conv_with_storage_weights_matches_cpu() {
    // Weights in one storage buffer: every group in one dispatch and no chunk limit, so the
    // 250-channel conv keeps two blocks per invocation; 23 outputs = 3 groups of 2 blocks. Then
    // tiles of 1, 2 and 4 blocks on 11 outputs (3 blocks: one 4-block group with a spare).
    let storage = WeightMemory::Storage;
    check_conv_tile(
        (tensor(130, 21, 17, 90), Read::Direct),
        Some((tensor(120, 21, 17, 91), Read::Direct)),
        23,
        true,
        17,
        21,
        92,
        Tile::default(),
        storage,
    );
    for (i, tile) in [Tile::new(4, 2), Tile::new(1, 1), Tile::with_cols(8, 2, 2), Tile::new(8, 4)].into_iter().enumerate() {
        let seed = 93 + 3 * i as u64;
        check_conv_tile(
            (tensor(6, 6, 11, seed), Read::Upsample),
            Some((tensor(5, 12, 22, seed + 1), Read::PoolUpsample)),
            11,
            false,
            22,
            12,
            seed + 2,
            tile.unwrap(),
            storage,
        );
    }
}

/// An Mma conv ([`Tile::mma`]) against the CPU convolution of f16-rounded inputs and weights:
/// the kernel multiplies f16 values (exactly, in f32) and sums in f32, so with the rounding of
/// its operands reproduced on the CPU it is held to the direct kernel's tolerance.
#[allow(clippy::too_many_arguments)]
fn check_conv_mma(a: (Chw, Read), b: Option<(Chw, Read)>, cout: usize, leaky: bool, w: usize, h: usize, seed: u64, tile: Tile) {
    let cin = a.0.c + b.as_ref().map_or(0, |b| b.0.c);
    let rel = 1e-5 * ((9 * cin) as f32 / 100.0).sqrt().max(1.0);
    let weight: Vec<f32> = noise(cout * cin * 9, seed).iter().map(|v| v * 0.3).collect();
    let bias = noise(cout, seed + 1);
    let got = gpu_conv((&a.0, a.1), b.as_ref().map(|b| (&b.0, b.1)), &weight, &bias, leaky, w, h, tile, WeightMemory::Storage);
    let f16 = |v: &f32| half::f16::from_f32(*v).to_f32();
    let ra = cpu::read(&a.0, a.1, h, w);
    let mut x = match &b {
        Some((t, m)) => cpu::concat(&ra, &cpu::read(t, *m, h, w)),
        None => ra,
    };
    x.data = x.data.iter().map(f16).collect();
    let weight16: Vec<f32> = weight.iter().map(f16).collect();
    let want = cpu::conv3x3(&x, &weight16, &bias, leaky.then_some(0.1));
    crate::assert_close(
        Tolerance { rel },
        &format!("mma conv {:?}/{:?} {w}x{h} tile {tile}", a.1, b.as_ref().map(|b| b.1)),
        &got.data,
        &want.data,
    );
    // And the products' rounding is what separates it from the f32 convolution.
    let exact = cpu::conv3x3(&x, &weight, &bias, leaky.then_some(0.1));
    assert!(got.data.iter().zip(&exact.data).any(|(g, e)| g != e), "f16 weights change some output");
}

#[test]
fn conv_mma_tiles_match_cpu() {
    // The matrix-unit kernel (emulated here unless the device has cooperative matrices), on
    // levels spanning partial 64-pixel and 4-row workgroups. 43 outputs: 3 tiles of 16, the
    // last partial, in groups of 2 (the second half empty) with mma32; a pooled source and a
    // direct one (11 + 6 blocks: 5 chunks of 16 channels, the last partial).
    check_conv_mma(
        (tensor(41, 18, 140, 300), Read::Pool),
        Some((tensor(22, 9, 70, 301), Read::Direct)),
        43,
        true,
        70,
        9,
        302,
        Tile::mma(32).unwrap(),
    );
    // Upsampled and pool-upsampled sources, a linear conv with 8 outputs (one tile of 16,
    // mma64 shrinks to it), a level 14 x 6.
    check_conv_mma(
        (tensor(6, 3, 7, 303), Read::Upsample),
        Some((tensor(5, 6, 14, 304), Read::PoolUpsample)),
        8,
        false,
        14,
        6,
        305,
        Tile::mma(64).unwrap(),
    );
    // One source, 20 outputs in tiles of 16 (two groups), one row.
    check_conv_mma((tensor(33, 1, 65, 306), Read::Direct), None, 20, true, 65, 1, 307, Tile::mma(16).unwrap());
    // 48 outputs in one group of 3 tiles.
    check_conv_mma(
        (tensor(12, 5, 19, 308), Read::Direct),
        Some((tensor(12, 5, 19, 309), Read::Direct)),
        48,
        true,
        19,
        5,
        310,
        Tile::mma(48).unwrap(),
    );
    assert_eq!(Tile::mma(32).unwrap().to_string(), "mma32");
    assert_eq!(Tile::mma(24), None);
}

/// A split Mma conv ([`Tile::mma_split`]) against the CPU convolution in f32, at the direct
/// kernel's tolerance of the output's largest value, on inputs and a bias scaled by `scale`:
/// the f16-rounded operands of the plain tiles must fail the same bound, so the test tells the
/// two apart.
#[allow(clippy::too_many_arguments)]
fn check_conv_mma_split(
    a: (Chw, Read),
    b: Option<(Chw, Read)>,
    cout: usize,
    leaky: bool,
    w: usize,
    h: usize,
    seed: u64,
    tile: Tile,
    scale: f32,
) {
    let scaled = |t: Chw| Chw { data: t.data.iter().map(|v| v * scale).collect(), ..t };
    let (a, b) = ((scaled(a.0), a.1), b.map(|b| (scaled(b.0), b.1)));
    let cin = a.0.c + b.as_ref().map_or(0, |b| b.0.c);
    let rel = 1e-5 * ((9 * cin) as f32 / 100.0).sqrt().max(1.0);
    let weight: Vec<f32> = noise(cout * cin * 9, seed).iter().map(|v| v * 0.3).collect();
    let bias: Vec<f32> = noise(cout, seed + 1).iter().map(|v| v * scale).collect();
    let got = gpu_conv((&a.0, a.1), b.as_ref().map(|b| (&b.0, b.1)), &weight, &bias, leaky, w, h, tile, WeightMemory::Storage);
    let ra = cpu::read(&a.0, a.1, h, w);
    let x = match &b {
        Some((t, m)) => cpu::concat(&ra, &cpu::read(t, *m, h, w)),
        None => ra,
    };
    let want = cpu::conv3x3(&x, &weight, &bias, leaky.then_some(0.1));
    // Errors over the output's largest value (Tolerance is absolute below 1).
    let top = want.data.iter().fold(0.0f32, |m, v| m.max(v.abs()));
    let unit = |d: &[f32]| d.iter().map(|v| v / top).collect::<Vec<f32>>();
    let what = format!("split mma conv {:?}/{:?} {w}x{h} tile {tile} scale {scale}", a.1, b.as_ref().map(|b| b.1));
    crate::assert_close(Tolerance { rel }, &what, &unit(&got.data), &unit(&want.data));
    // The plain tiles' operands, f16-rounded, miss that bound.
    let f16 = |v: &f32| half::f16::from_f32(*v).to_f32();
    let x16 = Chw { data: x.data.iter().map(f16).collect(), ..x };
    let plain = cpu::conv3x3(&x16, &weight.iter().map(f16).collect::<Vec<f32>>(), &bias, leaky.then_some(0.1));
    assert!(Tolerance { rel }.worst(&unit(&plain.data), &unit(&want.data)).0 > 1.0, "{what}: f16 operands would pass too");
}

#[test]
fn conv_mma_split_tiles_match_cpu_in_f32() {
    // The split matrix-unit kernel (emulated here unless the device has cooperative matrices)
    // holds f32 convolutions to the direct kernel's tolerance: mma32x3 over a pooled and a
    // direct source (5 chunks, the last partial) with 43 outputs in groups of two tiles on a
    // level spanning partial workgroups; mma64x3 (four tiles a group, one group short of its
    // last two) on the same; mma16x3 on upsampled sources at a thousandth of the scale, where
    // an unscaled remainder would be an f16 subnormal.
    check_conv_mma_split(
        (tensor(41, 18, 140, 320), Read::Pool),
        Some((tensor(22, 9, 70, 321), Read::Direct)),
        43,
        true,
        70,
        9,
        322,
        Tile::mma_split(32).unwrap(),
        1.0,
    );
    check_conv_mma_split(
        (tensor(41, 18, 140, 326), Read::Pool),
        Some((tensor(22, 9, 70, 327), Read::Direct)),
        43,
        true,
        70,
        9,
        328,
        Tile::mma_split(64).unwrap(),
        1.0,
    );
    check_conv_mma_split(
        (tensor(6, 3, 7, 323), Read::Upsample),
        Some((tensor(5, 6, 14, 324), Read::PoolUpsample)),
        20,
        false,
        14,
        6,
        325,
        Tile::mma_split(16).unwrap(),
        1e-3,
    );
    assert_eq!(Tile::mma_split(32).unwrap().to_string(), "mma32x3");
    assert_eq!(Tile::mma_split(80), None, "at most four 16-channel tiles");
}

#[test]
fn mma_tiles_need_storage_weights() {
    let g = gpu();
    let mut kernels = Kernels::new(&g.device, kernels::Precision::F32, WeightMemory::Uniform);
    let (weight, bias) = (vec![0.0; 4 * 8 * 9], vec![0.0; 4]);
    let spec = one_source_spec("d1.l1.0", 8, 8, 8, &weight, &bias);
    let err = ConvPlan::new(&g.device, &g.queue, &mut kernels, &[spec], &[Tile::mma(16).unwrap()])
        .err()
        .expect("uniform weights are refused")
        .to_string();
    assert!(err.contains("mma16") && err.contains("storage"), "{err}");
}

#[test]
fn mma_weights_are_laid_out_as_the_kernel_reads_them() {
    // pack_mma: chunk c, tap t, tile, row k (input channel of block 4c + k / 4, lane k % 4),
    // column n; source a's 5 channels pad to 8 (2 blocks), b's 3 channels follow at block 2.
    let (cout, ca, cb) = (20, 5, 3);
    let weight: Vec<f32> = (0..cout * (ca + cb) * 9).map(|i| i as f32).collect();
    let bias: Vec<f32> = (0..cout).map(|i| 1.0 + i as f32 / 3.0).collect();
    let spec = ConvSpec { cb, read_b: Read::Direct, ..one_source_spec("test", 8, 8, ca, &weight, &bias) };
    let packed = kernels::pack_mma(&spec, 16, 2, false);
    assert_eq!(packed.len(), 9 * 2 * 256 + 64, "one chunk of 3 blocks, 9 taps, 2 tiles, the bias");
    let at = |t: usize, tile: usize, k: usize, n: usize| packed[(t * 2 + tile) * 256 + k * 16 + n].to_f32();
    let w = |o: usize, i: usize, t: usize| half::f16::from_f32(weight[(o * (ca + cb) + i) * 9 + t]).to_f32();
    // Output 16 + n (n < 4 exist), input channel 4 (block 1, lane 0) at k = 4; b's channel 0
    // (input channel 5) at block 2, k = 8.
    assert_eq!(at(7, 0, 4, 3), w(19, 4, 7));
    assert_eq!(at(2, 0, 8, 0), w(16, 5, 2));
    assert_eq!(at(2, 0, 5, 0), 0.0, "a's padding lane");
    assert_eq!(at(0, 0, 12, 0), 0.0, "the chunk's padding block");
    assert_eq!(at(0, 0, 0, 4), 0.0, "output 20 is past the conv");
    assert!((0..16 * 9 * 2).all(|i| at(i / 32, 1, (i / 16) % 16, i % 16) == 0.0), "the second tile is all padding");
    // The bias in two halves whose sum is the f32 bias to ~22 bits.
    let hi = &packed[9 * 2 * 256..][..32];
    let lo = &packed[9 * 2 * 256 + 32..];
    for n in 0..4 {
        let b = bias[16 + n];
        assert!((hi[n].to_f32() + lo[n].to_f32() - b).abs() <= b.abs() * 2e-6, "bias {n}");
    }
    assert!(hi[4..].iter().chain(&lo[4..]).all(|v| v.to_f32() == 0.0));
    // Split: the same tiles, then each weight's remainder scaled by 2^11, then the same bias;
    // hi + lo / 2^11 is the f32 weight to 22 bits.
    let weight: Vec<f32> = weight.iter().map(|v| (v + 0.1) / 7.0).collect();
    let spec = ConvSpec { weight: &weight, ..spec };
    let (plain, split) = (kernels::pack_mma(&spec, 16, 2, false), kernels::pack_mma(&spec, 16, 2, true));
    let tiles = 9 * 2 * 256;
    assert_eq!(split.len(), 2 * tiles + 64);
    assert_eq!(split[..tiles], plain[..tiles], "the hi tiles");
    assert_eq!(split[2 * tiles..], plain[tiles..], "the bias");
    for (t, k, n) in [(7, 4, 3), (2, 8, 0), (0, 1, 2)] {
        let i = (t * 2) * 256 + k * 16 + n;
        let joined = split[i].to_f32() + split[tiles + i].to_f32() / kernels::MMA_LO_SCALE;
        // Rows 0-4: a's channels 0-4; rows 8-10: b's, input channels 5-7.
        let input = if k < 5 { k } else { 5 + (k - 8) };
        let w = weight[((16 + n) * (ca + cb) + input) * 9 + t];
        assert!((joined - w).abs() <= w.abs() * 2.5e-7, "tap {t} row {k} column {n}: {joined} against {w}");
    }
}

#[test]
fn conv_too_wide_for_a_weight_chunk_is_an_error() {
    let g = gpu();
    let mut kernels = Kernels::new(&g.device, kernels::Precision::F32, kernels::WeightMemory::Uniform);
    let (weight, bias) = (vec![0.0; 4 * 460 * 9], vec![0.0; 4]);
    let spec = one_source_spec("d1.l1.0", 8, 8, 460, &weight, &bias);
    let err =
        ConvPlan::new(&g.device, &g.queue, &mut kernels, &[spec], &[Tile::default()]).err().expect("460 channels do not fit").to_string();
    assert!(err.contains("d1.l1.0") && err.contains("460"), "{err}");
}

/// A frame of `w x h` with every buffer, smooth values plus the extremes the input policy
/// handles (NaN, +-Inf, negative, huge, albedo 0).
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
    [color, albedo, normal, depth, rough]
}

fn frame_of(b: &[Vec<f32>; 5]) -> FrameInputs<'_> {
    FrameInputs { color: &b[0], albedo: Some(&b[1]), normal: Some(&b[2]), depth: Some(&b[3]), roughness: Some(&b[4]) }
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
    // sizes that need padding: 37x21 (to 40x24) and 50x35 (to 64x64).
    let g = gpu();
    for (name, w, h) in [("weights_paper_tiny.safetensors", 37, 21), ("weights_color_tiny.safetensors", 50, 35)] {
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
            let want = cpu::finish(&weights.arch, &y, cpu::color_max(&x), Some(&b[1]), w, h);
            crate::assert_close(Tolerance { rel: 1e-4 }, &format!("{name} frame {t}"), &got, &want);
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
            plan.copy_staged(&mut enc, 0, &out);
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

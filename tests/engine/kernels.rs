//! Each conv kernel against the plain CPU implementation, on odd sizes spanning several
//! workgroups: direct, lanes and split-K tiles, weight memories, source kinds, pooled stores,
//! and how plans share pipelines. The helpers here serve the other kernel test modules too.

use rae_core::cpu::{self, Chw};
use rae_core::denoiser::read_texture;
use rae_core::graph::{Place, Read};
use rae_core::kernels::{self, Carve, ConvPlan, ConvSpec, Kernels, SourceAccess, Tile, WeightMemory, blocks};
use wgpu::util::DeviceExt;

use crate::{Tolerance, gpu};

/// Deterministic pseudo-random values in [-1, 1) (xorshift), so the test needs no RNG crate.
pub(crate) fn noise(n: usize, seed: u64) -> Vec<f32> {
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

pub(crate) fn upload(t: &Chw) -> wgpu::Texture {
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
pub(crate) fn output_texture(w: usize, h: usize, cout: usize) -> wgpu::Texture {
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

pub(crate) fn array_view(t: &wgpu::Texture) -> wgpu::TextureView {
    t.create_view(&wgpu::TextureViewDescriptor { dimension: Some(wgpu::TextureViewDimension::D2Array), ..Default::default() })
}

/// One conv3x3.wgsl dispatch over cat(read(a), read(b)) at `w x h`, its sources read as suits
/// the device.
#[allow(clippy::too_many_arguments)]
pub(crate) fn gpu_conv(
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
pub(crate) fn gpu_conv_with(
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
pub(crate) fn gpu_conv_pooled(
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
        carves: [Carve::NONE; 4],
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
pub(crate) fn check_conv(a: (Chw, Read), b: Option<(Chw, Read)>, cout: usize, leaky: bool, w: usize, h: usize, seed: u64) {
    check_conv_tile(a, b, cout, leaky, w, h, seed, Tile::cpu(&gpu().device), WeightMemory::Uniform);
}

#[allow(clippy::too_many_arguments)]
pub(crate) fn check_conv_tile(
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
pub(crate) fn check_conv_case(i: usize, seed: u64, tile: Tile, memory: WeightMemory) {
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

pub(crate) fn tensor(c: usize, h: usize, w: usize, seed: u64) -> Chw {
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
    assert_eq!(Some(Tile::CPU_LANES), Tile::lanes(8, 2, 1), "the CPU drivers' tile is one the kernel has");
    assert_eq!(Tile::CPU_LANES.to_string(), "lanes8x2");
    assert_eq!(lanes(8, 4, 2).to_string(), "lanes8x4w2");
    assert_eq!(Tile::with_cols(8, 2, 2).unwrap().with_lanes(), Tile::lanes(8, 2, 2));
    assert_eq!(Tile::lanes(16, 3, 1), None);
    assert_eq!(Tile::lanes(16, 4, 3), None);
    assert_eq!(Tile::lanes(16, 2, 2), None, "two-column lanes tiles have at most 8 rows");
    assert_eq!(Tile::with_cols(16, 2, 2).unwrap().with_lanes(), None);
    assert_eq!(Tile::with_cols(8, 2, 2).unwrap().with_group(32).unwrap().with_lanes().map(|t| t.group_x), Some(32));
    assert_eq!(Tile::winograd(2, 1).unwrap().with_lanes(), None);
}

/// The bits of `spec`'s output texels under each of `tiles` (one plan of `k` for them all),
/// reading `ta` and `tb`: for holding two ways of planning the same convs to each other bit
/// for bit.
pub(crate) fn outputs_per_tile(k: &mut Kernels, spec: ConvSpec, tiles: &[Tile], ta: &wgpu::Texture, tb: &wgpu::Texture) -> Vec<Vec<u32>> {
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

/// `tile` on a device without subgroups of 8 lanes or more: refused, with the reason.
pub(crate) fn refused_without_8_lanes(tile: Tile) {
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
pub(crate) fn pools_as_the_pool_pass(tile: Tile, seed: u64) {
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
pub(crate) fn one_source_spec<'a>(name: &'a str, width: u32, height: u32, ca: usize, weight: &'a [f32], bias: &'a [f32]) -> ConvSpec<'a> {
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
        carves: [Carve::NONE; 4],
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
    // The lanes tile pools in two columns (one column holds no whole 2x2 window).
    let tiles = [Tile::lanes(8, 2, 2).unwrap(), Tile::CPU_WINOGRAD, Tile::CPU_WINOGRAD4];
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

#[test]
fn carved_values_are_read_and_written_in_their_cells_only() {
    // A conv at level 1 of 64x40 arenas (cells of 32x20 at level 1, 16x10 at level 2) over
    // cat(upsample(a), b), both carved into one arena whose other texels hold large values
    // (a fetch outside a cell, or the padding read from a neighbour, shows), writing its
    // output and its pooled output into the cells of two others, whose other texels must stay
    // as they were. Bit for bit what the same conv computes over textures of their own, for
    // the CPU drivers' tiles (the F(4x4) one staged, as on lavapipe, and copied cell by cell)
    // and a direct one, with the kernels reading their padding from outside the textures where
    // the device allows it (as a Denoiser's do).
    let g = gpu();
    let dev = &g.device;
    let (aw, ah) = (64u32, 40u32);
    let (w, h) = ((aw >> 1) as usize, (ah >> 1) as usize);
    let (ca, cb, cout) = (6, 9, 7);
    let a = Chw { c: ca, h: h / 2, w: w / 2, data: noise(ca * h * w / 4, 81) };
    let b = Chw { c: cb, h, w, data: noise(cb * h * w, 82) };
    let weight: Vec<f32> = noise(cout * (ca + cb) * 9, 83).iter().map(|v| v * 0.3).collect();
    let bias = noise(cout, 84);
    let place = |arena, level, first, channels: usize| Place { arena, level, first, blocks: blocks(channels) };
    let (pa, pb, pout, ppool) = (place(0, 2, 5, ca), place(0, 1, 3, cb), place(1, 1, 2, cout), place(2, 2, 13, cout));
    let layers = |places: &[Place]| places.iter().map(|p| (p.first + p.blocks - 1) >> (2 * p.level)).max().unwrap() + 1;
    // An arena's texels with the places' values in their cells over `fill` elsewhere.
    let arena = |places: &[(Place, &Chw)], layers: u32, fill: &dyn Fn(usize) -> f32, pad: f32| {
        let mut data: Vec<f32> = (0..layers as usize * (aw * ah) as usize * 4).map(fill).collect();
        // The channels that pad a value's last block are `pad`: zero in a source, as a conv
        // writes them; NaN in an expected output, which `check` skips.
        for (p, t) in places {
            for c in 0..4 * blocks(t.c) as usize {
                let (x0, y0, layer) = p.cell(c as u32 / 4, aw, ah);
                for y in 0..t.h {
                    for x in 0..t.w {
                        let texel = (layer as usize * ah as usize + y0 as usize + y) * aw as usize + x0 as usize + x;
                        data[texel * 4 + c % 4] = if c < t.c { t.data[(c * t.h + y) * t.w + x] } else { pad };
                    }
                }
            }
        }
        data
    };
    let texture = |data: &[f32], layers: u32| {
        dev.create_texture_with_data(
            &g.queue,
            &wgpu::TextureDescriptor {
                label: None,
                size: wgpu::Extent3d { width: aw, height: ah, depth_or_array_layers: layers },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: kernels::ACTIVATION_FORMAT,
                usage: wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::STORAGE_BINDING
                    | wgpu::TextureUsages::COPY_SRC
                    | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            },
            wgpu::util::TextureDataOrder::LayerMajor,
            bytemuck::cast_slice(data),
        )
    };
    let big = noise(layers(&[pa, pb]) as usize * (aw * ah) as usize * 4, 85);
    let sources = texture(&arena(&[(pa, &a), (pb, &b)], layers(&[pa, pb]), &|i| 1e4 * big[i], 0.0), layers(&[pa, pb]));
    let lanes = kernels::lanes_supported(dev);
    let tiles =
        [Some(Tile::default()), lanes.then_some(Tile::CPU_LANES), kernels::winograd_lanes_supported(dev).then_some(Tile::CPU_WINOGRAD4)];
    for tile in tiles.into_iter().flatten() {
        let access = SourceAccess::for_device(dev);
        let (want, want_pooled) = gpu_conv_pooled(
            (&a, Read::Upsample),
            Some((&b, Read::Direct)),
            &weight,
            &bias,
            true,
            w,
            h,
            tile,
            WeightMemory::Storage,
            access,
            true,
        );
        let mut k = Kernels::with_sources(dev, kernels::Precision::F32, WeightMemory::Storage, access);
        k.pad_from_bounds();
        let staged = tile == Tile::CPU_WINOGRAD4;
        if staged {
            k.stage_outputs();
        }
        let carve = |p: &Place| Carve::of(p, aw, ah);
        let spec = ConvSpec {
            name: "carved",
            width: w as u32,
            height: h as u32,
            ca,
            cb,
            cout,
            weight: &weight,
            bias: &bias,
            read_a: Read::Upsample,
            read_b: Read::Direct,
            leaky: true,
            slope: 0.1,
            b_is_hidden: false,
            pooled: true,
            carves: [carve(&pa), carve(&pb), carve(&pout), carve(&ppool)],
        };
        let plan = ConvPlan::with_sources(dev, &g.queue, &mut k, &[spec], &[tile], &[access]).unwrap();
        assert_eq!(plan.staged(0), staged, "{tile}");
        let sentinel = |_| 7.0;
        let (out_layers, pool_layers) = (layers(&[pout]), layers(&[ppool]));
        let out = texture(&arena(&[], out_layers, &sentinel, 0.0), out_layers);
        let pooled = texture(&arena(&[], pool_layers, &sentinel, 0.0), pool_layers);
        let group =
            plan.bind_group(dev, &k, 0, &array_view(&sources), &array_view(&sources), &array_view(&out), Some(&array_view(&pooled)));
        let mut enc = dev.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            plan.record(&mut pass, 0, false, &group);
        }
        let cells: Vec<wgpu::Origin3d> = (0..pout.blocks)
            .map(|j| {
                let (x, y, z) = pout.cell(j, aw, ah);
                wgpu::Origin3d { x, y, z }
            })
            .collect();
        plan.copy_staged(&mut enc, 0, &out, &cells);
        g.queue.submit(Some(enc.finish()));
        // Each texel read back: the value of `t` where a cell of `p` holds it, else 7.
        let check = |texture: &wgpu::Texture, p: &Place, t: &Chw, what: &str| {
            let got = read_texture(dev, &g.queue, texture).unwrap();
            let expected = arena(&[(*p, t)], layers(&[*p]), &sentinel, f32::NAN);
            let wrong: Vec<usize> =
                (0..got.len()).filter(|&i| !expected[i].is_nan() && got[i].to_bits() != expected[i].to_bits()).collect();
            assert!(wrong.is_empty(), "{tile} {what}: {} of {} texels differ, first at {:?}", wrong.len(), got.len(), wrong.first());
        };
        check(&out, &pout, &want, "output");
        if plan.pools(0) {
            check(&pooled, &ppool, &want_pooled.expect("the uncarved conv pools too"), "pooled output");
        }
    }
}

//! The conv kernel's register tile ([`Tile`]): how many rows, output blocks and columns an
//! invocation computes, by which method ([`Method`]), its text form (`Display` and `FromStr`
//! are inverses), and the tile CPU drivers run per level ([`Tile::cpu_for`]).

use super::*;

/// Most output rows per conv invocation (the tile of conv3x3.wgsl; `ROWS` picks up to it).
pub const CONV_ROWS: u32 = 16;
/// Workgroup size in x and y of every kernel (the conv's default shape; [`Tile::group_x`]).
pub const WORKGROUP: u32 = 8;

/// The most pixels of a level whose convs run 4-row lanes tiles on CPU drivers
/// ([`Tile::cpu_for`]): 8 x 8.
pub const CPU_SHORT_TILE_MAX_PIXELS: u32 = 8 * 8;

/// The fewest input blocks (4 channels each) of a conv that runs [`Tile::CPU_WINOGRAD`] on CPU
/// drivers ([`Tile::cpu_for`]): 8 (32 channels). On lavapipe the 3-channel conv runs slower in
/// it and the 8-channel one as fast (`docs/perf/lavapipe-2026-11-25-s22.log`).
pub const CPU_WINOGRAD_MIN_BLOCKS: u32 = 8;

/// The fewest pixels of a level whose convs run [`Tile::CPU_WINOGRAD4`] on CPU drivers that
/// run it (64 x 64): every conv there, down to one input block (the 256x256 frame's first conv,
/// 2 input blocks, takes 0.82x the time of `lanes8x2w2`'s; `docs/perf/lavapipe-2026-11-25-s23.log`).
/// On 32 x 32 levels F(4x4) also runs faster than F(2x2), but a level that small is a few
/// percent of any frame worth timing, and lavapipe compiles an F(4x4) pipeline for seconds
/// where F(2x2)'s take a fraction of that: a 64x64 frame's first frame compiles in 14.9 s
/// into an empty shader cache, 24.9 s with F(4x4) on its 32 x 32 level too, and the 256x256
/// frame takes the same time either way (1.01x host to host; `docs/perf/lavapipe-2026-12-05-s45.log`).
pub const CPU_WINOGRAD4_MIN_PIXELS: u32 = 64 * 64;

/// How a conv tile is computed: the entry point of conv3x3.wgsl.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Method {
    /// `main`: the direct sum, each invocation fetching its inputs from the textures.
    #[default]
    Direct,
    /// `winograd`: Winograd F(2x2, 3x3), 16 multiplies per 2x2 outputs and channel pair for 36.
    Winograd,
    /// `lanes`: the direct sum with each weight vec4 loaded by one lane of the subgroup and
    /// broadcast to the others (one or two columns, the two-column step in conv3x3_rows.wgsl;
    /// subgroups of at least 8 lanes, [`lanes_supported`]). On lavapipe a weight load is
    /// otherwise a lane-by-lane gather.
    Lanes,
    /// `winograd_lanes` (conv3x3_wino.wgsl): [`Method::Winograd`] with each weight vec4 loaded
    /// by one lane of the subgroup, from the plan's weight texture, and broadcast to the others
    /// (subgroups of at least 8 lanes, [`winograd_lanes_supported`]), for CPU drivers.
    WinogradLanes,
    /// `winograd4_lanes` (conv3x3_wino4.wgsl): Winograd F(4x4, 3x3), 36 multiplies per 4x4
    /// outputs and channel pair for 144, with its weights loaded across the subgroup as
    /// [`Method::WinogradLanes`] loads them (subgroups of at least 8 lanes), for CPU drivers.
    Winograd4Lanes,
    /// conv3x3_mma.wgsl: an implicit matrix product in 16 x 16 x 16 tiles of f16 products
    /// summed in f32, in the device's matrix units (tensor cores, [`matrix_units_supported`])
    /// or emulated where it has none ([`Tile::mma`]).
    Mma,
    /// conv3x3_mma.wgsl's split entry points: [`Method::Mma`] with each operand carried as two
    /// f16 halves and three products per pair, f32-class results ([`Tile::mma_split`]).
    MmaSplit,
}

impl Method {
    /// Weights per input-output channel pair: 9 taps, or 16 transformed ones for Winograd
    /// F(2x2, 3x3) and 36 for F(4x4, 3x3).
    pub fn taps(self) -> u32 {
        match self {
            Method::Direct | Method::Lanes | Method::Mma | Method::MmaSplit => 9,
            Method::Winograd | Method::WinogradLanes => 16,
            Method::Winograd4Lanes => 36,
        }
    }

    /// The entry point in conv3x3.wgsl (conv3x3_mma.wgsl's `mma` and `mma_split` for the Mma
    /// methods, or `mma_emulated` and `mma_split_emulated` on devices without matrix units).
    pub fn entry_point(self) -> &'static str {
        match self {
            Method::Direct => "main",
            Method::Winograd => "winograd",
            Method::Lanes => "lanes",
            Method::WinogradLanes => "winograd_lanes",
            Method::Winograd4Lanes => "winograd4_lanes",
            Method::Mma => "mma",
            Method::MmaSplit => "mma_split",
        }
    }

    /// Whether this is Winograd ([`Method::Winograd`], [`Method::WinogradLanes`],
    /// [`Method::Winograd4Lanes`]): transformed weights per channel pair ([`Method::taps`]),
    /// tiles of a fixed width (2 or 4 columns), no split.
    pub fn is_winograd(self) -> bool {
        matches!(self, Method::Winograd | Method::WinogradLanes | Method::Winograd4Lanes)
    }

    /// Whether this is Winograd with its weights across the subgroup ([`Method::WinogradLanes`],
    /// [`Method::Winograd4Lanes`]): subgroups of at least 8 lanes, weights from the plan's
    /// weight texture (binding 7, whatever the weight memory), the output pooled in the conv
    /// where the plan asks.
    pub fn is_winograd_lanes(self) -> bool {
        matches!(self, Method::WinogradLanes | Method::Winograd4Lanes)
    }

    /// Whether this is one of conv3x3_mma.wgsl's methods ([`Method::Mma`] and the split ones).
    pub fn is_mma(self) -> bool {
        matches!(self, Method::Mma | Method::MmaSplit)
    }

    /// Whether this is conv3x3_mma.wgsl's split method ([`Method::MmaSplit`]).
    pub fn is_mma_split(self) -> bool {
        self == Method::MmaSplit
    }
}

/// The most rows of a two-column lanes tile: conv3x3_rows.wgsl has no more (16 rows in two
/// columns ran 1.36-1.41x the time of 8 on lavapipe, and every row it has costs build time).
pub const LANES_W2_MAX_ROWS: u32 = 8;

/// The conv kernel's register tile: at most `rows` output rows x `blocks` output blocks (4
/// channels each) x `cols` adjacent columns per invocation, computed directly or by Winograd's
/// F(2x2, 3x3). Levels lower than `rows` and convs with fewer output blocks (or too many input
/// blocks for `blocks` in one weight chunk) get a smaller tile.
///
/// Taller tiles share each weight load among more outputs; wider ones share each input fetch
/// (a 2-column tile fetches 4 input columns for 2 outputs, a 1-column tile 3 for 1). A Winograd
/// tile (2 columns, 2 or 4 rows) multiplies 16 times per 2x2 outputs and input channel where the
/// direct one multiplies 36 times, for 16 weights per channel pair instead of 9 and a few
/// additions. CPU drivers run the Winograd lanes tiles and, where those do not run,
/// [`Tile::cpu`] (8 x 2, weights loaded across the subgroup; [`Tile::cpu_for`]); GPUs tune per
/// conv ([`crate::TileChoice`]) and fall back to the default (16 x 2) where they cannot time
/// candidates; `rae-cli bench --tile` sweeps any of them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Tile {
    /// Output rows per invocation: 1, 2, 4, 8 or 16 ([`CONV_ROWS`]).
    pub rows: u32,
    /// Output blocks per invocation: 1, 2, or 4 with one column.
    pub blocks: u32,
    /// Output columns per invocation: 1 or 2.
    pub cols: u32,
    /// Workgroup width in invocations (8, 16, 32 or 64; the height makes 64 invocations).
    pub group_x: u32,
    /// How the tile is computed ([`Tile::winograd`]).
    pub method: Method,
    /// Parts the input blocks are split into (split-K, direct tiles only; 1: none): each part
    /// sums its share into a partial buffer and a second pass adds them ([`Tile::with_split`]).
    pub split: u32,
}

impl Default for Tile {
    fn default() -> Self {
        Tile { rows: CONV_ROWS, blocks: 2, cols: 1, group_x: WORKGROUP, method: Method::Direct, split: 1 }
    }
}

impl Tile {
    /// The tile of CPU drivers without subgroups: 16 rows x 4 blocks (2 or 1 where a conv's
    /// weights or outputs are fewer), 0.83-0.93x the time of 16 x 2 on lavapipe
    /// (`docs/perf/lavapipe-2026-11-23-s6.log`); [`Tile::cpu`] picks [`Tile::CPU_LANES`] instead
    /// where the device has subgroups.
    pub const CPU: Tile = Tile { rows: CONV_ROWS, blocks: 4, cols: 1, group_x: WORKGROUP, method: Method::Direct, split: 1 };

    /// The tile of CPU drivers with subgroups: 8 rows x 2 blocks in one column, weights loaded
    /// across the subgroup. In the CPU plan ([`Tile::cpu_for`]) it runs only the convs the
    /// Winograd tiles do not: few input blocks on levels under 64 x 64, and (in 4 rows) levels
    /// of at most 8 x 8, where one column keeps twice the lanes busy that two columns do and
    /// runs faster (the 256x256 frame's bottleneck convs 1.05-1.15x the GFLOP/s of
    /// `lanes4x2w2`, the 64x64 frame's 8 x 8 to 2 x 2 levels 1.1-1.6x). Its pipelines compile
    /// into an empty shader cache in an eighth of the two-column tile's time (0.44 s against
    /// 3.6 s on Zen 4: `cargo run --release -p rae-core --example compile_cost -- lanes8x2
    /// lanes8x2w2`), which is what the cold first frames of small frames and the test suite
    /// wait on. Run on every conv, `lanes8x2w2` takes 0.76x its frame time at 256x256
    /// (`docs/perf/lavapipe-2026-12-06-s50.log`).
    pub const CPU_LANES: Tile = Tile { rows: 8, blocks: 2, cols: 1, group_x: WORKGROUP, method: Method::Lanes, split: 1 };

    /// The CPU drivers' Winograd tile: F(2x2, 3x3) in two stacked 2x2 output tiles (4 rows x
    /// 2 columns) x 4 blocks, weights loaded across the subgroup ([`Method::WinogradLanes`]).
    /// It takes 256 multiply-adds per 4 outputs and input block where [`Tile::CPU_LANES`] takes
    /// 576: on lavapipe the 256x256 frame's convs of 32 input channels and more take about 0.8x
    /// the time of `lanes8x2w2` (`docs/perf/lavapipe-2026-11-25-s22.log`); with 8 lanes its
    /// bottleneck convs take half the time of `lanes4x2w2`'s (`lavapipe-2026-12-02-s31.log`).
    /// Its weights are texels of the plan's weight texture (a 64 KiB uniform chunk would hold
    /// four blocks of 16 weights per channel pair only up to 15 input blocks). The rounding is
    /// Winograd's: within the golden tolerance.
    pub const CPU_WINOGRAD: Tile = Tile { rows: 4, blocks: 4, cols: 2, group_x: WORKGROUP, method: Method::WinogradLanes, split: 1 };

    /// The CPU drivers' F(4x4, 3x3) tile: one 4x4 output tile (4 rows x 4 columns) x 4 blocks,
    /// weights loaded across the subgroup from the plan's weight texture
    /// ([`Method::Winograd4Lanes`]). It takes 144 multiply-adds per 16 outputs and input block
    /// where [`Tile::CPU_WINOGRAD`] takes 256: on lavapipe the 256x256 frame's convs on levels of
    /// 32 x 32 and more take 0.6-0.9x the time of the F(2x2) tile's and `lanes8x2w2`'s; on 16 x
    /// 16 levels, where a subgroup covers half its pixels, 1.3-1.7x
    /// (`docs/perf/lavapipe-2026-11-25-s23.log`). One 4x4 tile a lane is as fast as two stacked
    /// (0.91-1.02x the frame from 128x128 to 1280x720) and compiles in half the time, 5.7 s a
    /// pipeline into an empty shader cache with 16 lanes (`lavapipe-2026-12-03-s32.log`,
    /// `cargo run --release -p rae-core --example compile_cost`). Its rounding is within the
    /// golden tolerance.
    pub const CPU_WINOGRAD4: Tile = Tile { rows: 4, blocks: 4, cols: 4, group_x: WORKGROUP, method: Method::Winograd4Lanes, split: 1 };

    /// The tile of a browser's software WebGPU adapter (Chromium's SwiftShader): 4 rows x 1
    /// block. SwiftShader compiles the unrolled conv bodies slowly: on this project's 2-core
    /// machine the shipped models' frame builds in seconds with 4 x 1, did not build in 200 s
    /// with 8 x 1, and with [`Tile::CPU`] its GPU process exits after two minutes. Of the tiles
    /// that build it runs fastest: the sample's 128x128 frame in 0.65x the time of 4 x 2 and
    /// 0.6x that of 2 x 1 (`docs/perf/chromium-swiftshader-2026-12-03-s38.log`).
    pub const BROWSER_CPU: Tile = Tile { rows: 4, blocks: 1, cols: 1, group_x: WORKGROUP, method: Method::Direct, split: 1 };

    /// The tile of CPU drivers on `device`: [`Tile::CPU_LANES`] where the device has subgroups
    /// of 8 or more lanes ([`lanes_supported`]), [`Tile::BROWSER_CPU`] on a browser's WebGPU,
    /// else [`Tile::CPU`].
    pub fn cpu(device: &wgpu::Device) -> Tile {
        if lanes_supported(device) {
            Tile::CPU_LANES
        } else if device.adapter_info().backend == wgpu::Backend::BrowserWebGpu {
            Tile::BROWSER_CPU
        } else {
            Tile::CPU
        }
    }

    /// The tile of CPU drivers for a conv reading `in_blocks` input blocks on a `width` x
    /// `height` level: [`Tile::cpu`]; where that is [`Tile::CPU_LANES`] and the device runs the
    /// Winograd lanes tiles ([`winograd_lanes_supported`]), [`Tile::CPU_WINOGRAD4`] on levels of
    /// at least [`CPU_WINOGRAD4_MIN_PIXELS`] and [`Tile::CPU_WINOGRAD`] below them for convs of
    /// at least [`CPU_WINOGRAD_MIN_BLOCKS`]: down to 1 x 1 where subgroups have 8 lanes
    /// ([`narrow_gathers`]), above [`CPU_SHORT_TILE_MAX_PIXELS`] where they have 16. The rest
    /// take [`Tile::CPU_LANES`], in 4 rows instead of 8 on levels of at most
    /// [`CPU_SHORT_TILE_MAX_PIXELS`].
    ///
    /// An 8 x 8 level is 8 invocations of 8 rows per output group, so half a subgroup's 16
    /// lanes have pixels, and the others still load weights for them; at 4 rows every lane
    /// works (in two columns, `lanes4x2w2`, half of them again: the one-column tile runs the
    /// 256x256 frame's bottleneck convs at 1.05-1.15x its GFLOP/s,
    /// `docs/perf/lavapipe-2026-12-06-s50.log`). With 16 lanes `lanes4x2w2` runs those convs
    /// 4-18% faster than [`Tile::CPU_WINOGRAD`] (`lavapipe-2026-12-03-s32.log`); with 8 lanes
    /// the Winograd tile takes half its time (`lavapipe-2026-12-02-s31.log`).
    pub fn cpu_for(device: &wgpu::Device, width: u32, height: u32, in_blocks: u32) -> Tile {
        let tile = Tile::cpu(device);
        let (winograd, narrow) = (winograd_lanes_supported(device), narrow_gathers(device));
        let pixels = width * height;
        if tile != Tile::CPU_LANES {
            tile
        } else if winograd && pixels >= CPU_WINOGRAD4_MIN_PIXELS {
            Tile::CPU_WINOGRAD4
        } else if winograd && in_blocks >= CPU_WINOGRAD_MIN_BLOCKS && (narrow || pixels > CPU_SHORT_TILE_MAX_PIXELS) {
            Tile::CPU_WINOGRAD
        } else if pixels <= CPU_SHORT_TILE_MAX_PIXELS {
            Tile { rows: 4, ..tile }
        } else {
            tile
        }
    }

    /// A one-column tile, if the kernel has one of this shape.
    pub fn new(rows: u32, blocks: u32) -> Option<Self> {
        Self::with_cols(rows, blocks, 1)
    }

    /// A tile, if the kernel has one of this shape.
    pub fn with_cols(rows: u32, blocks: u32, cols: u32) -> Option<Self> {
        // Four blocks take the accumulators a second column would use.
        ([1, 2, 4, 8, 16].contains(&rows) && ((1..=2).contains(&blocks) || (blocks == 4 && cols == 1)) && (1..=2).contains(&cols))
            .then_some(Tile { rows, blocks, cols, group_x: WORKGROUP, method: Method::Direct, split: 1 })
    }

    /// A Winograd F(2x2, 3x3) tile of `rows` (2: one 2x2 output tile, 4: two stacked) x
    /// `blocks` (1 or 2), if the kernel has it.
    pub fn winograd(rows: u32, blocks: u32) -> Option<Self> {
        ([2, 4].contains(&rows) && (1..=2).contains(&blocks)).then_some(Tile {
            rows,
            blocks,
            cols: 2,
            group_x: WORKGROUP,
            method: Method::Winograd,
            split: 1,
        })
    }

    /// A Winograd F(2x2, 3x3) tile with its weights loaded across the subgroup
    /// ([`Method::WinogradLanes`]): `rows` (4: two stacked 2x2 output tiles) x `blocks` (1, 2
    /// or 4), if the kernel has it.
    pub fn winograd_lanes(rows: u32, blocks: u32) -> Option<Self> {
        (rows == 4 && [1, 2, 4].contains(&blocks)).then_some(Tile {
            rows,
            blocks,
            cols: 2,
            group_x: WORKGROUP,
            method: Method::WinogradLanes,
            split: 1,
        })
    }

    /// A Winograd F(4x4, 3x3) tile with its weights loaded across the subgroup
    /// ([`Method::Winograd4Lanes`]): `rows` (4: one 4x4 output tile) x 4 columns x `blocks` (1, 2
    /// or 4), if the kernel has it.
    pub fn winograd4_lanes(rows: u32, blocks: u32) -> Option<Self> {
        (rows == 4 && [1, 2, 4].contains(&blocks)).then_some(Tile {
            rows,
            blocks,
            cols: 4,
            group_x: WORKGROUP,
            method: Method::Winograd4Lanes,
            split: 1,
        })
    }

    /// This direct tile with its weights loaded across the subgroup ([`Method::Lanes`]), if it
    /// is direct.
    pub fn with_lanes(self) -> Option<Self> {
        Tile::lanes(self.rows, self.blocks, self.cols).filter(|_| self.method == Method::Direct).map(|t| Tile {
            group_x: self.group_x,
            split: self.split,
            ..t
        })
    }

    /// A tile with its weights loaded across the subgroup ([`Method::Lanes`]): `rows` x `blocks`
    /// x `cols`, where lanes tiles also take 4 blocks in 2 columns (and two columns at most
    /// [`LANES_W2_MAX_ROWS`] rows), if the kernel has it.
    pub fn lanes(rows: u32, blocks: u32, cols: u32) -> Option<Self> {
        let rows_ok = [1, 2, 4, 8, 16].contains(&rows) && (cols == 1 || rows <= LANES_W2_MAX_ROWS);
        (rows_ok && [1, 2, 4].contains(&blocks) && (1..=2).contains(&cols)).then_some(Tile {
            rows,
            blocks,
            cols,
            group_x: WORKGROUP,
            method: Method::Lanes,
            split: 1,
        })
    }

    /// A matrix-unit tile ([`Method::Mma`]): workgroups of 4 rows x 64 pixels x `channels`
    /// output channels (16, 32, 48 or 64), if the kernel has it. Inputs and weights are rounded
    /// to f16 for the products (inputs clamped to +-65504), which are summed in f32: with f16
    /// activations that adds the weights' rounding to the storage's; with f32 activations it is
    /// a TF32-like mode (10-bit mantissas in), not f32 arithmetic. Needs storage weights
    /// ([`WeightMemory::Storage`]) and SHADER_F16; runs in matrix units where the device has
    /// them ([`matrix_units_supported`]), else emulated (correct, slow: for tests).
    pub fn mma(channels: u32) -> Option<Self> {
        [16, 32, 48, 64].contains(&channels).then_some(Tile {
            rows: 4,
            blocks: channels / 4,
            cols: 1,
            group_x: WORKGROUP,
            method: Method::Mma,
            split: 1,
        })
    }

    /// A split matrix-unit tile ([`Method::MmaSplit`]): workgroups of 4 rows x 32 pixels
    /// ([`MMA_SPLIT_PIXELS`]) x `channels` output channels (16, 32, 48 or 64), if the kernel has
    /// it. Each operand x goes in as hi and its remainder scaled by 2^11, lo = f16(2^11 (x -
    /// hi)) (hi = f16(x) for the weights, x cut to f16's 10 mantissa bits for the activations),
    /// and a product as hi(a) hi(b) + (hi(a) lo(b) + lo(a) hi(b)) / 2^11: 21- to 22-bit
    /// operands, so f32 activations get f32-class results (held to the golden tolerance) for
    /// three times the matrix products, and f16 activations (exact in f16) two. Inputs are
    /// clamped to +-65504 as for [`Tile::mma`] (the default model's activations stay under 26,
    /// docs/STABILITY.md). Needs what [`Tile::mma`] needs.
    pub fn mma_split(channels: u32) -> Option<Self> {
        Some(Tile { method: Method::MmaSplit, ..Tile::mma(channels)? })
    }

    /// Weights per input-output channel pair ([`Method::taps`]).
    pub fn taps(&self) -> u32 {
        self.method.taps()
    }

    /// This tile in workgroups `group_x` invocations wide (8, 16, 32 or 64), if the kernel has it.
    pub fn with_group(self, group_x: u32) -> Option<Self> {
        [8, 16, 32, 64].contains(&group_x).then_some(Tile { group_x, ..self })
    }

    /// This direct tile with its input blocks split `split` ways (1 to 16; 1: no split), if it
    /// is direct.
    pub fn with_split(self, split: u32) -> Option<Self> {
        (!self.method.is_winograd() && (1..=16).contains(&split)).then_some(Tile { split, ..self })
    }

    /// Workgroup height in invocations.
    pub fn group_y(&self) -> u32 {
        64 / self.group_x
    }
}

impl std::fmt::Display for Tile {
    /// `ROWSxBLOCKS`, with `wCOLS` appended for a 2-column tile (`8x1w2`) and `gGROUPX` for a
    /// workgroup other than 8 x 8 and `kSPLIT` for a split tile (`8x1g32k4`); Winograd tiles are
    /// `wino` and `ROWSxBLOCKS` (`wino4x1g32`); Mma tiles are `mma` and their output channels
    /// (`mma32`), with `x3` for the split ones' three products (`mma32x3`).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.method {
            Method::Mma => return write!(f, "mma{}", 4 * self.blocks),
            Method::MmaSplit => return write!(f, "mma{}x3", 4 * self.blocks),
            Method::Direct => {}
            Method::Winograd => write!(f, "wino")?,
            Method::Lanes => write!(f, "lanes")?,
            Method::WinogradLanes => write!(f, "winolanes")?,
            Method::Winograd4Lanes => write!(f, "wino4lanes")?,
        }
        write!(f, "{}x{}", self.rows, self.blocks)?;
        if self.cols > 1 && !self.method.is_winograd() {
            write!(f, "w{}", self.cols)?;
        }
        if self.group_x != WORKGROUP {
            write!(f, "g{}", self.group_x)?;
        }
        if self.split > 1 {
            write!(f, "k{}", self.split)?;
        }
        Ok(())
    }
}

/// Output rows per invocation for a conv `height` pixels high with at most `max_rows`
/// (a power of two up to [`CONV_ROWS`]): the smallest of 2, 4, 8 that covers a lower level
/// whole, so levels a few pixels high (the deepest ones of small frames) do not compute 16 rows
/// to keep 2, else `max_rows`.
pub fn rows_per_invocation(height: u32, max_rows: u32) -> u32 {
    [2, 4, 8].into_iter().find(|&r| height <= r).unwrap_or(CONV_ROWS).min(max_rows)
}

/// Output blocks per invocation for a conv reading `cin4` input blocks with `taps` weights
/// per channel pair (9, or 16 for Winograd): the most of 4, 2, 1 whose weights and biases fit
/// one weight chunk (more outputs per input fetch; direct tiles get 4 up to 28 input blocks);
/// `None` when not even one block fits (direct: more than 113 input blocks, 452 channels;
/// Winograd: more than 63, 252 channels).
pub fn blocks_per_invocation(cin4: u32, taps: u32) -> Option<u32> {
    [4, 2, 1].into_iter().find(|&ob| (cin4 * taps * 4 + 1) * ob <= WEIGHT_CHUNK)
}

/// The grammar of a fixed tile, for errors ([`Tile`]'s `FromStr`).
const TILE_GRAMMAR: &str =
    "[wino|lanes|winolanes|wino4lanes]ROWSxBLOCKS[wCOLS][gGROUPX][kSPLIT], or mmaC / mmaCx3 (C output channels: 16, 32, 48, 64)";

impl std::str::FromStr for Tile {
    type Err = crate::Error;

    /// The tile `Display` writes: `16x2`, `8x1w2`, `8x1g32k4`, `lanes8x2w2`, `wino2x1g32`,
    /// `winolanes4x4`, `wino4lanes4x4`, `mma32`, `mma32x3`. Refused where the kernel has no
    /// such tile, with the reason.
    fn from_str(s: &str) -> Result<Tile, crate::Error> {
        let bad = |reason: &str| crate::Error::TileText { text: s.to_string(), reason: reason.to_string() };
        let number = |t: &str| t.parse::<u32>().map_err(|_| bad(&format!("`{t}` is not a number; a tile is {TILE_GRAMMAR}")));
        if let Some(channels) = s.strip_prefix("mma") {
            let (channels, split) = channels.strip_suffix("x3").map_or((channels, false), |c| (c, true));
            let tile = if split { Tile::mma_split(number(channels)?) } else { Tile::mma(number(channels)?) };
            return tile.ok_or_else(|| bad("matrix-unit tiles have 16, 32, 48 or 64 output channels"));
        }
        let (method, rest) = [
            ("wino4lanes", Method::Winograd4Lanes),
            ("winolanes", Method::WinogradLanes),
            ("wino", Method::Winograd),
            ("lanes", Method::Lanes),
        ]
        .iter()
        .find_map(|(p, m)| s.strip_prefix(p).map(|r| (*m, r)))
        .unwrap_or((Method::Direct, s));
        let (rest, split) = rest.split_once('k').map_or(Ok((rest, 1)), |(a, k)| number(k).map(|k| (a, k)))?;
        let (rest, group) = rest.split_once('g').map_or(Ok((rest, WORKGROUP)), |(a, g)| number(g).map(|g| (a, g)))?;
        let (shape, cols) = rest.split_once('w').map_or(Ok((rest, None)), |(a, c)| number(c).map(|c| (a, Some(c))))?;
        let (rows, blocks) = shape.split_once('x').ok_or_else(|| bad(&format!("no ROWSxBLOCKS; a tile is {TILE_GRAMMAR}")))?;
        let (rows, blocks) = (number(rows)?, number(blocks)?);
        let winograd = method.is_winograd();
        if winograd && (cols.is_some() || split != 1) {
            return Err(bad("Winograd tiles have a fixed width and no split"));
        }
        let tile = match method {
            Method::Direct => Tile::with_cols(rows, blocks, cols.unwrap_or(1)),
            Method::Lanes => Tile::lanes(rows, blocks, cols.unwrap_or(1)),
            Method::Winograd => Tile::winograd(rows, blocks),
            Method::WinogradLanes => Tile::winograd_lanes(rows, blocks),
            Method::Winograd4Lanes => Tile::winograd4_lanes(rows, blocks),
            Method::Mma | Method::MmaSplit => unreachable!("parsed above"),
        };
        let reason = match method {
            Method::Direct | Method::Lanes => {
                "the kernel has 1, 2, 4, 8 or 16 rows, 1, 2 or 4 blocks (4 with one column, except lanes tiles), 1 or 2 columns (lanes tiles with 2 at most 8 rows)"
            }
            Method::Winograd => "Winograd tiles have 2 or 4 rows and 1 or 2 blocks",
            _ => "Winograd lanes tiles have 4 rows and 1, 2 or 4 blocks",
        };
        let tile = tile.ok_or_else(|| bad(reason))?;
        let tile = tile.with_group(group).ok_or_else(|| bad("workgroups are 8, 16, 32 or 64 wide"))?;
        if split == 1 { Ok(tile) } else { tile.with_split(split).ok_or_else(|| bad("splits are 1 to 16, of direct tiles only")) }
    }
}

/// The most tiles a [`TileList`] holds.
pub const TILE_LIST_MAX: usize = 16;

/// A short list of tiles held by value (so that [`crate::TileChoice`] and
/// [`crate::Options`] stay `Copy`): the candidates of [`crate::TileChoice::TunedAmong`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TileList {
    tiles: [Tile; TILE_LIST_MAX],
    len: usize,
}

impl TileList {
    /// The list of `tiles`; panics past [`TILE_LIST_MAX`] (a parsed list is checked instead).
    pub fn new(tiles: &[Tile]) -> Self {
        assert!(tiles.len() <= TILE_LIST_MAX, "at most {TILE_LIST_MAX} tiles in a list");
        let mut list = TileList { tiles: [Tile::default(); TILE_LIST_MAX], len: tiles.len() };
        list.tiles[..tiles.len()].copy_from_slice(tiles);
        list
    }

    /// The tiles, in order.
    pub fn as_slice(&self) -> &[Tile] {
        &self.tiles[..self.len]
    }
}

impl std::fmt::Display for TileList {
    /// The tiles joined by `+` (`lanes8x2w2+wino4lanes4x4`).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for (i, t) in self.as_slice().iter().enumerate() {
            write!(f, "{}{t}", if i > 0 { "+" } else { "" })?;
        }
        Ok(())
    }
}

impl std::str::FromStr for TileList {
    type Err = crate::Error;

    /// Tiles joined by `+`, each as [`Tile`] parses it; 1 to [`TILE_LIST_MAX`] of them.
    fn from_str(s: &str) -> Result<TileList, crate::Error> {
        let tiles = s.split('+').map(str::parse).collect::<Result<Vec<Tile>, _>>()?;
        if tiles.len() > TILE_LIST_MAX {
            return Err(crate::Error::TileText { text: s.to_string(), reason: format!("at most {TILE_LIST_MAX} tiles in a list") });
        }
        Ok(TileList::new(&tiles))
    }
}

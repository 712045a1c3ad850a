//! Choosing each conv's tile: [`TileChoice`], the candidate tables per device class, and the
//! two-round timing on the device that picks among them ([`tune`]).

use super::*;

/// How a [`Denoiser`] picks the conv kernel's register tile.
// A TileList is held by value so that Options stays Copy; a choice is made once per Denoiser.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum TileChoice {
    /// [`TileChoice::TunedMma`] on GPUs that have timestamps inside passes (that is
    /// [`TileChoice::Tuned`] where the device has no matrix units), [`Tile::cpu_for`] each
    /// conv's level on CPU drivers (lavapipe compiles each variant for seconds, and its tiles
    /// are known: Winograd F(4x4) and F(2x2) in 4 rows with weights across the subgroup, direct
    /// 8 x 2 in two columns for the convs of fewer than 32 channels below 32 x 32, 4 rows on
    /// the smallest levels), the default tile elsewhere.
    #[default]
    Auto,
    /// One tile for every conv (smaller where a level or a conv is smaller).
    Fixed(Tile),
    /// Time every conv with each of [`TUNE_TILES`] on this device while building
    /// ([`TUNE_TILES_CPU`] on CPU drivers with subgroups), and keep the fastest per conv: big
    /// levels want tall tiles (fewer weight loads), deep levels want small ones (enough
    /// invocations to fill the GPU).
    Tuned,
    /// [`TileChoice::Tuned`] among these candidates only (fewer pipelines to compile).
    TunedAmong(TileList),
    /// [`TileChoice::Tuned`] with matrix-unit tiles among the candidates where the device has
    /// matrix units ([`crate::kernels::matrix_units_supported`]) and the weights are in a
    /// storage buffer, those that keep the precision's accuracy: with f32 activations the split
    /// tiles [`MMA_SPLIT_TILES`] (f32-class results, [`Tile::mma_split`]), with f16 ones
    /// [`MMA_TILES`] (f16 products summed in f32, [`Tile::mma`]). What [`TileChoice::Auto`]
    /// does on GPUs: on the H100 the split tiles pass the goldens, and f32 frames take 0.89x the
    /// time of [`TileChoice::Tuned`]'s (`docs/perf/h100-2026-11-24-s15.log`). The TF32-like plain tiles
    /// with f32 activations are fixed tiles only (`Fixed(Tile::mma(32))`).
    TunedMma,
}

impl std::fmt::Display for TileChoice {
    /// `auto`, `tuned`, `tuned-mma`, `tuned:T+T+...` (a [`TileList`]) or the fixed tile's name.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            TileChoice::Auto => write!(f, "auto"),
            TileChoice::Tuned => write!(f, "tuned"),
            TileChoice::TunedMma => write!(f, "tuned-mma"),
            TileChoice::TunedAmong(list) => write!(f, "tuned:{list}"),
            TileChoice::Fixed(tile) => write!(f, "{tile}"),
        }
    }
}

impl std::str::FromStr for TileChoice {
    type Err = Error;

    /// What `Display` writes: `auto`, `tuned`, `tuned-mma`, `tuned:T+T+...` or a fixed tile.
    fn from_str(s: &str) -> Result<TileChoice> {
        Ok(match s {
            "auto" => TileChoice::Auto,
            "tuned" => TileChoice::Tuned,
            "tuned-mma" => TileChoice::TunedMma,
            _ => match s.strip_prefix("tuned:") {
                Some(list) => TileChoice::TunedAmong(list.parse().map_err(|e| match e {
                    Error::TileText { text, reason } => Error::TileText { text: s.to_string(), reason: format!("`{text}`: {reason}") },
                    e => e,
                })?),
                None => TileChoice::Fixed(s.parse().map_err(|e| match e {
                    Error::TileText { text, reason } => {
                        Error::TileText { text, reason: format!("{reason} (or auto, tuned, tuned-mma, tuned:T+T+...)") }
                    }
                    e => e,
                })?),
            },
        })
    }
}

/// The matrix-unit tiles [`TileChoice::TunedMma`] adds to [`TUNE_TILES`] with f16 activations:
/// 16 to 64 output channels per workgroup.
pub const MMA_TILES: [Tile; 4] = [
    Tile { rows: 4, blocks: 4, cols: 1, group_x: 8, method: Method::Mma, split: 1 },
    Tile { rows: 4, blocks: 8, cols: 1, group_x: 8, method: Method::Mma, split: 1 },
    Tile { rows: 4, blocks: 12, cols: 1, group_x: 8, method: Method::Mma, split: 1 },
    Tile { rows: 4, blocks: 16, cols: 1, group_x: 8, method: Method::Mma, split: 1 },
];

/// The split matrix-unit tiles [`TileChoice::TunedMma`] adds to [`TUNE_TILES`] with f32
/// activations: 16 to 64 output channels per workgroup ([`Tile::mma_split`]).
pub const MMA_SPLIT_TILES: [Tile; 4] = [
    Tile { rows: 4, blocks: 4, cols: 1, group_x: 8, method: Method::MmaSplit, split: 1 },
    Tile { rows: 4, blocks: 8, cols: 1, group_x: 8, method: Method::MmaSplit, split: 1 },
    Tile { rows: 4, blocks: 12, cols: 1, group_x: 8, method: Method::MmaSplit, split: 1 },
    Tile { rows: 4, blocks: 16, cols: 1, group_x: 8, method: Method::MmaSplit, split: 1 },
];

/// The tiles [`TileChoice::Tuned`] times on CPU drivers with subgroups: the lanes tile in 8
/// and 4 rows and the Winograd lanes tiles ([`Tile::CPU_LANES`], [`Tile::CPU_WINOGRAD`],
/// [`Tile::CPU_WINOGRAD4`]): what [`TileChoice::Tuned`] times on CPU drivers with subgroups
/// of 8 lanes or more ([`crate::kernels::winograd_lanes_supported`]); every tile
/// [`Tile::cpu_for`] gives there is among them.
pub const TUNE_TILES_CPU: [Tile; 4] = [Tile::CPU_LANES, Tile { rows: 4, ..Tile::CPU_LANES }, Tile::CPU_WINOGRAD, Tile::CPU_WINOGRAD4];

/// The tiles [`TileChoice::Tuned`] times on GPUs (and CPU drivers without subgroups).
pub const TUNE_TILES: [Tile; 33] = [
    Tile { rows: 16, blocks: 2, cols: 1, group_x: 8, method: Method::Direct, split: 1 },
    Tile { rows: 8, blocks: 2, cols: 1, group_x: 8, method: Method::Direct, split: 1 },
    Tile { rows: 4, blocks: 2, cols: 1, group_x: 8, method: Method::Direct, split: 1 },
    Tile { rows: 2, blocks: 2, cols: 1, group_x: 8, method: Method::Direct, split: 1 },
    Tile { rows: 1, blocks: 2, cols: 1, group_x: 8, method: Method::Direct, split: 1 },
    Tile { rows: 8, blocks: 1, cols: 1, group_x: 8, method: Method::Direct, split: 1 },
    Tile { rows: 4, blocks: 1, cols: 1, group_x: 8, method: Method::Direct, split: 1 },
    Tile { rows: 1, blocks: 1, cols: 1, group_x: 8, method: Method::Direct, split: 1 },
    Tile { rows: 16, blocks: 1, cols: 2, group_x: 8, method: Method::Direct, split: 1 },
    Tile { rows: 8, blocks: 2, cols: 2, group_x: 8, method: Method::Direct, split: 1 },
    Tile { rows: 8, blocks: 1, cols: 2, group_x: 8, method: Method::Direct, split: 1 },
    Tile { rows: 4, blocks: 2, cols: 2, group_x: 8, method: Method::Direct, split: 1 },
    Tile { rows: 4, blocks: 1, cols: 2, group_x: 8, method: Method::Direct, split: 1 },
    Tile { rows: 16, blocks: 2, cols: 1, group_x: 32, method: Method::Direct, split: 1 },
    Tile { rows: 8, blocks: 1, cols: 1, group_x: 32, method: Method::Direct, split: 1 },
    Tile { rows: 8, blocks: 1, cols: 2, group_x: 16, method: Method::Direct, split: 1 },
    Tile { rows: 4, blocks: 2, cols: 2, group_x: 16, method: Method::Direct, split: 1 },
    Tile { rows: 4, blocks: 1, cols: 1, group_x: 16, method: Method::Direct, split: 1 },
    Tile { rows: 8, blocks: 1, cols: 1, group_x: 16, method: Method::Direct, split: 1 },
    Tile { rows: 8, blocks: 1, cols: 2, group_x: 32, method: Method::Direct, split: 1 },
    Tile { rows: 8, blocks: 1, cols: 1, group_x: 64, method: Method::Direct, split: 1 },
    Tile { rows: 16, blocks: 2, cols: 1, group_x: 64, method: Method::Direct, split: 1 },
    Tile { rows: 4, blocks: 4, cols: 1, group_x: 32, method: Method::Direct, split: 1 },
    Tile { rows: 8, blocks: 4, cols: 1, group_x: 32, method: Method::Direct, split: 1 },
    Tile { rows: 2, blocks: 1, cols: 2, group_x: 8, method: Method::Winograd, split: 1 },
    Tile { rows: 2, blocks: 1, cols: 2, group_x: 32, method: Method::Winograd, split: 1 },
    Tile { rows: 2, blocks: 2, cols: 2, group_x: 32, method: Method::Winograd, split: 1 },
    Tile { rows: 4, blocks: 1, cols: 2, group_x: 32, method: Method::Winograd, split: 1 },
    Tile { rows: 4, blocks: 1, cols: 1, group_x: 8, method: Method::Direct, split: 4 },
    Tile { rows: 4, blocks: 1, cols: 1, group_x: 8, method: Method::Direct, split: 8 },
    Tile { rows: 2, blocks: 1, cols: 1, group_x: 8, method: Method::Direct, split: 8 },
    Tile { rows: 8, blocks: 1, cols: 1, group_x: 32, method: Method::Direct, split: 4 },
    Tile { rows: 4, blocks: 2, cols: 1, group_x: 16, method: Method::Direct, split: 8 },
];

/// A tile and source kind that reached the second round of tuning for a conv, with its time
/// there ([`Denoiser::tuning`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Finalist {
    /// The candidate tile (before a conv's size shrinks it, [`Denoiser::conv_tiles`]).
    pub tile: Tile,
    /// How the conv read its sources.
    pub sources: SourceAccess,
    /// The conv's time with them: the lower of its two medians, in nanoseconds.
    pub ns: f64,
}

/// Timed runs of the convs per timing of a candidate plan ([`tune`]).
const TUNE_ROUNDS: usize = 5;

/// Tiles per conv that the first round of [`tune`] passes to the second.
const TUNE_SHORTLIST: usize = 2;

/// The tiles a [`Denoiser`] times for `choice` on a device with timestamps inside passes
/// (empty where `choice` fixes the tile): `base` (the device class's list), a
/// [`TileChoice::TunedAmong`] list, or for [`TileChoice::Auto`] and [`TileChoice::TunedMma`]
/// `base` and, where `mma` (matrix units, storage weights, room for their workgroup memory), the
/// precision's matrix-unit tiles.
pub(super) fn tuning_candidates(choice: TileChoice, precision: Precision, mma: bool, base: &[Tile]) -> Vec<Tile> {
    let mut candidates = match choice {
        TileChoice::Fixed(_) => return Vec::new(),
        TileChoice::Tuned => return base.to_vec(),
        TileChoice::TunedAmong(list) => return list.as_slice().to_vec(),
        TileChoice::Auto | TileChoice::TunedMma => base.to_vec(),
    };
    if mma {
        candidates.extend(match precision {
            Precision::F32 => MMA_SPLIT_TILES,
            Precision::F16 => MMA_TILES,
        });
    }
    candidates
}

/// The textures one conv is bound to while tuning: its sources, its destination, and the
/// value its output is max-pooled into, if any.
pub(super) struct NodeViews {
    pub(super) a: wgpu::TextureView,
    pub(super) b: wgpu::TextureView,
    pub(super) out: wgpu::TextureView,
    pub(super) pooled: Option<wgpu::TextureView>,
}

/// The fastest tile and source access for each conv on this device, among `candidates` and
/// `accesses`, in two rounds:
/// 1. Every candidate with `accesses[0]`, one plan at a time; each conv's
///    [`TUNE_SHORTLIST`] fastest tiles go on.
/// 2. Every tile some conv shortlisted, with every access, all plans built first and then
///    timed twice, in one order and then the reverse, with nothing compiled between; each conv
///    keeps the tile and access of its lowest time. Timing the finalists side by side, and
///    each in both halves of the run, is what makes the picks steady: in round 1 each
///    candidate is timed right after its own pipelines were compiled, at whatever clock the
///    GPU had come back to, and picks of near-equal tiles varied from build to build (about
///    0.3 ms of a 1080p frame on the H100, `docs/perf/h100-2026-11-24-s15.log`).
///
/// A timing runs the plan's convs once untimed (first dispatches) and then [`TUNE_ROUNDS`]
/// times in one pass, with a timestamp after each conv; a conv's time is the median of its
/// rounds. The activations hold whatever they hold (zeros on a fresh denoiser): the kernel's
/// time does not depend on values (no data-dependent branches). Each conv reads its weights
/// from `memory_of(tile, conv)`, the memory the plan built from the picks gives it.
#[allow(clippy::too_many_arguments)]
pub(super) fn tune(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    kernels: &mut Kernels,
    specs: &[ConvSpec],
    views: &[NodeViews],
    candidates: &[Tile],
    accesses: &[SourceAccess],
    memory_of: &dyn Fn(Tile, &ConvSpec) -> WeightMemory,
) -> Result<Vec<Vec<Finalist>>> {
    let n = specs.len();
    if candidates.len() == 1 && accesses.len() == 1 {
        return Ok(vec![vec![Finalist { tile: candidates[0], sources: accesses[0], ns: f64::NAN }]; n]);
    }
    // Per round: the opening timestamp, its spare, one after each conv.
    let count = ((n + 2) * (TUNE_ROUNDS + 1)) as u32;
    let queries = device.create_query_set(&wgpu::QuerySetDescriptor { label: Some("tile tuning"), ty: wgpu::QueryType::Timestamp, count });
    let build = |kernels: &mut Kernels, tile: Tile, access: SourceAccess| -> Result<(ConvPlan, Vec<wgpu::BindGroup>)> {
        let memories: Vec<WeightMemory> = specs.iter().map(|s| memory_of(tile, s)).collect();
        let plan = ConvPlan::with_choices(device, queue, kernels, specs, &[tile], &[access], &memories)?;
        let groups =
            views.iter().enumerate().map(|(i, v)| plan.bind_group(device, kernels, i, &v.a, &v.b, &v.out, v.pooled.as_ref())).collect();
        Ok((plan, groups))
    };
    // Round 1: each conv's times of every candidate, then its shortlist.
    let mut times: Vec<Vec<f64>> = vec![Vec::with_capacity(candidates.len()); n];
    for &tile in candidates {
        let (plan, groups) = build(kernels, tile, accesses[0])?;
        for (conv, t) in times.iter_mut().zip(time_plan(device, queue, &queries, &plan, &groups)?) {
            conv.push(t);
        }
    }
    let mut finalists: Vec<Tile> = Vec::new();
    for conv in &times {
        let mut order: Vec<usize> = (0..candidates.len()).collect();
        order.sort_by(|&a, &b| conv[a].total_cmp(&conv[b]));
        for &k in order.iter().take(TUNE_SHORTLIST) {
            if !finalists.contains(&candidates[k]) {
                finalists.push(candidates[k]);
            }
        }
    }
    // Round 2: the finalists with every access, side by side, forwards then backwards.
    let entries: Vec<(Tile, SourceAccess)> = accesses.iter().flat_map(|&a| finalists.iter().map(move |&t| (t, a))).collect();
    let plans: Vec<(ConvPlan, Vec<wgpu::BindGroup>)> = entries.iter().map(|&(t, a)| build(kernels, t, a)).collect::<Result<_>>()?;
    let mut finals: Vec<Vec<Finalist>> =
        vec![entries.iter().map(|&(tile, sources)| Finalist { tile, sources, ns: f64::INFINITY }).collect(); n];
    let order: Vec<usize> = (0..plans.len()).chain((0..plans.len()).rev()).collect();
    for k in order {
        let (plan, groups) = &plans[k];
        for (conv, t) in finals.iter_mut().zip(time_plan(device, queue, &queries, plan, groups)?) {
            conv[k].ns = conv[k].ns.min(t);
        }
    }
    for conv in &mut finals {
        conv.sort_by(|a, b| a.ns.total_cmp(&b.ns));
    }
    Ok(finals)
}

/// One timing of a candidate plan for [`tune`]: the median time of each conv over
/// [`TUNE_ROUNDS`] rounds after an untimed one, in nanoseconds.
fn time_plan(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    queries: &wgpu::QuerySet,
    plan: &ConvPlan,
    groups: &[wgpu::BindGroup],
) -> Result<Vec<f64>> {
    let n = groups.len();
    let rounds = TUNE_ROUNDS + 1;
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("tile tuning") });
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("tile tuning"), timestamp_writes: None });
        for r in 0..rounds {
            let base = (r * (n + 2)) as u32;
            write_opening_timestamp(&mut pass, queries, base, base + n as u32 + 1);
            for (i, group) in groups.iter().enumerate() {
                plan.record(&mut pass, i, false, group);
                pass.write_timestamp(queries, base + 1 + i as u32);
            }
        }
    }
    queue.submit(Some(encoder.finish()));
    let ticks = read_timestamps(device, queue, queries, (rounds * (n + 2)) as u32)?;
    let period = queue.get_timestamp_period() as f64;
    Ok((0..n)
        .map(|i| {
            // Round 0 is the untimed one.
            let mut t: Vec<f64> =
                (1..rounds).map(|r| ticks[r * (n + 2) + i + 1].saturating_sub(ticks[r * (n + 2) + i]) as f64 * period).collect();
            t.sort_by(f64::total_cmp);
            t[t.len() / 2]
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tuning_times_the_choices_candidates() {
        let join = |parts: &[&[Tile]]| parts.concat();
        let two: &'static [Tile] = &[Tile::CPU_LANES, Tile::CPU_WINOGRAD];
        // Plain tuning and a list ignore the matrix units; a fixed tile tunes nothing.
        assert_eq!(tuning_candidates(TileChoice::Tuned, Precision::F32, true, &TUNE_TILES), TUNE_TILES);
        assert_eq!(tuning_candidates(TileChoice::Tuned, Precision::F32, false, &TUNE_TILES_CPU), TUNE_TILES_CPU);
        assert_eq!(tuning_candidates(TileChoice::TunedAmong(TileList::new(two)), Precision::F16, true, &TUNE_TILES), two);
        assert!(tuning_candidates(TileChoice::Fixed(Tile::default()), Precision::F32, true, &TUNE_TILES).is_empty());
        // Auto and tuned-mma add the precision's matrix-unit tiles where they run.
        for choice in [TileChoice::Auto, TileChoice::TunedMma] {
            assert_eq!(tuning_candidates(choice, Precision::F32, true, &TUNE_TILES), join(&[&TUNE_TILES, &MMA_SPLIT_TILES]));
            assert_eq!(tuning_candidates(choice, Precision::F16, true, &TUNE_TILES), join(&[&TUNE_TILES, &MMA_TILES]));
            assert_eq!(tuning_candidates(choice, Precision::F32, false, &TUNE_TILES), TUNE_TILES);
        }
    }

    #[test]
    fn tile_choices_parse_what_they_display() {
        let list = TileList::new(&[Tile::new(16, 2).unwrap(), Tile::CPU_LANES, Tile::mma_split(32).unwrap(), Tile::CPU_WINOGRAD4]);
        for choice in [
            TileChoice::Auto,
            TileChoice::Tuned,
            TileChoice::TunedMma,
            TileChoice::TunedAmong(list),
            TileChoice::Fixed(Tile::winograd(4, 2).unwrap().with_group(32).unwrap()),
            TileChoice::Fixed(Tile::new(8, 1).unwrap().with_group(32).unwrap().with_split(4).unwrap()),
            TileChoice::Fixed(Tile::lanes(8, 2, 2).unwrap()),
            TileChoice::Fixed(Tile::mma(64).unwrap()),
        ] {
            assert_eq!(choice.to_string().parse::<TileChoice>().unwrap(), choice, "{choice}");
        }
        assert_eq!("tuned:16x2+lanes8x2+mma32x3+wino4lanes4x4".parse::<TileChoice>().unwrap(), TileChoice::TunedAmong(list));
        assert_eq!(TileChoice::TunedAmong(list).to_string(), "tuned:16x2+lanes8x2+mma32x3+wino4lanes4x4");
        // Named tiles of each kind, and their names back.
        for name in ["16x2", "8x1w2", "8x1g32k4", "wino4x2", "winolanes4x4", "wino4lanes4x4g16", "wino4lanes4x1", "mma48"] {
            assert_eq!(name.parse::<Tile>().unwrap().to_string(), name);
        }
    }

    #[test]
    fn bad_tile_text_says_what_the_kernels_have() {
        for (text, says) in [
            ("wino4lanes8x4", "4 rows and 1, 2 or 4 blocks"),
            ("wino4lanes4x3", "4 rows and 1, 2 or 4 blocks"),
            ("wino4lanes4x4w2", "fixed width"),
            ("wino4lanes4", "no ROWSxBLOCKS"),
            ("9x9", "1, 2, 4, 8 or 16 rows"),
            ("16x2g7", "workgroups are 8, 16, 32 or 64 wide"),
            ("mma40", "16, 32, 48 or 64"),
            ("tuned:16x2+auto", "`auto`"),
            ("fast", "no ROWSxBLOCKS"),
        ] {
            let err = text.parse::<TileChoice>().unwrap_err().to_string();
            assert!(err.contains(&format!("tile `{text}`")) && err.contains(says), "{text}: {err}");
        }
        let many = vec!["16x2"; crate::kernels::TILE_LIST_MAX + 1].join("+");
        assert!(format!("tuned:{many}").parse::<TileChoice>().is_err());
    }
}

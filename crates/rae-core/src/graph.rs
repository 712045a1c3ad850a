//! The network as a list of convolutions over named values, built from an [`Arch`].
//!
//! Upsampling and concatenation are not nodes: they are how a convolution reads its sources
//! ([`Read`]), so every node is one fused kernel dispatch. Max-pooling is read the same way in
//! principle ([`Read::Pool`]), but each encoder block's output is read pooled by two convs (the
//! next block's first, and the decoder's skip in the reference network), at 9 taps x 4 texels
//! per value; so the graph pools it once per frame into a value of its own ([`Pool`],
//! [`Value::Pooled`]) and those convs read one texel per value. Node names are the PyTorch
//! module names, so a node finds its weights as `"{name}.weight"` and `"{name}.bias"`.

use crate::model::{Arch, OutputActivation, Skip};

/// How a convolution reads one of its sources (matches the READ_* constants of conv3x3.wgsl).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Read {
    /// As-is, at the convolution's resolution.
    Direct = 0,
    /// Max-pooled 2x2 from twice the resolution.
    Pool = 1,
    /// Nearest-upsampled 2x from half the resolution.
    Upsample = 2,
    /// Max-pooled then upsampled, at the convolution's resolution (the reference code's skips).
    PoolUpsample = 3,
}

/// A tensor the graph reads or writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Value {
    /// The packed network input.
    Input,
    /// Hidden state of encoder block `i` (0-based, the bottleneck last) from the previous frame.
    HiddenPrev(usize),
    /// Hidden state of encoder block `i` written this frame (also the block's output).
    HiddenNew(usize),
    /// An intermediate, live from the node that writes it to the last node that reads it.
    Temp(usize),
    /// `HiddenNew(i)` max-pooled 2x2, at level `i + 1` ([`Graph::pools`]).
    Pooled(usize),
}

/// One source of a convolution.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Source {
    /// The value read.
    pub value: Value,
    /// How it is read.
    pub read: Read,
    /// Its channels.
    pub channels: usize,
}

/// A 3x3 convolution with bias over `cat(a, b)`, LeakyReLU optional.
#[derive(Debug, Clone, PartialEq)]
pub struct ConvNode {
    /// PyTorch module name, e.g. `d1.l2.0`.
    pub name: String,
    /// Resolution level: the node runs at `full >> level`.
    pub level: usize,
    /// First source (its channels come first).
    pub a: Source,
    /// Second source, if any.
    pub b: Option<Source>,
    /// Output value.
    pub out: Value,
    /// Output channels.
    pub cout: usize,
    /// LeakyReLU after the bias (false: linear).
    pub leaky: bool,
}

impl ConvNode {
    /// Input channels (a then b).
    pub fn cin(&self) -> usize {
        self.a.channels + self.b.map_or(0, |b| b.channels)
    }
}

/// A 2x2 max-pool of encoder block `hidden`'s new state into [`Value::Pooled`]`(hidden)`, run
/// right after node `after` (the conv that writes that state), or written by that conv itself
/// where its tile holds whole 2x2 windows ([`crate::kernels::ConvPlan::pools`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Pool {
    /// Encoder block (index into [`Graph::hidden`]).
    pub hidden: usize,
    /// Level of the pooled value (the block's level + 1).
    pub level: usize,
    /// Channels.
    pub channels: usize,
    /// Index of the node after which it runs.
    pub after: usize,
}

/// Shape of a temporary value.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TempInfo {
    /// Resolution level.
    pub level: usize,
    /// Channels.
    pub channels: usize,
    /// Index of the node writing it.
    pub def: usize,
    /// Index of the last node reading it (`nodes.len()` for the network output).
    pub last_use: usize,
}

/// The network's dataflow.
#[derive(Debug, Clone)]
pub struct Graph {
    /// Convolutions in execution order.
    pub nodes: Vec<ConvNode>,
    /// Temporaries, indexed by `Value::Temp(i)`.
    pub temps: Vec<TempInfo>,
    /// Channels of each hidden state (encoder blocks, bottleneck last) and its level.
    pub hidden: Vec<(usize, usize)>,
    /// Pool passes, in execution order; `pools[i]` writes `Value::Pooled(i)`.
    pub pools: Vec<Pool>,
    /// The value holding the network output (level 0).
    pub output: Value,
    /// Channels of the packed input.
    pub in_channels: usize,
}

impl Graph {
    /// Build the dataflow of an architecture.
    pub fn new(arch: &Arch) -> Self {
        let mut b = Builder { nodes: Vec::new(), temps: Vec::new() };
        let levels = arch.levels();
        let mut hidden = Vec::new();
        let mut pools = Vec::new();

        // Encoder: d1..dN, then the bottleneck (hidden index N), each recurrent.
        let mut src = Source { value: Value::Input, read: Read::Direct, channels: arch.in_channels() };
        let widths: Vec<usize> = arch.encoder.iter().copied().chain([arch.bottleneck]).collect();
        for (i, &w) in widths.iter().enumerate() {
            let name = if i < levels { format!("d{}", i + 1) } else { "bottleneck".to_string() };
            let op1 = b.conv(format!("{name}.l1.0"), i, src, None, w, true);
            let direct = |value, channels| Source { value, read: Read::Direct, channels };
            let hidden_prev = direct(Value::HiddenPrev(i), w);
            let mid = b.conv(format!("{name}.l2.0"), i, direct(op1, w), Some(hidden_prev), w, true);
            b.conv_into(format!("{name}.l2.2"), i, direct(mid, w), None, w, true, Value::HiddenNew(i));
            hidden.push((w, i));
            // The next block reads this one's output max-pooled (the bottleneck is not pooled).
            if i < levels {
                pools.push(Pool { hidden: i, level: i + 1, channels: w, after: b.nodes.len() - 1 });
                src = Source { value: Value::Pooled(i), read: Read::Direct, channels: w };
            }
        }

        // Decoder: uN..u1, each over cat(upsampled previous, skip of d_k).
        let mut prev = Source { value: Value::HiddenNew(levels), read: Read::Upsample, channels: arch.bottleneck };
        let mut out = Value::Input;
        for k in (1..=levels).rev() {
            let level = k - 1;
            // The reference network's skip is upsample(pool(d_k)): the pooled value, upsampled.
            let (skip_value, skip_read) = match arch.skip {
                Skip::Pooled => (Value::Pooled(k - 1), Read::Upsample),
                Skip::Prepool => (Value::HiddenNew(k - 1), Read::Direct),
            };
            let skip = Source { value: skip_value, read: skip_read, channels: arch.encoder[k - 1] };
            let w = arch.decoder_width(k);
            let t = b.conv(format!("u{k}.l1.1"), level, prev, Some(skip), w, true);
            let leaky = !(k == 1 && arch.output_activation == OutputActivation::Linear);
            out = b.conv(format!("u{k}.l1.3"), level, Source { value: t, read: Read::Direct, channels: w }, None, w, leaky);
            prev = Source { value: out, read: Read::Upsample, channels: w };
        }

        // Liveness: the last node reading each temporary; the output is read after all nodes.
        let n = b.nodes.len();
        for (i, node) in b.nodes.iter().enumerate() {
            for s in std::iter::once(node.a).chain(node.b) {
                if let Value::Temp(t) = s.value {
                    b.temps[t].last_use = b.temps[t].last_use.max(i);
                }
            }
        }
        if let Value::Temp(t) = out {
            b.temps[t].last_use = n;
        }
        Graph { nodes: b.nodes, temps: b.temps, hidden, pools, output: out, in_channels: arch.in_channels() }
    }

    /// Multiply-adds per full-resolution pixel.
    pub fn macs_per_pixel(&self) -> f64 {
        self.nodes.iter().map(|n| (9 * n.cin() * n.cout) as f64 / (1u64 << (2 * n.level)) as f64).sum()
    }

    /// The most bytes of values live at once while any node runs, each value in a texture of
    /// exactly its channel blocks at `texel_bytes` a texel, the frame padded to `pwidth` x
    /// `pheight`, and the node where that peak is: the least that any allocation of one texture
    /// per value can hold for the frame, however it shares textures. Live at node `i`: every
    /// block's hidden state (one copy: the frame's state is kept between frames), the input
    /// until its last reader, each temporary from its writer to its last reader, and each
    /// pooled value from the node after which it is pooled to its last reader.
    pub fn least_live_bytes(&self, pwidth: u32, pheight: u32, texel_bytes: u64) -> (u64, usize) {
        let bytes = |level: usize, channels: usize| {
            (pwidth >> level) as u64 * (pheight >> level) as u64 * channels.div_ceil(4) as u64 * texel_bytes
        };
        let reads = |n: &ConvNode, v: Value| n.a.value == v || n.b.is_some_and(|b| b.value == v);
        let last_reader = |v: Value| self.nodes.iter().rposition(|n| reads(n, v)).unwrap_or(0);
        let hidden: u64 = self.hidden.iter().map(|&(c, level)| bytes(level, c)).sum();
        let input_until = last_reader(Value::Input);
        let pooled: Vec<(usize, usize, u64)> =
            self.pools.iter().enumerate().map(|(k, p)| (p.after, last_reader(Value::Pooled(k)), bytes(p.level, p.channels))).collect();
        (0..self.nodes.len())
            .map(|i| {
                let input = if i <= input_until { bytes(0, self.in_channels) } else { 0 };
                let temps: u64 = self.temps.iter().filter(|t| t.def <= i && i <= t.last_use).map(|t| bytes(t.level, t.channels)).sum();
                let pools: u64 = pooled.iter().filter(|&&(from, to, _)| from <= i && i <= to).map(|&(_, _, b)| b).sum();
                (hidden + input + temps + pools, i)
            })
            .max_by_key(|&(b, i)| (b, std::cmp::Reverse(i)))
            .unwrap_or((hidden, 0))
    }

    /// Where every value that lives within a frame (the input, the temporaries, the pooled
    /// values) is kept: packed by lifetime into arenas, full-resolution texture arrays that
    /// values of every level share ([`Place`]). Greedy in the order the values are written:
    /// each takes the lowest free cells of the arena it grows least, never an arena that the
    /// node writing it reads (a dispatch does not read and write one texture). Every block's
    /// hidden state, kept between frames, has a texture of its own.
    pub fn place(&self) -> Placement {
        let reads = |n: &ConvNode, v: Value| n.a.value == v || n.b.is_some_and(|b| b.value == v);
        let last_reader = |v: Value, from: usize| self.nodes.iter().rposition(|n| reads(n, v)).unwrap_or(from).max(from);
        let item = |value, level, channels: usize, def: usize, last| {
            // The node that writes the value (the input's reader, for the input) reads these.
            let n = &self.nodes[def];
            let writer_reads = if value == Value::Input { [None, None] } else { [Some(n.a.value), n.b.map(|b| b.value)] };
            Lived { value, level, blocks: channels.div_ceil(4) as u32, def, last, writer_reads }
        };
        let mut items = vec![item(Value::Input, 0, self.in_channels, 0, last_reader(Value::Input, 0))];
        items.extend(self.temps.iter().enumerate().map(|(t, i)| item(Value::Temp(t), i.level, i.channels, i.def, i.last_use)));
        items.extend(self.pools.iter().enumerate().map(|(k, p)| {
            let v = Value::Pooled(k);
            item(v, p.level, p.channels, p.after, last_reader(v, p.after))
        }));
        items.sort_by_key(|item| item.def);
        // Addresses count cells of the deepest level placed: a cell of level l is 4^(finest - l)
        // of them, and starts at a multiple of that (a Morton-ordered grid nests).
        let finest = items.iter().map(|item| item.level).max().unwrap_or(0);
        let cell = |level: usize| 1u64 << (2 * (finest - level));
        // Per item: its arena and its first and end addresses.
        let mut placed: Vec<(usize, u64, u64)> = Vec::new();
        let mut ends: Vec<u64> = Vec::new();
        for (i, it) in items.iter().enumerate() {
            let (align, size) = (cell(it.level), it.blocks as u64 * cell(it.level));
            let forbidden: Vec<usize> = (0..i).filter(|&j| it.writer_reads.contains(&Some(items[j].value))).map(|j| placed[j].0).collect();
            // (growth of the arena, end, arena, start): the least growth, then the lowest end.
            let mut best: Option<(u64, u64, usize, u64)> = None;
            for arena in (0..=ends.len()).filter(|a| !forbidden.contains(a)) {
                let mut busy: Vec<(u64, u64)> = (0..i)
                    .filter(|&j| placed[j].0 == arena && items[j].def <= it.last && it.def <= items[j].last)
                    .map(|j| (placed[j].1, placed[j].2))
                    .collect();
                busy.sort_unstable();
                let mut start = 0u64;
                for &(s, e) in &busy {
                    if start + size <= s {
                        break;
                    }
                    start = start.max(e.next_multiple_of(align));
                }
                let end = start + size;
                let growth = end.saturating_sub(ends.get(arena).copied().unwrap_or(0));
                if best.is_none_or(|b| (growth, end) < (b.0, b.1)) {
                    best = Some((growth, end, arena, start));
                }
            }
            let (_, end, arena, start) = best.expect("a new arena is always allowed");
            if arena == ends.len() {
                ends.push(0);
            }
            ends[arena] = ends[arena].max(end);
            placed.push((arena, start, end));
        }
        let place = |v: Value| {
            let i = items.iter().position(|item| item.value == v).expect("every value placed");
            let it = &items[i];
            Place { arena: placed[i].0, level: it.level, first: (placed[i].1 / cell(it.level)) as u32, blocks: it.blocks }
        };
        Placement {
            input: place(Value::Input),
            temps: (0..self.temps.len()).map(|t| place(Value::Temp(t))).collect(),
            pooled: (0..self.pools.len()).map(|k| place(Value::Pooled(k))).collect(),
            arena_layers: ends.iter().map(|&e| e.div_ceil(cell(0)) as u32).collect(),
        }
    }
}

/// A value that lives within a frame, as [`Graph::place`] packs it.
struct Lived {
    value: Value,
    level: usize,
    blocks: u32,
    /// The node that writes it (the input: its reader, node 0) and the last that reads it.
    def: usize,
    last: usize,
    /// What the node writing it reads (an arena it must not share).
    writer_reads: [Option<Value>; 2],
}

/// Where a value that lives within a frame is kept ([`Graph::place`]): in an arena, a texture
/// array at full resolution. A layer of an arena holds `4^level` cells of a level-`level`
/// value, a `2^level x 2^level` grid of images of the level's size, numbered in Morton order
/// (cell `k`'s column is `k`'s even bits, its row its odd bits), so the four cells of level
/// `l + 1` inside a cell of level `l` are consecutive. Channel block `j` of the value is cell
/// `first + j`: arena layer `(first + j) >> 2 level`, cell `(first + j) mod 4^level` there.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Place {
    /// The arena.
    pub arena: usize,
    /// The value's resolution level.
    pub level: usize,
    /// Its first cell, in cells of its level.
    pub first: u32,
    /// Its channel blocks: cells.
    pub blocks: u32,
}

impl Place {
    /// Where channel block `j` is: the cell's top-left texel and arena layer, for a frame
    /// padded to `pwidth` x `pheight` (conv_common.wgsl's `carved`).
    pub fn cell(&self, j: u32, pwidth: u32, pheight: u32) -> (u32, u32, u32) {
        let cell = self.first + j;
        let shift = 2 * self.level as u32;
        let k = cell & ((1u32 << shift) - 1);
        let even_bits = |v: u32| (0..16).map(|b| ((v >> (2 * b)) & 1) << b).sum::<u32>();
        (even_bits(k) * (pwidth >> self.level), even_bits(k >> 1) * (pheight >> self.level), cell >> shift)
    }
}

/// Every frame-local value's [`Place`] and the arenas' sizes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Placement {
    /// The packed input's.
    pub input: Place,
    /// Each temporary's, by index.
    pub temps: Vec<Place>,
    /// Each pooled value's, by index.
    pub pooled: Vec<Place>,
    /// Layers of each arena.
    pub arena_layers: Vec<u32>,
}

impl Placement {
    /// The place of `v`; `None` for a hidden state (a texture of its own).
    pub fn of(&self, v: Value) -> Option<Place> {
        match v {
            Value::Input => Some(self.input),
            Value::Temp(t) => Some(self.temps[t]),
            Value::Pooled(k) => Some(self.pooled[k]),
            Value::HiddenPrev(_) | Value::HiddenNew(_) => None,
        }
    }
}

struct Builder {
    nodes: Vec<ConvNode>,
    temps: Vec<TempInfo>,
}

impl Builder {
    fn conv(&mut self, name: String, level: usize, a: Source, b: Option<Source>, cout: usize, leaky: bool) -> Value {
        let t = Value::Temp(self.temps.len());
        self.temps.push(TempInfo { level, channels: cout, def: self.nodes.len(), last_use: self.nodes.len() });
        self.conv_into(name, level, a, b, cout, leaky, t);
        t
    }

    #[allow(clippy::too_many_arguments)]
    fn conv_into(&mut self, name: String, level: usize, a: Source, b: Option<Source>, cout: usize, leaky: bool, out: Value) {
        self.nodes.push(ConvNode { name, level, a, b, out, cout, leaky });
    }
}

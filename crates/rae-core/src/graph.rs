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

    /// Map temporaries onto as few physical buffers as their lifetimes allow.
    ///
    /// Returns, per temporary, the index of its slot, and per slot its (level, channels). A slot
    /// is reused only at the same level once its last reader has run; the node that reads a
    /// value never writes into that value's slot (it is bound for reading in the same dispatch).
    pub fn allocate_temps(&self) -> (Vec<usize>, Vec<(usize, usize)>) {
        let mut slots: Vec<(usize, usize)> = Vec::new();
        let mut busy_until: Vec<usize> = Vec::new();
        let mut assign = vec![usize::MAX; self.temps.len()];
        for (t, info) in self.temps.iter().enumerate() {
            // Free: slots whose last reader ran before this temp's writer.
            let candidate = (0..slots.len())
                .filter(|&s| slots[s].0 == info.level && busy_until[s] < info.def)
                .min_by_key(|&s| (slots[s].1 < info.channels, slots[s].1.abs_diff(info.channels)));
            let s = match candidate {
                Some(s) => {
                    slots[s].1 = slots[s].1.max(info.channels);
                    s
                }
                None => {
                    slots.push((info.level, info.channels));
                    busy_until.push(0);
                    slots.len() - 1
                }
            };
            busy_until[s] = info.last_use;
            assign[t] = s;
        }
        (assign, slots)
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

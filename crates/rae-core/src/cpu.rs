//! Plain CPU implementations of every operation, written for clarity, not speed: the reference
//! that the WGSL kernels are tested against, and a whole-network forward built from them.

use crate::graph::{Graph, Read, Value};
use crate::weights::Weights;

/// A channel-major tensor (`c x h x w`).
#[derive(Debug, Clone, PartialEq)]
pub struct Chw {
    /// Channels.
    pub c: usize,
    /// Height.
    pub h: usize,
    /// Width.
    pub w: usize,
    /// Values, `data[(ch * h + y) * w + x]`.
    pub data: Vec<f32>,
}

impl Chw {
    /// All zeros.
    pub fn zeros(c: usize, h: usize, w: usize) -> Self {
        Self { c, h, w, data: vec![0.0; c * h * w] }
    }

    /// Value at (channel, y, x).
    pub fn at(&self, c: usize, y: usize, x: usize) -> f32 {
        self.data[(c * self.h + y) * self.w + x]
    }
}

/// 2x2 max pooling, stride 2 (odd trailing rows/columns dropped, as PyTorch does).
pub fn max_pool2(x: &Chw) -> Chw {
    let mut o = Chw::zeros(x.c, x.h / 2, x.w / 2);
    for c in 0..x.c {
        for y in 0..o.h {
            for xx in 0..o.w {
                let m = x.at(c, 2 * y, 2 * xx).max(x.at(c, 2 * y, 2 * xx + 1)).max(x.at(c, 2 * y + 1, 2 * xx)).max(x.at(
                    c,
                    2 * y + 1,
                    2 * xx + 1,
                ));
                o.data[(c * o.h + y) * o.w + xx] = m;
            }
        }
    }
    o
}

/// Nearest-neighbour 2x upsampling to `h x w` (pixel (x, y) takes source (x/2, y/2)).
pub fn upsample2(x: &Chw, h: usize, w: usize) -> Chw {
    let mut o = Chw::zeros(x.c, h, w);
    for c in 0..x.c {
        for y in 0..h {
            for xx in 0..w {
                o.data[(c * h + y) * w + xx] = x.at(c, y / 2, xx / 2);
            }
        }
    }
    o
}

/// A source read the way the conv kernel reads it, at output size `h x w`.
pub fn read(x: &Chw, mode: Read, h: usize, w: usize) -> Chw {
    match mode {
        Read::Direct => x.clone(),
        Read::Pool => max_pool2(x),
        Read::Upsample => upsample2(x, h, w),
        Read::PoolUpsample => upsample2(&max_pool2(x), h, w),
    }
}

/// Channel concatenation, `a` first.
pub fn concat(a: &Chw, b: &Chw) -> Chw {
    assert_eq!((a.h, a.w), (b.h, b.w), "concat of different sizes");
    let mut data = a.data.clone();
    data.extend_from_slice(&b.data);
    Chw { c: a.c + b.c, h: a.h, w: a.w, data }
}

/// 3x3 convolution, zero padding 1, bias, then LeakyReLU with `slope` if given. `weight` is
/// OIHW (`cout x x.c x 3 x 3`). Accumulates in f64.
pub fn conv3x3(x: &Chw, weight: &[f32], bias: &[f32], slope: Option<f32>) -> Chw {
    let cout = bias.len();
    assert_eq!(weight.len(), cout * x.c * 9, "weight shape");
    let mut o = Chw::zeros(cout, x.h, x.w);
    for co in 0..cout {
        for y in 0..x.h {
            for xx in 0..x.w {
                let mut acc = bias[co] as f64;
                for ci in 0..x.c {
                    for ky in 0..3 {
                        for kx in 0..3 {
                            let (sy, sx) = (y as isize + ky as isize - 1, xx as isize + kx as isize - 1);
                            if sy < 0 || sx < 0 || sy >= x.h as isize || sx >= x.w as isize {
                                continue;
                            }
                            let wv = weight[((co * x.c + ci) * 3 + ky) * 3 + kx] as f64;
                            acc += wv * x.at(ci, sy as usize, sx as usize) as f64;
                        }
                    }
                }
                let v = acc as f32;
                o.data[(co * x.h + y) * x.w + xx] = match slope {
                    Some(s) if v < 0.0 => v * s,
                    _ => v,
                };
            }
        }
    }
    o
}

/// The whole network on the CPU, hidden state carried between calls of [`CpuNetwork::forward`].
pub struct CpuNetwork<'w> {
    weights: &'w Weights,
    graph: Graph,
    hidden: Vec<Option<Chw>>,
}

impl<'w> CpuNetwork<'w> {
    /// A network with zero hidden state.
    pub fn new(weights: &'w Weights) -> Self {
        let graph = Graph::new(&weights.arch);
        let hidden = vec![None; graph.hidden.len()];
        Self { weights, graph, hidden }
    }

    /// Run the convolutions on a packed input (`in_channels x h x w`, sizes multiples of
    /// `2^levels`); returns the raw network output (before the output stage).
    pub fn forward(&mut self, input: &Chw) -> Chw {
        let mut temps: Vec<Option<Chw>> = vec![None; self.graph.temps.len()];
        let mut new_hidden: Vec<Option<Chw>> = vec![None; self.hidden.len()];
        let slope = self.weights.arch.negative_slope;
        for node in &self.graph.nodes {
            let (h, w) = (input.h >> node.level, input.w >> node.level);
            let get = |v: Value, c: usize, temps: &[Option<Chw>], new_hidden: &[Option<Chw>]| -> Chw {
                match v {
                    Value::Input => input.clone(),
                    Value::Temp(t) => temps[t].clone().expect("defined before use"),
                    Value::HiddenNew(k) => new_hidden[k].clone().expect("defined before use"),
                    Value::Pooled(k) => max_pool2(new_hidden[k].as_ref().expect("defined before use")),
                    Value::HiddenPrev(k) => self.hidden[k].clone().unwrap_or_else(|| Chw::zeros(c, h, w)),
                }
            };
            let a = read(&get(node.a.value, node.a.channels, &temps, &new_hidden), node.a.read, h, w);
            let x = match node.b {
                Some(b) => concat(&a, &read(&get(b.value, b.channels, &temps, &new_hidden), b.read, h, w)),
                None => a,
            };
            let wt = self.weights.get(&format!("{}.weight", node.name)).expect("validated");
            let bs = self.weights.get(&format!("{}.bias", node.name)).expect("validated");
            let y = conv3x3(&x, &wt.data, &bs.data, node.leaky.then_some(slope));
            match node.out {
                Value::Temp(t) => temps[t] = Some(y),
                Value::HiddenNew(k) => new_hidden[k] = Some(y),
                _ => unreachable!("nodes write temporaries or hidden state"),
            }
        }
        self.hidden = new_hidden;
        let Value::Temp(t) = self.graph.output else { unreachable!() };
        temps[t].take().expect("output computed")
    }

    /// Zero the hidden state.
    pub fn reset(&mut self) {
        self.hidden.iter_mut().for_each(|h| *h = None);
    }
}

/// Bounds of the input policy (see [`crate::frame`]); shared with the WGSL kernels by value.
pub mod limits {
    /// Largest radiance kept; +Inf maps here.
    pub const RADIANCE_MAX: f32 = 1e8;
    /// Largest albedo kept.
    pub const ALBEDO_MAX: f32 = 1e3;
    /// Largest depth kept; +Inf (a miss) maps here.
    pub const DEPTH_MAX: f32 = 1e6;
    /// The network output is clamped to `[0, OUT_LOG_MAX]` before `exp(y) - 1`.
    pub const OUT_LOG_MAX: f32 = 80.0;
    /// The output's demodulated radiance is at most `OUT_GAIN` times the frame's largest
    /// demodulated input radiance (see [`super::output_limit`]).
    pub const OUT_GAIN: f32 = 2.0;
}

/// Largest prepared color value (channels 0..3, transfer space) of a packed network input.
pub fn color_max(x: &Chw) -> f32 {
    x.data[..3 * x.h * x.w].iter().fold(0.0f32, |m, &v| m.max(v))
}

/// Upper clamp of the network output (transfer space) given the frame's largest prepared color
/// `in_max`: the denoised demodulated radiance never exceeds `OUT_GAIN` times the brightest
/// demodulated input radiance of the frame (a denoiser redistributes energy, it does not make
/// it), nor `exp(OUT_LOG_MAX) - 1`. An all-black frame therefore gives an all-black result.
pub fn output_limit(arch: &crate::Arch, in_max: f32) -> f32 {
    match arch.transfer {
        crate::model::Transfer::Log1p => ((limits::OUT_GAIN * (in_max.exp() - 1.0)).ln_1p()).min(limits::OUT_LOG_MAX),
        crate::model::Transfer::None => (limits::OUT_GAIN * in_max).min(limits::RADIANCE_MAX),
    }
}

/// NaN -> 0, +Inf -> `posinf`, -Inf -> `lo`, then clamp to `[lo, hi]`.
pub fn sanitize(v: f32, lo: f32, hi: f32, posinf: f32) -> f32 {
    if v.is_nan() {
        0f32.clamp(lo, hi)
    } else if v == f32::NEG_INFINITY {
        lo
    } else if v == f32::INFINITY {
        posinf.clamp(lo, hi)
    } else {
        v.clamp(lo, hi)
    }
}

/// Depth as prep reads it: a miss is a miss whatever the renderer writes for it (+inf, 0, NaN,
/// a negative value): all become [`limits::DEPTH_MAX`].
pub fn sanitize_depth(v: f32) -> f32 {
    let d = sanitize(v, 0.0, limits::DEPTH_MAX, limits::DEPTH_MAX);
    if d > 0.0 { d } else { limits::DEPTH_MAX }
}

fn sanitize_albedo(v: f32) -> f32 {
    sanitize(v, 0.0, limits::ALBEDO_MAX, 0.0)
}

/// Whether pixel `i` of a frame is a miss, from the buffers `arch` reads ([`crate::Arch::miss_by`]):
/// depth at [`limits::DEPTH_MAX`] once sanitised, or a zero normal.
pub fn is_miss(arch: &crate::Arch, frame: &crate::FrameInputs, i: usize) -> bool {
    let (by_depth, by_normal) = arch.miss_by();
    let depth = || sanitize_depth(frame.depth.expect("validated")[i]) >= limits::DEPTH_MAX;
    let normal = || (0..3).all(|k| sanitize(frame.normal.expect("validated")[3 * i + k], -1.0, 1.0, 0.0) == 0.0);
    (by_depth && depth()) || (by_normal && normal())
}

/// Channel `k` of pixel `i`'s albedo as prep reads it: sanitised, 1 at a miss.
fn albedo_at(arch: &crate::Arch, frame: &crate::FrameInputs, i: usize, k: usize) -> f32 {
    if is_miss(arch, frame, i) { 1.0 } else { sanitize_albedo(frame.albedo.expect("validated")[3 * i + k]) }
}

/// Channel `k` of pixel `i`'s color as prep prepares it: sanitised, demodulated, transfer applied.
fn prepared_color(arch: &crate::Arch, frame: &crate::FrameInputs, i: usize, k: usize) -> f32 {
    let mut s = sanitize(frame.color[3 * i + k], 0.0, limits::RADIANCE_MAX, limits::RADIANCE_MAX);
    if arch.demodulate {
        s /= albedo_at(arch, frame, i, k) + arch.albedo_eps;
    }
    if arch.transfer == crate::model::Transfer::Log1p { (1.0 + s).ln() } else { s }
}

/// The prep kernel on the CPU: a frame (`w x h`) -> packed network input at `pw x ph`.
pub fn prepare(arch: &crate::Arch, frame: &crate::FrameInputs, w: usize, h: usize, pw: usize, ph: usize) -> Chw {
    use crate::model::InputBuffer;
    let mut o = Chw::zeros(arch.in_channels(), ph, pw);
    for y in 0..ph {
        for x in 0..pw {
            let i = y.min(h - 1) * w + x.min(w - 1);
            let mut c0 = 0;
            for &b in &arch.inputs {
                let data = frame.get(b).expect("frame validated");
                let vals: Vec<f32> = match b {
                    InputBuffer::Color => (0..3).map(|k| prepared_color(arch, frame, i, k)).collect(),
                    InputBuffer::Albedo => (0..3).map(|k| albedo_at(arch, frame, i, k)).collect(),
                    InputBuffer::Normal => (0..3).map(|k| sanitize(data[3 * i + k], -1.0, 1.0, 0.0)).collect(),
                    InputBuffer::Depth => vec![(1.0 + sanitize_depth(data[i])).ln()],
                    InputBuffer::Roughness => vec![sanitize(data[i], 0.0, 1.0, 0.0)],
                };
                for (k, v) in vals.into_iter().enumerate() {
                    o.data[((c0 + k) * ph + y) * pw + x] = v;
                }
                c0 += b.channels();
            }
        }
    }
    o
}

/// The largest prepared color value (demodulated, transfer space) of a frame, as prep.wgsl
/// computes it per pixel: the output's bound ([`output_limit`]) for a frame run in tiles, where
/// each tile's prep sees only its part.
pub fn prepared_color_max(arch: &crate::Arch, frame: &crate::FrameInputs) -> f32 {
    if !arch.inputs.contains(&crate::model::InputBuffer::Color) {
        return 0.0;
    }
    (0..frame.color.len()).map(|c| prepared_color(arch, frame, c / 3, c % 3)).fold(0.0, f32::max)
}

/// The output kernel on the CPU: raw network output (padded) -> RGB radiance at `w x h`; at a
/// miss ([`is_miss`]) the sanitised input color.
pub fn finish(arch: &crate::Arch, y: &Chw, in_max: f32, frame: &crate::FrameInputs, w: usize, h: usize) -> Vec<f32> {
    use crate::model::Transfer;
    let limit = output_limit(arch, in_max);
    let mut out = vec![0.0; w * h * 3];
    for py in 0..h {
        for px in 0..w {
            let i = py * w + px;
            let miss = is_miss(arch, frame, i);
            for k in 0..3 {
                let v = y.at(k, py, px).clamp(0.0, limit);
                let mut r = match arch.transfer {
                    Transfer::Log1p => v.exp() - 1.0,
                    Transfer::None => v,
                };
                if miss {
                    r = sanitize(frame.color[3 * i + k], 0.0, limits::RADIANCE_MAX, limits::RADIANCE_MAX);
                } else if arch.demodulate {
                    r *= sanitize_albedo(frame.albedo.expect("validated")[3 * i + k]) + arch.albedo_eps;
                }
                out[3 * i + k] = r;
            }
        }
    }
    out
}

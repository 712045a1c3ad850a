//! Weight layouts as the kernels read them: direct taps, Winograd F(2x2, 3x3) and F(4x4, 3x3)
//! transformed weights ([`winograd_taps`], [`winograd4_taps`]), and the matrix-unit tiles' f16
//! layout ([`pack_mma`]).

use super::*;

/// Winograd F(2x2, 3x3)'s weight transform G g G^T of one 3x3 kernel (row-major, `[ky][kx]`),
/// in f64 and rounded once: the 16 weights conv3x3.wgsl's `winograd` multiplies with.
pub fn winograd_taps(g: &[f32]) -> [f32; 16] {
    const G: [[f64; 3]; 4] = [[1.0, 0.0, 0.0], [0.5, 0.5, 0.5], [0.5, -0.5, 0.5], [0.0, 0.0, 1.0]];
    weight_transform(&G, g)
}

/// G g G^T of one 3x3 kernel `g` for the N x 3 matrix `m` = G, in f64 and rounded once,
/// row-major (position p = N i + j).
fn weight_transform<const N: usize, const NN: usize>(m: &[[f64; 3]; N], g: &[f32]) -> [f32; NN] {
    debug_assert_eq!(N * N, NN);
    std::array::from_fn(|p| {
        let (i, j) = (p / N, p % N);
        let mut u = 0.0;
        for a in 0..3 {
            for b in 0..3 {
                u += m[i][a] * g[a * 3 + b] as f64 * m[j][b];
            }
        }
        u as f32
    })
}

/// Winograd F(4x4, 3x3)'s weight transform G g G^T of one 3x3 kernel (row-major, `[ky][kx]`),
/// in f64 and rounded once: the 36 weights conv3x3_wino4.wgsl's `winograd4_lanes` multiplies
/// with, for its B and A (points 0, 1, -1, 2, -2 and infinity).
pub fn winograd4_taps(g: &[f32]) -> [f32; 36] {
    const G: [[f64; 3]; 6] = [
        [1.0 / 4.0, 0.0, 0.0],
        [-1.0 / 6.0, -1.0 / 6.0, -1.0 / 6.0],
        [-1.0 / 6.0, 1.0 / 6.0, -1.0 / 6.0],
        [1.0 / 24.0, 1.0 / 12.0, 1.0 / 6.0],
        [1.0 / 24.0, -1.0 / 12.0, 1.0 / 6.0],
        [0.0, 0.0, 1.0],
    ];
    weight_transform(&G, g)
}

/// The weight chunk of output blocks `ob0 .. ob0 + ob` of a conv over `cat(a, b)`, laid out as
/// conv3x3.wgsl reads it: taps `[in block][ky*3+kx][in lane][j]` -> vec4 over block `ob0 + j`'s
/// 4 output channels, then `ob` bias vec4s. With [`Method::Winograd`] the 9 taps of each pair
/// are the 16 of [`winograd_taps`] (`[in block][position][in lane][j]`), with
/// [`Method::Winograd4Lanes`] the 36 of [`winograd4_taps`].
///
/// Input blocks follow the sources: source a's channels padded to a multiple of 4, then source
/// b's, so the kernel reads each source's texture layers without a concat. Padding weights are
/// zero, so padding channels (always written as zero) and padding outputs contribute nothing.
pub fn pack_group(spec: &ConvSpec, ob0: usize, ob: usize, method: Method) -> Vec<[f32; 4]> {
    let (weight, bias, cout, ca, cb) = (spec.weight, spec.bias, spec.cout, spec.ca, spec.cb);
    let cin = ca + cb;
    debug_assert_eq!(weight.len(), cout * cin * 9);
    let (ba, bb) = (blocks(ca) as usize, blocks(cb) as usize);
    let channel = |ib: usize, lane: usize| input_channel(spec, ib, lane);
    let taps = method.taps() as usize;
    // The weights of one channel pair as the kernel multiplies them.
    let pair = |o: usize, i: usize| -> [f32; 36] {
        let g = &weight[(o * cin + i) * 9..][..9];
        match method {
            Method::Winograd4Lanes => winograd4_taps(g),
            Method::Winograd | Method::WinogradLanes => {
                let u = winograd_taps(g);
                std::array::from_fn(|t| u.get(t).copied().unwrap_or(0.0))
            }
            _ => std::array::from_fn(|t| g.get(t).copied().unwrap_or(0.0)),
        }
    };
    let mut out = Vec::with_capacity((ba + bb) * taps * 4 * ob + ob);
    for ib in 0..ba + bb {
        // [lane][j][l] -> the pair's weights, zero for padding.
        let pairs: Vec<[[f32; 36]; 4]> = (0..4 * ob)
            .map(|k| {
                let (lane, j) = (k / ob, k % ob);
                std::array::from_fn(|l| {
                    let o = 4 * (ob0 + j) + l;
                    match channel(ib, lane) {
                        Some(i) if o < cout => pair(o, i),
                        _ => [0.0; 36],
                    }
                })
            })
            .collect();
        for tap in 0..taps {
            out.extend(pairs.iter().map(|p| std::array::from_fn(|l| p[l][tap])));
        }
    }
    for j in 0..ob {
        out.push(std::array::from_fn(|l| bias.get(4 * (ob0 + j) + l).copied().unwrap_or(0.0)));
    }
    out
}

/// The input channel of `cat(a, b)` at lane `lane` of input block `ib` (source a's channels
/// padded to a multiple of 4, then source b's), or `None` for a padding lane.
fn input_channel(spec: &ConvSpec, ib: usize, lane: usize) -> Option<usize> {
    let ba = blocks(spec.ca) as usize;
    if ib < ba {
        let c = 4 * ib + lane;
        (c < spec.ca).then_some(c)
    } else {
        let c = 4 * (ib - ba) + lane;
        (c < spec.cb).then_some(spec.ca + c)
    }
}

/// f16 values of one Mma group's weights ([`Method::Mma`]): output channels `n0 .. n0 + 16 *
/// nt` of a conv over `cat(a, b)`, laid out as conv3x3_mma.wgsl reads them. For chunk c (input
/// blocks 4c .. 4c + 3, in [`pack_group`]'s block order) and tap t = ky * 3 + kx, `nt` tiles of
/// 16 x 16 `[k][n]` (input channel of block 4c + k / 4, lane k % 4; output channel
/// n0 + 16 tile + n); with `split` ([`Method::MmaSplit`]) all those tiles again as the
/// weights' scaled remainders f16((w - f16(w)) * 2^11); then the bias as hi = f16(b) for the
/// 16 * nt channels and lo = f16(b - hi) for them. Padding is zero.
pub fn pack_mma(spec: &ConvSpec, n0: usize, nt: usize, split: bool) -> Vec<half::f16> {
    let (weight, cout, cin) = (spec.weight, spec.cout, spec.ca + spec.cb);
    debug_assert_eq!(weight.len(), cout * cin * 9);
    let chunks = (blocks(spec.ca) + blocks(spec.cb)).div_ceil(4) as usize;
    // The tiles' weights in f32, in the kernel's order.
    let mut tiles: Vec<f32> = Vec::with_capacity(chunks * 9 * nt * 256);
    for c in 0..chunks {
        // The input channel of each row k of this chunk's tiles.
        let rows: Vec<Option<usize>> = (0..16).map(|k| input_channel(spec, 4 * c + k / 4, k % 4)).collect();
        for t in 0..9 {
            for tile in 0..nt {
                for i in &rows {
                    for n in 0..16 {
                        let o = n0 + 16 * tile + n;
                        tiles.push(match *i {
                            Some(i) if o < cout => weight[(o * cin + i) * 9 + t],
                            _ => 0.0,
                        });
                    }
                }
            }
        }
    }
    let mut out: Vec<half::f16> = Vec::with_capacity(tiles.len() * (1 + split as usize) + 32 * nt);
    out.extend(tiles.iter().map(|&w| half::f16::from_f32(w)));
    if split {
        // Each weight's remainder below its f16, scaled by 2^11 (conv3x3_mma.wgsl's LO_SCALE)
        // so that it stays a normal f16 where an unscaled one would be subnormal.
        out.extend(tiles.iter().map(|&w| half::f16::from_f32((w - half::f16::from_f32(w).to_f32()) * MMA_LO_SCALE)));
    }
    let bias: Vec<f32> = (0..16 * nt).map(|n| spec.bias.get(n0 + n).copied().unwrap_or(0.0)).collect();
    let hi: Vec<half::f16> = bias.iter().map(|&b| half::f16::from_f32(b)).collect();
    out.extend(&hi);
    out.extend(bias.iter().zip(&hi).map(|(&b, h)| half::f16::from_f32(b - h.to_f32())));
    out
}

/// Scale of a split operand's remainder ([`Method::MmaSplit`], conv3x3_mma.wgsl's LO_SCALE):
/// 2^11, one f16 mantissa.
pub const MMA_LO_SCALE: f32 = 2048.0;

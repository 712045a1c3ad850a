//! Temporal accumulation of the denoised output along the motion: each output pixel blended
//! with the previous frame's accumulated output at `x + motion`, clipped to what the network
//! sees now. weights-tool's `rae_weights/accumulate.py` is the same computation, and the two are
//! held to shared vectors (`tests/fixtures/accumulate_vectors.safetensors`).
//!
//! Real-time denoisers (SVGF, the OptiX temporal mode) all reuse the previous result this way:
//! the network's residual error changes from frame to frame, and averaging it along the motion
//! lowers both the error and the flicker (`docs/MODELS.md`, "Temporal accumulation"). Per
//! pixel, on tonemapped values `T(x) = x / (1 + x)` (one bright sample cannot dominate the
//! statistics or the blend):
//! 1. The history is the previous accumulated output at `x + motion`, tonemapped, bilinear
//!    between pixel centres. It is used only where the motion is valid (finite, at most
//!    [`crate::frame::MOTION_ABSURD`] times the frame's larger side) and the point lies inside
//!    the frame; elsewhere the output is the network's.
//! 2. The history is clipped, per channel, to `mean ± GAMMA * std` of `T` over the current
//!    output's 3x3 neighbourhood (the pixels inside the frame), and to that neighbourhood's
//!    minimum and maximum: history that disagrees with what the network sees now (a
//!    disocclusion, a moving shadow) is pulled to it, so there is no ghosting, without a test
//!    on depth or normals; and the output stays within its neighbourhood's range, so every
//!    bound of the output stage holds for it too.
//! 3. The result is `T⁻¹(ALPHA * T(current) + (1 - ALPHA) * T(history))`, at most
//!    [`crate::cpu::limits::RADIANCE_MAX`].
//!
//! This is the CPU reference: a [`crate::Denoiser`] built with [`crate::Options::accumulate`] runs
//! the same computation on the GPU (`shaders/accumulate.wgsl`), in the frame's encoder after the
//! output pass, and the tests hold the two to each other.

use crate::cpu::limits::RADIANCE_MAX;
use crate::frame::MOTION_ABSURD;

/// The current output's share of the blend.
pub const ALPHA: f32 = 0.5;
/// The history is clipped to the neighbourhood's mean ± `GAMMA` standard deviations.
pub const GAMMA: f32 = 0.5;

fn tonemap(x: f32) -> f32 {
    x / (1.0 + x)
}

/// One frame's accumulation: `current` (the network's output, RGB, `width * height * 3`), the
/// previous frame's accumulated output and this frame's motion (two f32 per pixel, rae's
/// convention) into `out`.
pub fn accumulate(current: &[f32], previous: &[f32], motion: &[f32], width: usize, height: usize, out: &mut [f32]) {
    let n = width * height;
    assert!(current.len() == 3 * n && previous.len() == 3 * n && out.len() == 3 * n && motion.len() == 2 * n);
    let limit = MOTION_ABSURD * width.max(height) as f32;
    let (wl, hl) = ((width - 1) as f32, (height - 1) as f32);
    for y in 0..height {
        for x in 0..width {
            let i = y * width + x;
            let (mx, my) = (motion[2 * i], motion[2 * i + 1]);
            // NaN fails every comparison, and an infinity exceeds the limit.
            let valid = mx.abs() <= limit && my.abs() <= limit;
            let (sx, sy) = (x as f32 + mx, y as f32 + my);
            if !(valid && sx >= 0.0 && sx <= wl && sy >= 0.0 && sy <= hl) {
                out[3 * i..3 * i + 3].copy_from_slice(&current[3 * i..3 * i + 3]);
                continue;
            }
            let (x0, y0) = (sx.floor(), sy.floor());
            let (fx, fy) = (sx - x0, sy - y0);
            let (x0, y0) = (x0 as usize, y0 as usize);
            let (x1, y1) = ((x0 + 1).min(width - 1), (y0 + 1).min(height - 1));
            let (ylo, yhi) = (y.saturating_sub(1), (y + 1).min(height - 1));
            let (xlo, xhi) = (x.saturating_sub(1), (x + 1).min(width - 1));
            let count = ((yhi - ylo + 1) * (xhi - xlo + 1)) as f32;
            for c in 0..3 {
                let t = |j: usize| tonemap(current[3 * j + c]);
                let (mut sum, mut lowest, mut highest) = (0.0, f32::INFINITY, f32::NEG_INFINITY);
                for q in ylo..=yhi {
                    for p in xlo..=xhi {
                        let v = t(q * width + p);
                        sum += v;
                        lowest = lowest.min(v);
                        highest = highest.max(v);
                    }
                }
                let mean = sum / count;
                let mut dev = 0.0;
                for q in ylo..=yhi {
                    for p in xlo..=xhi {
                        let d = t(q * width + p) - mean;
                        dev += d * d;
                    }
                }
                let std = (dev / count).sqrt();
                let h = |px: usize, py: usize| tonemap(previous[3 * (py * width + px) + c]);
                let top = h(x0, y0) * (1.0 - fx) + h(x1, y0) * fx;
                let bottom = h(x0, y1) * (1.0 - fx) + h(x1, y1) * fx;
                let (lo, hi) = ((mean - GAMMA * std).max(lowest), (mean + GAMMA * std).min(highest));
                let history = (top * (1.0 - fy) + bottom * fy).max(lo).min(hi);
                let b = ALPHA * t(i) + (1.0 - ALPHA) * history;
                out[3 * i + c] = (b / (1.0 - b).max(1e-30)).min(RADIANCE_MAX);
            }
        }
    }
}

/// The accumulated output kept between frames, on the host: [`Self::apply`] each frame's output
/// in place (what a [`crate::Denoiser`] built with [`crate::Options::accumulate`] does on the GPU).
#[derive(Debug, Clone)]
pub struct Accumulator {
    width: usize,
    height: usize,
    /// The last frame's accumulated output (empty before the first frame or after a reset).
    previous: Vec<f32>,
    current: Vec<f32>,
}

impl Accumulator {
    /// An accumulator for frames of `width` x `height`; holds two RGB f32 frames once running.
    pub fn new(width: u32, height: u32) -> Self {
        Accumulator { width: width as usize, height: height as usize, previous: Vec::new(), current: Vec::new() }
    }

    /// Forget the history: the next frame passes through as the first of a sequence.
    pub fn reset(&mut self) {
        self.previous.clear();
    }

    /// Bytes it holds while running (the previous output and a copy of the current one).
    pub fn bytes(&self) -> u64 {
        2 * self.width as u64 * self.height as u64 * 12
    }

    /// Accumulate `out` (this frame's network output, RGB) in place with the history and
    /// `motion`; a frame without motion, or the first after a reset, passes through and
    /// starts the history.
    pub fn apply(&mut self, out: &mut [f32], motion: Option<&[f32]>) {
        if let Some(m) = motion
            && self.previous.len() == out.len()
        {
            self.current.clear();
            self.current.extend_from_slice(out);
            accumulate(&self.current, &self.previous, m, self.width, self.height, out);
        }
        self.previous.clear();
        self.previous.extend_from_slice(out);
    }
}

//! Random numbers and the sampling routines every part of the tracer shares.

use std::f32::consts::PI;

use glam::{Vec2, Vec3A, vec3a};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg32;

/// A per-path random stream: one independent PCG32 per (seed, frame, pixel, pass), so a frame
/// is the same whatever the thread schedule, and every frame draws new numbers.
pub struct Sampler(Pcg32);

impl Sampler {
    /// The stream of one pixel of one frame and pass.
    pub fn new(seed: u64, frame: u32, pixel: u32, pass: u32) -> Self {
        // splitmix64-style mixing so nearby pixels get unrelated streams.
        let mut z = seed ^ ((frame as u64) << 40) ^ ((pass as u64) << 32) ^ pixel as u64;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d049bb133111eb);
        Self(Pcg32::seed_from_u64(z ^ (z >> 31)))
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f32 {
        self.0.random::<f32>()
    }

    /// Two uniforms in [0, 1).
    pub fn uniform2(&mut self) -> Vec2 {
        Vec2::new(self.uniform(), self.uniform())
    }
}

/// An orthonormal basis around a unit normal (Duff et al. 2017).
#[derive(Debug, Clone, Copy)]
pub struct Frame {
    /// Tangent.
    pub t: Vec3A,
    /// Bitangent.
    pub b: Vec3A,
    /// Normal.
    pub n: Vec3A,
}

impl Frame {
    /// Basis with `n` as z.
    pub fn new(n: Vec3A) -> Self {
        let sign = 1f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        Self { t: vec3a(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x), b: vec3a(b, sign + n.y * n.y * a, -n.y), n }
    }

    /// World -> local.
    pub fn to_local(&self, v: Vec3A) -> Vec3A {
        vec3a(v.dot(self.t), v.dot(self.b), v.dot(self.n))
    }

    /// Local -> world.
    pub fn to_world(&self, v: Vec3A) -> Vec3A {
        self.t * v.x + self.b * v.y + self.n * v.z
    }
}

/// Cosine-weighted hemisphere direction (local, z up); pdf = cos / pi.
pub fn cosine_hemisphere(u: Vec2) -> Vec3A {
    let r = u.x.sqrt();
    let phi = 2.0 * PI * u.y;
    vec3a(r * phi.cos(), r * phi.sin(), (1.0 - u.x).max(0.0).sqrt())
}

/// Uniform direction in the cone of half-angle acos(cos_max) around z.
pub fn uniform_cone(u: Vec2, cos_max: f32) -> Vec3A {
    let cos = 1.0 - u.x * (1.0 - cos_max);
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    vec3a(sin * phi.cos(), sin * phi.sin(), cos)
}

/// Power heuristic (beta = 2) for multiple importance sampling.
pub fn power_heuristic(pdf_a: f32, pdf_b: f32) -> f32 {
    let (a, b) = (pdf_a * pdf_a, pdf_b * pdf_b);
    if a + b > 0.0 { a / (a + b) } else { 0.0 }
}

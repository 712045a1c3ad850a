//! Surface colour: constants, procedural patterns and bitmaps.

use glam::{Vec2, Vec3A};

/// A texture, looked up by surface uv.
#[derive(Debug, Clone)]
pub enum Texture {
    /// One colour.
    Constant(Vec3A),
    /// Checkerboard of two colours, `scale` squares per uv unit.
    Checker {
        /// First colour.
        a: Vec3A,
        /// Second colour.
        b: Vec3A,
        /// Squares per uv unit.
        scale: f32,
    },
    /// Smooth value noise between two colours, `scale` cells per uv unit.
    Noise {
        /// Colour at 0.
        a: Vec3A,
        /// Colour at 1.
        b: Vec3A,
        /// Cells per uv unit.
        scale: f32,
        /// Pattern seed.
        seed: u32,
    },
    /// A bitmap (linear RGB, row-major, top row first), bilinearly filtered, repeating.
    Image {
        /// Width.
        width: usize,
        /// Height.
        height: usize,
        /// Pixels.
        texels: Vec<Vec3A>,
        /// Repeats per uv unit.
        scale: f32,
    },
}

fn hash(x: i32, y: i32, seed: u32) -> f32 {
    let mut h = (x as u32).wrapping_mul(0x8da6b343) ^ (y as u32).wrapping_mul(0xd8163841) ^ seed.wrapping_mul(0xcb1ab31f);
    h ^= h >> 13;
    h = h.wrapping_mul(0x5bd1e995);
    h ^= h >> 15;
    (h & 0xffffff) as f32 / 0xffffff as f32
}

impl Texture {
    /// Colour at `uv`.
    pub fn eval(&self, uv: Vec2) -> Vec3A {
        match self {
            Texture::Constant(c) => *c,
            Texture::Checker { a, b, scale } => {
                let p = (uv * *scale).floor();
                if (p.x as i64 + p.y as i64).rem_euclid(2) == 0 { *a } else { *b }
            }
            Texture::Noise { a, b, scale, seed } => {
                let p = uv * *scale;
                let (i, f) = (p.floor(), p - p.floor());
                let s = f * f * (Vec2::splat(3.0) - 2.0 * f);
                let (x, y) = (i.x as i32, i.y as i32);
                let v0 = hash(x, y, *seed) + (hash(x + 1, y, *seed) - hash(x, y, *seed)) * s.x;
                let v1 = hash(x, y + 1, *seed) + (hash(x + 1, y + 1, *seed) - hash(x, y + 1, *seed)) * s.x;
                a.lerp(*b, v0 + (v1 - v0) * s.y)
            }
            Texture::Image { width, height, texels, scale } => {
                let p = uv * *scale * Vec2::new(*width as f32, *height as f32) - 0.5;
                let (i, f) = (p.floor(), p - p.floor());
                let at = |x: f32, y: f32| {
                    let xi = (x as i64).rem_euclid(*width as i64) as usize;
                    let yi = (y as i64).rem_euclid(*height as i64) as usize;
                    texels[yi * width + xi]
                };
                let top = at(i.x, i.y).lerp(at(i.x + 1.0, i.y), f.x);
                let bottom = at(i.x, i.y + 1.0).lerp(at(i.x + 1.0, i.y + 1.0), f.x);
                top.lerp(bottom, f.y)
            }
        }
    }

    /// A brick-wall bitmap drawn procedurally (exercises the image path without shipping files).
    pub fn bricks(brick: Vec3A, mortar: Vec3A) -> Texture {
        let (width, height) = (64usize, 64usize);
        let texels = (0..width * height)
            .map(|i| {
                let (x, y) = (i % width, i / width);
                let row = y / 16;
                let shift = if row % 2 == 0 { 0 } else { 16 };
                let edge = y % 16 < 2 || (x + shift) % 32 < 2;
                let tint = 0.85 + 0.3 * hash((x + shift) as i32 / 32, row as i32, 7);
                if edge { mortar } else { brick * tint }
            })
            .collect();
        Texture::Image { width, height, texels, scale: 1.0 }
    }
}

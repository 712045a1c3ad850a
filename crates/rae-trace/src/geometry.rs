//! Primitives (triangles, spheres), their intersection and surface data.

use std::f32::consts::PI;

use glam::{Vec2, Vec3A};
use obvhs::aabb::Aabb;
use obvhs::ray::Ray;

/// A primitive's shape.
#[derive(Debug, Clone)]
pub enum Shape {
    /// A triangle with per-vertex uv (and optional shading normals).
    Triangle {
        /// Vertices.
        p: [Vec3A; 3],
        /// Texture coordinates.
        uv: [Vec2; 3],
        /// Shading normals, if smooth.
        n: Option<[Vec3A; 3]>,
    },
    /// A sphere (uv: longitude, latitude).
    Sphere {
        /// Centre.
        center: Vec3A,
        /// Radius.
        radius: f32,
    },
}

/// A shape with its material index.
#[derive(Debug, Clone)]
pub struct Prim {
    /// Geometry, as at frame 0.
    pub shape: Shape,
    /// Index into the scene's materials.
    pub material: u32,
    /// World-space translation per frame (zero for static geometry): at frame f the shape is
    /// where it was at frame 0 moved by `f * velocity` ([`crate::scene::Scene::at_frame`]).
    pub velocity: Vec3A,
}

/// What the integrator needs at a hit.
#[derive(Debug, Clone, Copy)]
pub struct Surface {
    /// Position.
    pub p: Vec3A,
    /// Geometric normal (unit, as modelled).
    pub ng: Vec3A,
    /// Shading normal (unit, same side as `ng`).
    pub ns: Vec3A,
    /// Texture coordinates.
    pub uv: Vec2,
}

impl obvhs::Boundable for Prim {
    fn aabb(&self) -> Aabb {
        match &self.shape {
            Shape::Triangle { p, .. } => Aabb::from_points(p),
            Shape::Sphere { center, radius } => Aabb::new(*center - Vec3A::splat(*radius), *center + Vec3A::splat(*radius)),
        }
    }
}

impl Prim {
    /// This primitive moved by `by`.
    pub fn translated(&self, by: Vec3A) -> Prim {
        let shape = match &self.shape {
            Shape::Triangle { p, uv, n } => Shape::Triangle { p: p.map(|q| q + by), uv: *uv, n: *n },
            Shape::Sphere { center, radius } => Shape::Sphere { center: *center + by, radius: *radius },
        };
        Prim { shape, ..self.clone() }
    }

    /// Distance along `ray` to the nearest hit in (tmin, tmax), or infinity.
    pub fn intersect(&self, ray: &Ray) -> f32 {
        match &self.shape {
            Shape::Triangle { p, .. } => {
                // Moller-Trumbore.
                let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
                let pv = ray.direction.cross(e2);
                let det = e1.dot(pv);
                if det.abs() < 1e-12 {
                    return f32::INFINITY;
                }
                let inv = 1.0 / det;
                let tv = ray.origin - p[0];
                let u = tv.dot(pv) * inv;
                if !(0.0..=1.0).contains(&u) {
                    return f32::INFINITY;
                }
                let qv = tv.cross(e1);
                let v = ray.direction.dot(qv) * inv;
                if v < 0.0 || u + v > 1.0 {
                    return f32::INFINITY;
                }
                let t = e2.dot(qv) * inv;
                if t > ray.tmin && t < ray.tmax { t } else { f32::INFINITY }
            }
            Shape::Sphere { center, radius } => {
                let oc = ray.origin - *center;
                let b = oc.dot(ray.direction);
                let c = oc.length_squared() - radius * radius;
                let disc = b * b - c;
                if disc < 0.0 {
                    return f32::INFINITY;
                }
                let sq = disc.sqrt();
                for t in [-b - sq, -b + sq] {
                    if t > ray.tmin && t < ray.tmax {
                        return t;
                    }
                }
                f32::INFINITY
            }
        }
    }

    /// Surface data at a point on the primitive.
    pub fn surface(&self, p: Vec3A) -> Surface {
        match &self.shape {
            Shape::Triangle { p: v, uv, n } => {
                let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
                let ng = e1.cross(e2).normalize();
                // Barycentrics of p.
                let d = p - v[0];
                let (d00, d01, d11) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
                let (d20, d21) = (d.dot(e1), d.dot(e2));
                let den = d00 * d11 - d01 * d01;
                let b1 = (d11 * d20 - d01 * d21) / den;
                let b2 = (d00 * d21 - d01 * d20) / den;
                let b0 = 1.0 - b1 - b2;
                let uv = uv[0] * b0 + uv[1] * b1 + uv[2] * b2;
                let ns = match n {
                    Some(n) => {
                        let s = (n[0] * b0 + n[1] * b1 + n[2] * b2).normalize();
                        if s.dot(ng) < 0.0 { -s } else { s }
                    }
                    None => ng,
                };
                Surface { p, ng, ns, uv }
            }
            Shape::Sphere { center, .. } => {
                let n = (p - *center).normalize();
                let uv = Vec2::new(0.5 + n.z.atan2(n.x) / (2.0 * PI), n.y.clamp(-1.0, 1.0).acos() / PI);
                Surface { p, ng: n, ns: n, uv }
            }
        }
    }

    /// Surface area.
    pub fn area(&self) -> f32 {
        match &self.shape {
            Shape::Triangle { p, .. } => 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length(),
            Shape::Sphere { radius, .. } => 4.0 * PI * radius * radius,
        }
    }
}

/// Two triangles of a parallelogram `corner`, `corner + u`, `corner + u + v`, `corner + v`
/// (uv 0..1 over it, scaled by `uv_scale`), facing `u x v`.
pub fn quad(corner: Vec3A, u: Vec3A, v: Vec3A, uv_scale: f32, material: u32) -> [Prim; 2] {
    let (a, b, c, d) = (corner, corner + u, corner + u + v, corner + v);
    let (ta, tb, tc, td) = (Vec2::ZERO, Vec2::new(uv_scale, 0.0), Vec2::splat(uv_scale), Vec2::new(0.0, uv_scale));
    [
        Prim { shape: Shape::Triangle { p: [a, b, c], uv: [ta, tb, tc], n: None }, material, velocity: Vec3A::ZERO },
        Prim { shape: Shape::Triangle { p: [a, c, d], uv: [ta, tc, td], n: None }, material, velocity: Vec3A::ZERO },
    ]
}

/// The 12 triangles of a box, rotated by `yaw` radians about +y, outward facing.
pub fn cuboid(center: Vec3A, half: Vec3A, yaw: f32, material: u32) -> Vec<Prim> {
    let rot = glam::Mat3A::from_rotation_y(yaw);
    let ax = [rot * Vec3A::X * half.x, rot * Vec3A::Y * half.y, rot * Vec3A::Z * half.z];
    let mut out = Vec::new();
    for (i, j, k) in [(0usize, 1usize, 2usize), (1, 2, 0), (2, 0, 1)] {
        for s in [1.0f32, -1.0] {
            // Face at +-ax[i], spanned by ax[j], ax[k]; order so the normal points outward.
            let c = center + ax[i] * s;
            let (u, v) = if s > 0.0 { (ax[j] * 2.0, ax[k] * 2.0) } else { (ax[k] * 2.0, ax[j] * 2.0) };
            out.extend(quad(c - u * 0.5 - v * 0.5, u, v, 1.0, material));
        }
    }
    out
}

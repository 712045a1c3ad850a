//! A scene: primitives in a BVH, materials, lights, an environment and a camera animation.

use std::f32::consts::PI;
use std::time::Duration;

use glam::{Vec2, Vec3A, vec3a};
use obvhs::ray::{Ray, RayHit};
use obvhs::{BvhBuildParams, bvh2::Bvh2};

use crate::geometry::{Prim, Shape, Surface};
use crate::material::Material;
use crate::sampling::{Frame, Sampler, uniform_cone};

/// Light arriving from directions that hit nothing.
#[derive(Debug, Clone, Copy)]
pub enum Environment {
    /// No light.
    Black,
    /// A sky: `zenith` overhead blending to `horizon`, `ground` below.
    Sky {
        /// Radiance straight up.
        zenith: Vec3A,
        /// Radiance at the horizon.
        horizon: Vec3A,
        /// Radiance below the horizon.
        ground: Vec3A,
    },
}

impl Environment {
    /// Radiance arriving along `-dir` (i.e. seen looking along `dir`).
    pub fn radiance(&self, dir: Vec3A) -> Vec3A {
        match *self {
            Environment::Black => Vec3A::ZERO,
            Environment::Sky { zenith, horizon, ground } => {
                if dir.y >= 0.0 {
                    horizon.lerp(zenith, dir.y.sqrt())
                } else {
                    ground
                }
            }
        }
    }
}

/// A pinhole camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub position: Vec3A,
    /// Point looked at.
    pub target: Vec3A,
    /// Vertical field of view, degrees.
    pub vfov: f32,
}

impl Camera {
    fn basis(&self) -> (Vec3A, Vec3A, Vec3A) {
        let forward = (self.target - self.position).normalize();
        let right = forward.cross(Vec3A::Y).normalize();
        let up = right.cross(forward);
        (right, up, forward)
    }

    /// Focal length in pixels for an image `height` pixels tall.
    pub fn focal_pixels(&self, height: u32) -> f32 {
        0.5 * height as f32 / (0.5 * self.vfov.to_radians()).tan()
    }

    /// Unit ray direction through image point (x, y) in pixels (x right, y down, pixel centres
    /// at +0.5).
    pub fn direction(&self, x: f32, y: f32, width: u32, height: u32) -> Vec3A {
        let (right, up, forward) = self.basis();
        let f = self.focal_pixels(height);
        (forward * f + right * (x - 0.5 * width as f32) - up * (y - 0.5 * height as f32)).normalize()
    }

    /// Image point (pixels) where `p` appears, if in front of the camera.
    pub fn project(&self, p: Vec3A, width: u32, height: u32) -> Option<Vec2> {
        let (right, up, forward) = self.basis();
        let d = p - self.position;
        let z = d.dot(forward);
        if z <= 1e-6 {
            return None;
        }
        let f = self.focal_pixels(height);
        Some(Vec2::new(0.5 * width as f32 + f * d.dot(right) / z, 0.5 * height as f32 - f * d.dot(up) / z))
    }
}

/// A smooth camera animation: Catmull-Rom through key cameras, evenly spaced over the sequence.
#[derive(Debug, Clone)]
pub struct CameraPath {
    /// Key cameras (at least one).
    pub keys: Vec<Camera>,
}

impl CameraPath {
    /// Camera at `t` in [0, 1] (clamped).
    pub fn at(&self, t: f32) -> Camera {
        let n = self.keys.len();
        if n == 1 {
            return self.keys[0];
        }
        let s = t.clamp(0.0, 1.0) * (n - 1) as f32;
        let i = (s.floor() as usize).min(n - 2);
        let f = s - i as f32;
        let k = |j: isize| self.keys[j.clamp(0, n as isize - 1) as usize];
        let (k0, k1, k2, k3) = (k(i as isize - 1), k(i as isize), k(i as isize + 1), k(i as isize + 2));
        let cr = |a: Vec3A, b: Vec3A, c: Vec3A, d: Vec3A| {
            0.5 * ((2.0 * b) + (c - a) * f + (2.0 * a - 5.0 * b + 4.0 * c - d) * f * f + (3.0 * b - a - 3.0 * c + d) * f * f * f)
        };
        Camera {
            position: cr(k0.position, k1.position, k2.position, k3.position),
            target: cr(k0.target, k1.target, k2.target, k3.target),
            vfov: k1.vfov + (k2.vfov - k1.vfov) * f,
        }
    }

    /// Camera of frame `i` of `frames` (frame -1 is frame 0: no motion before the start).
    pub fn frame(&self, i: i64, frames: u32) -> Camera {
        let t = if frames <= 1 { 0.0 } else { i.max(0) as f32 / (frames - 1) as f32 };
        self.at(t)
    }
}

/// A light sample seen from a shading point.
pub struct LightSample {
    /// Unit direction to the light.
    pub wi: Vec3A,
    /// Distance to the sampled point.
    pub dist: f32,
    /// Emitted radiance toward the shading point.
    pub radiance: Vec3A,
    /// Solid-angle pdf, light selection included.
    pub pdf: f32,
}

/// Everything to render.
pub struct Scene {
    /// Primitives, in BVH order after [`Scene::new`].
    pub prims: Vec<Prim>,
    /// Materials.
    pub materials: Vec<Material>,
    /// Light from missed rays.
    pub environment: Environment,
    /// Camera animation.
    pub camera: CameraPath,
    bvh: Bvh2,
    lights: Vec<u32>,
    light_cdf: Vec<f32>,
    light_pmf: Vec<f32>,
}

impl Scene {
    /// Build the BVH and the light distribution (emitters picked by power).
    pub fn new(prims: Vec<Prim>, materials: Vec<Material>, environment: Environment, camera: CameraPath) -> Self {
        let bvh = obvhs::bvh2::builder::build_bvh2(&prims, BvhBuildParams::medium_build(), &mut Duration::default());
        // Reorder primitives to BVH order so a hit index is a primitive index.
        let prims: Vec<Prim> = bvh.primitive_indices.iter().map(|&i| prims[i as usize].clone()).collect();
        let mut lights = Vec::new();
        let mut power = Vec::new();
        for (i, p) in prims.iter().enumerate() {
            if let Material::Emitter { radiance } = materials[p.material as usize] {
                lights.push(i as u32);
                power.push((radiance.x + radiance.y + radiance.z) * p.area());
            }
        }
        let total: f32 = power.iter().sum();
        let light_pmf: Vec<f32> = power.iter().map(|p| p / total).collect();
        let mut acc = 0.0;
        let light_cdf = light_pmf
            .iter()
            .map(|p| {
                acc += p;
                acc
            })
            .collect();
        Scene { prims, materials, environment, camera, bvh, lights, light_cdf, light_pmf }
    }

    /// The scene at frame `frame`, its moving primitives moved there (`None` if none moves: the
    /// scene is the same at every frame).
    pub fn at_frame(&self, frame: u32) -> Option<Scene> {
        if self.prims.iter().all(|p| p.velocity == Vec3A::ZERO) {
            return None;
        }
        let prims = self.prims.iter().map(|p| p.translated(p.velocity * frame as f32)).collect();
        Some(Scene::new(prims, self.materials.clone(), self.environment, self.camera.clone()))
    }

    /// Closest hit along the ray within (tmin, tmax): (primitive index, distance).
    pub fn intersect(&self, ray: Ray) -> Option<(usize, f32)> {
        let mut hit = RayHit::none();
        // Primitives are in BVH order, so the traversal's index is the primitive's.
        if self.bvh.ray_traverse(ray, &mut hit, |r, id| self.prims[id].intersect(r)) {
            Some((hit.primitive_id as usize, hit.t))
        } else {
            None
        }
    }

    /// Whether anything blocks the segment from `p` along `dir` up to `dist`.
    pub fn occluded(&self, p: Vec3A, dir: Vec3A, dist: f32) -> bool {
        let ray = Ray::new(p, dir, 0.0, dist * (1.0 - 1e-4));
        !self.bvh.ray_traverse_miss(ray, |r, id| self.prims[id].intersect(r))
    }

    /// Material of a primitive.
    pub fn material(&self, prim: usize) -> &Material {
        &self.materials[self.prims[prim].material as usize]
    }

    /// Whether the scene has emitters to sample.
    pub fn has_lights(&self) -> bool {
        !self.lights.is_empty()
    }

    /// Sample a light as seen from `p`.
    pub fn sample_light(&self, p: Vec3A, s: &mut Sampler) -> Option<LightSample> {
        if self.lights.is_empty() {
            return None;
        }
        let u = s.uniform();
        let k = self.light_cdf.partition_point(|&c| c < u).min(self.lights.len() - 1);
        let prim = &self.prims[self.lights[k] as usize];
        let Material::Emitter { radiance } = self.materials[prim.material as usize] else { unreachable!() };
        let pmf = self.light_pmf[k];
        match &prim.shape {
            Shape::Sphere { center, radius } => {
                // Uniform in the cone the sphere subtends.
                let to = *center - p;
                let d2 = to.length_squared();
                if d2 <= radius * radius {
                    return None;
                }
                let cos_max = (1.0 - radius * radius / d2).max(0.0).sqrt();
                let frame = Frame::new(to / d2.sqrt());
                let wi = frame.to_world(uniform_cone(s.uniform2(), cos_max));
                let ray = Ray::new(p, wi, 0.0, f32::INFINITY);
                let dist = prim.intersect(&ray);
                if !dist.is_finite() {
                    return None;
                }
                Some(LightSample { wi, dist, radiance, pdf: pmf / (2.0 * PI * (1.0 - cos_max)).max(1e-12) })
            }
            Shape::Triangle { p: v, .. } => {
                let (mut a, mut b) = (s.uniform(), s.uniform());
                if a + b > 1.0 {
                    (a, b) = (1.0 - a, 1.0 - b);
                }
                let q = v[0] + (v[1] - v[0]) * a + (v[2] - v[0]) * b;
                let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
                let to = q - p;
                let dist = to.length();
                let wi = to / dist;
                let cos_l = -wi.dot(n);
                if cos_l <= 0.0 {
                    return None; // back of a one-sided emitter
                }
                Some(LightSample { wi, dist, radiance, pdf: pmf * dist * dist / (cos_l * prim.area()) })
            }
        }
    }

    /// Solid-angle pdf with which [`Scene::sample_light`] from `p` picks the point `q` on light
    /// primitive `prim` (for MIS when a BSDF sample hits an emitter).
    pub fn light_pdf(&self, p: Vec3A, prim: usize, q: &Surface) -> f32 {
        let Some(k) = self.lights.iter().position(|&l| l as usize == prim) else { return 0.0 };
        let pmf = self.light_pmf[k];
        match &self.prims[prim].shape {
            Shape::Sphere { center, radius } => {
                let d2 = (*center - p).length_squared();
                if d2 <= radius * radius {
                    return 0.0;
                }
                let cos_max = (1.0 - radius * radius / d2).max(0.0).sqrt();
                pmf / (2.0 * PI * (1.0 - cos_max)).max(1e-12)
            }
            Shape::Triangle { .. } => {
                let to = q.p - p;
                let d2 = to.length_squared();
                let cos_l = (-to.normalize().dot(q.ng)).max(0.0);
                if cos_l <= 0.0 { 0.0 } else { pmf * d2 / (cos_l * self.prims[prim].area()) }
            }
        }
    }
}

/// Shorthand for a vector.
pub fn v(x: f32, y: f32, z: f32) -> Vec3A {
    vec3a(x, y, z)
}

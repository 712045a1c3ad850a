//! The integrator (unidirectional path tracing with next-event estimation, multiple importance
//! sampling and Russian roulette) and the per-frame buffers it fills.

use glam::{Vec2, Vec3A};
use obvhs::ray::Ray;
use rayon::prelude::*;

use crate::material::Material;
use crate::sampling::{Frame, Sampler, power_heuristic};
use crate::scene::Scene;

/// How to render a sequence.
#[derive(Debug, Clone, Copy)]
pub struct Settings {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Samples per pixel of the noisy image.
    pub spp: u32,
    /// Samples per pixel of the reference (0: none).
    pub ref_spp: u32,
    /// Seed of every random number.
    pub seed: u64,
    /// Longest path, in bounces.
    pub max_depth: u32,
    /// Where the auxiliary buffers come from.
    pub aux: Aux,
}

/// Where the auxiliary buffers (albedo, normal, depth, roughness) come from. Renderers differ:
/// a rasteriser's G-buffer is the pixel centre's surface, an offline path tracer averages its
/// samples' surfaces; a denoiser trained on both serves either.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Aux {
    /// The ray through the pixel centre, at its first surface: noise-free and aliased.
    #[default]
    Centre,
    /// The noisy color's own jittered rays, averaged, each recorded at its first surface that
    /// is not near-specular (mirrors, smooth glass and polished metal are followed, their
    /// tint multiplied into the albedo), as Cycles writes its Denoising passes: antialiased,
    /// and noisy at edges and through glass. Normals are then shorter than 1 at silhouettes.
    Samples,
}

/// GGX roughness below which the [`Aux::Samples`] buffers look through a surface to what it
/// reflects or transmits (alpha 0.075).
pub const FEATURE_SPECULAR: f32 = 0.274;

/// Most near-specular surfaces an [`Aux::Samples`] ray follows before it records where it is.
const FEATURE_BOUNCES: u32 = 8;

/// The auxiliary values one camera ray sees ([`Aux::Samples`]).
#[derive(Debug, Clone, Copy, Default)]
struct Features {
    albedo: Vec3A,
    normal: Vec3A,
    /// Distance to the first surface, and 1 where there is one (0 at a miss).
    depth: f32,
    hit: f32,
    roughness: f32,
}

impl std::ops::AddAssign for Features {
    fn add_assign(&mut self, o: Self) {
        self.albedo += o.albedo;
        self.normal += o.normal;
        self.depth += o.depth;
        self.hit += o.hit;
        self.roughness += o.roughness;
    }
}

/// Traces a camera ray for [`Aux::Samples`]: through near-specular surfaces (drawing from `s`
/// where glass reflects or refracts) to the first one that is not, or to the sky, which counts
/// as albedo 1 (the engine's convention at a miss).
fn features(scene: &Scene, origin: Vec3A, dir: Vec3A, s: &mut Sampler) -> Features {
    let mut f = Features::default();
    let mut tint = Vec3A::ONE;
    let (mut o, mut d) = (origin, dir);
    for bounce in 0..=FEATURE_BOUNCES {
        let Some((prim, t)) = scene.intersect(Ray::new(o, d, 0.0, f32::INFINITY)) else {
            if bounce > 0 {
                f.albedo = tint;
            }
            return f;
        };
        let surf = scene.prims[prim].surface(o + d * t);
        let mat = scene.material(prim);
        let dielectric = matches!(mat, Material::Dielectric { .. });
        let n = if surf.ns.dot(d) > 0.0 && !dielectric { -surf.ns } else { surf.ns };
        if bounce == 0 {
            (f.depth, f.hit, f.normal, f.roughness) = (t, 1.0, n, mat.roughness());
        }
        let specular = match mat {
            Material::Conductor { roughness, .. } | Material::Dielectric { roughness, .. } => *roughness < FEATURE_SPECULAR,
            _ => false,
        };
        let next = if specular && bounce < FEATURE_BOUNCES {
            let frame = Frame::new(n);
            mat.sample(frame.to_local(-d), surf.uv, s).map(|bs| frame.to_world(bs.wi).normalize())
        } else {
            None
        };
        match next {
            Some(wi) => {
                tint *= mat.albedo(surf.uv);
                o = offset(surf.p, surf.ng, wi);
                d = wi;
            }
            None => {
                f.albedo = tint * mat.albedo(surf.uv);
                f.normal = n;
                f.roughness = mat.roughness();
                return f;
            }
        }
    }
    f
}

/// One frame's buffers, row-major, top row first (the layout rae-core reads).
#[derive(Debug, Clone, PartialEq)]
pub struct FrameBuffers {
    /// Noisy radiance, RGB.
    pub color: Vec<f32>,
    /// Reference radiance, RGB (empty when not rendered).
    pub reference: Vec<f32>,
    /// First-hit albedo, RGB.
    pub albedo: Vec<f32>,
    /// First-hit shading normal, world space, facing the camera.
    pub normal: Vec<f32>,
    /// Distance along the primary ray; +inf where it misses.
    pub depth: Vec<f32>,
    /// First-hit roughness (0 where the ray misses).
    pub roughness: Vec<f32>,
    /// Screen-space motion to the previous frame, pixels (x right, y down): where this pixel's
    /// surface point was in the previous frame, minus where it is now.
    pub motion: Vec<f32>,
}

const RAY_EPS: f32 = 1e-4;

fn offset(p: Vec3A, n: Vec3A, toward: Vec3A) -> Vec3A {
    let s = if n.dot(toward) >= 0.0 { 1.0 } else { -1.0 };
    p + n * (s * RAY_EPS * p.abs().max_element().max(1.0))
}

/// Radiance along a camera ray.
pub fn radiance(scene: &Scene, origin: Vec3A, dir: Vec3A, max_depth: u32, s: &mut Sampler) -> Vec3A {
    let mut l = Vec3A::ZERO;
    let mut beta = Vec3A::ONE;
    let (mut o, mut d) = (origin, dir);
    // MIS state of the previous bounce: its BSDF pdf, whether it was specular, where it was.
    let (mut prev_pdf, mut prev_specular, mut prev_p) = (0.0f32, true, origin);
    for depth in 0..max_depth {
        let Some((prim, t)) = scene.intersect(Ray::new(o, d, 0.0, f32::INFINITY)) else {
            l += beta * scene.environment.radiance(d);
            break;
        };
        let surf = scene.prims[prim].surface(o + d * t);
        let mat = scene.material(prim);
        let wo_world = -d;
        if let Material::Emitter { radiance } = mat {
            // One-sided emitters light their front.
            if surf.ng.dot(wo_world) > 0.0 {
                let w = if prev_specular || depth == 0 { 1.0 } else { power_heuristic(prev_pdf, scene.light_pdf(prev_p, prim, &surf)) };
                l += beta * *radiance * w;
            }
            break;
        }
        // Shade with normals facing the viewer, except for dielectrics (inside/outside matters).
        let dielectric = matches!(mat, Material::Dielectric { .. });
        let (ng, ns) = if !dielectric && surf.ng.dot(wo_world) < 0.0 { (-surf.ng, -surf.ns) } else { (surf.ng, surf.ns) };
        let frame = Frame::new(ns);
        let wo = frame.to_local(wo_world);
        if !dielectric && wo.z <= 0.0 {
            break;
        }

        // Next-event estimation.
        if mat.is_smooth_free() && scene.has_lights() {
            let p = offset(surf.p, ng, ng);
            if let Some(ls) = scene.sample_light(p, s) {
                let wi = frame.to_local(ls.wi);
                let (f_cos, bsdf_pdf) = mat.eval(wo, wi, surf.uv);
                if f_cos != Vec3A::ZERO && ls.wi.dot(ng) > 0.0 && !scene.occluded(p, ls.wi, ls.dist) {
                    l += beta * f_cos * ls.radiance * (power_heuristic(ls.pdf, bsdf_pdf) / ls.pdf);
                }
            }
        }

        // Continue the path by sampling the BSDF.
        let Some(bs) = mat.sample(wo, surf.uv, s) else { break };
        beta *= bs.weight;
        let wi_world = frame.to_world(bs.wi);
        o = offset(surf.p, ng, wi_world);
        d = wi_world.normalize();
        (prev_pdf, prev_specular, prev_p) = (bs.pdf, bs.specular, o);

        // Russian roulette after a few bounces.
        if depth >= 3 {
            let q = beta.max_element().clamp(0.05, 0.95);
            if s.uniform() >= q {
                break;
            }
            beta /= q;
        }
        if !beta.is_finite() {
            break;
        }
    }
    l
}

/// Render frame `frame` of `frames`: noisy radiance, reference and auxiliary buffers.
pub fn render_frame(scene: &Scene, frame: u32, frames: u32, st: &Settings) -> FrameBuffers {
    let (w, h) = (st.width, st.height);
    // Moving primitives where they are at this frame.
    let moved = scene.at_frame(frame);
    let scene = moved.as_ref().unwrap_or(scene);
    let cam = scene.camera.frame(frame as i64, frames);
    let prev = scene.camera.frame(frame as i64 - 1, frames);
    let pixels: Vec<_> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let (px, py) = (x as f32 + 0.5, y as f32 + 0.5);
            // Auxiliary buffers from the ray through the pixel centre.
            let dir = cam.direction(px, py, w, h);
            let mut aux = ([0.0f32; 3], [0.0f32; 3], f32::INFINITY, 0.0f32, [0.0f32; 2]);
            let far = cam.position + dir * 1e6;
            let mut seen = far;
            if let Some((prim, t)) = scene.intersect(Ray::new(cam.position, dir, 0.0, f32::INFINITY)) {
                let surf = scene.prims[prim].surface(cam.position + dir * t);
                let mat = scene.material(prim);
                let n = if surf.ns.dot(dir) > 0.0 && !matches!(mat, Material::Dielectric { .. }) { -surf.ns } else { surf.ns };
                aux.0 = mat.albedo(surf.uv).to_array();
                aux.1 = n.to_array();
                aux.2 = t;
                aux.3 = mat.roughness();
                // Where this surface point was on the previous frame: a moving primitive was one
                // step of its velocity back.
                seen = surf.p - scene.prims[prim].velocity;
            }
            if let Some(q) = prev.project(seen, w, h) {
                aux.4 = [q.x - px, q.y - py];
            }
            // Averages `n` jittered paths of stream `pass`; `feat` also sums each one's
            // auxiliary values (traced from a stream of their own: the color's noise is the
            // same whichever way the auxiliary buffers are made).
            let sample = |pass: u32, n: u32, mut feat: Option<&mut Features>| -> [f32; 3] {
                if n == 0 {
                    return [0.0; 3];
                }
                let mut s = Sampler::new(st.seed, frame, i, pass);
                let mut fs = Sampler::new(st.seed, frame, i, 2);
                let mut acc = Vec3A::ZERO;
                for _ in 0..n {
                    let j: Vec2 = s.uniform2();
                    let d = cam.direction(x as f32 + j.x, y as f32 + j.y, w, h);
                    if let Some(f) = feat.as_deref_mut() {
                        *f += features(scene, cam.position, d, &mut fs);
                    }
                    acc += radiance(scene, cam.position, d, st.max_depth, &mut s);
                }
                (acc / n as f32).to_array()
            };
            let sampled = st.aux == Aux::Samples && st.spp > 0;
            let mut feat = Features::default();
            let color = sample(0, st.spp, sampled.then_some(&mut feat));
            if sampled {
                // Albedo and normal over all samples (a miss adds zero), depth and roughness over
                // those that hit; a pixel none of whose samples hit is a miss, as at the centre.
                let n = st.spp as f32;
                aux.0 = (feat.albedo / n).to_array();
                aux.1 = (feat.normal / n).to_array();
                (aux.2, aux.3) = if feat.hit > 0.0 { (feat.depth / feat.hit, feat.roughness / feat.hit) } else { (f32::INFINITY, 0.0) };
            }
            (color, sample(1, st.ref_spp, None), aux)
        })
        .collect();
    let mut fb = FrameBuffers {
        color: Vec::with_capacity(pixels.len() * 3),
        reference: Vec::new(),
        albedo: Vec::with_capacity(pixels.len() * 3),
        normal: Vec::with_capacity(pixels.len() * 3),
        depth: Vec::with_capacity(pixels.len()),
        roughness: Vec::with_capacity(pixels.len()),
        motion: Vec::with_capacity(pixels.len() * 2),
    };
    for (c, r, aux) in pixels {
        fb.color.extend(c);
        if st.ref_spp > 0 {
            fb.reference.extend(r);
        }
        fb.albedo.extend(aux.0);
        fb.normal.extend(aux.1);
        fb.depth.push(aux.2);
        fb.roughness.push(aux.3);
        fb.motion.extend(aux.4);
    }
    fb
}

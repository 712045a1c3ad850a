//! Materials and their BSDFs: Lambertian diffuse, rough conductor (GGX), rough dielectric
//! (GGX, reflection and refraction), plastic (diffuse base under a GGX coat), and emitters.
//!
//! Directions are in the local shading frame (normal = +z), `wo` toward the viewer. Weights are
//! `f * cos / pdf`. Dielectrics are sampled only (no `eval`): they act as specular for next-event
//! estimation and multiple importance sampling.

use std::f32::consts::PI;

use glam::{Vec2, Vec3A, vec3a};

use crate::sampling::{Sampler, cosine_hemisphere};
use crate::texture::Texture;

/// Roughness below which a lobe is treated as a perfect mirror or smooth glass.
pub const SMOOTH: f32 = 0.02;

/// A surface material.
#[derive(Debug, Clone)]
pub enum Material {
    /// Lambertian.
    Diffuse {
        /// Reflectance.
        albedo: Texture,
    },
    /// Metal with Schlick Fresnel from `f0` and GGX roughness.
    Conductor {
        /// Reflectance at normal incidence (textured: tarnish, brushed patterns).
        f0: Texture,
        /// Perceptual roughness (alpha = roughness^2).
        roughness: f32,
    },
    /// Glass: GGX rough or smooth dielectric.
    Dielectric {
        /// Index of refraction.
        ior: f32,
        /// Perceptual roughness.
        roughness: f32,
    },
    /// Diffuse base under a dielectric GGX coat (F0 = 0.04).
    Plastic {
        /// Base reflectance.
        albedo: Texture,
        /// Coat roughness.
        roughness: f32,
    },
    /// A light: emits radiance from its front side and reflects nothing.
    Emitter {
        /// Emitted radiance.
        radiance: Vec3A,
    },
}

/// A sampled direction.
#[derive(Debug, Clone, Copy)]
pub struct BsdfSample {
    /// Incoming direction (local).
    pub wi: Vec3A,
    /// f * |cos| / pdf.
    pub weight: Vec3A,
    /// Solid-angle pdf (0 for specular).
    pub pdf: f32,
    /// Sampled from a delta-like lobe: no MIS with light sampling.
    pub specular: bool,
}

fn alpha(roughness: f32) -> f32 {
    (roughness * roughness).max(1e-4)
}

fn ggx_d(h: Vec3A, a: f32) -> f32 {
    let a2 = a * a;
    let c = h.z * h.z * (a2 - 1.0) + 1.0;
    a2 / (PI * c * c)
}

fn ggx_lambda(w: Vec3A, a: f32) -> f32 {
    let c2 = w.z * w.z;
    if c2 <= 0.0 {
        return 0.0;
    }
    let t2 = (1.0 - c2).max(0.0) / c2;
    0.5 * (-1.0 + (1.0 + a * a * t2).sqrt())
}

fn ggx_g1(w: Vec3A, a: f32) -> f32 {
    1.0 / (1.0 + ggx_lambda(w, a))
}

fn ggx_g2(wo: Vec3A, wi: Vec3A, a: f32) -> f32 {
    1.0 / (1.0 + ggx_lambda(wo, a) + ggx_lambda(wi, a))
}

/// Visible-normal sample of GGX (Heitz 2018) for `wo` in the upper hemisphere.
fn sample_vndf(wo: Vec3A, a: f32, u: Vec2) -> Vec3A {
    let vh = vec3a(a * wo.x, a * wo.y, wo.z).normalize();
    let len2 = vh.x * vh.x + vh.y * vh.y;
    let t1 = if len2 > 0.0 { vec3a(-vh.y, vh.x, 0.0) / len2.sqrt() } else { vec3a(1.0, 0.0, 0.0) };
    let t2 = vh.cross(t1);
    let r = u.x.sqrt();
    let phi = 2.0 * PI * u.y;
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
    let nh = t1 * p1 + t2 * p2 + vh * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    vec3a(a * nh.x, a * nh.y, nh.z.max(1e-6)).normalize()
}

fn reflect(w: Vec3A, h: Vec3A) -> Vec3A {
    2.0 * w.dot(h) * h - w
}

fn schlick(f0: Vec3A, cos: f32) -> Vec3A {
    f0 + (Vec3A::ONE - f0) * (1.0 - cos.clamp(0.0, 1.0)).powi(5)
}

/// Unpolarised Fresnel reflectance of a dielectric; `eta` = n_incident / n_transmitted.
fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (rs * rs + rp * rp)
}

/// GGX specular reflection: (f * cos, pdf) for a coat or metal with Fresnel `f`.
fn ggx_reflect_eval(wo: Vec3A, wi: Vec3A, a: f32, fresnel: impl Fn(f32) -> Vec3A) -> (Vec3A, f32) {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return (Vec3A::ZERO, 0.0);
    }
    let h = (wo + wi).normalize();
    let d = ggx_d(h, a);
    let f_cos = fresnel(wo.dot(h)) * d * ggx_g2(wo, wi, a) / (4.0 * wo.z);
    let pdf = ggx_g1(wo, a) * d / (4.0 * wo.z);
    (f_cos, pdf)
}

const COAT_F0: f32 = 0.04;

fn plastic_spec_probability(roughness: f32) -> f32 {
    0.5 - 0.4 * roughness.clamp(0.0, 1.0)
}

impl Material {
    /// Whether next-event estimation can use this material (it has a non-delta `eval`).
    pub fn is_smooth_free(&self) -> bool {
        match self {
            Material::Diffuse { .. } | Material::Plastic { .. } => true,
            Material::Conductor { roughness, .. } => *roughness >= SMOOTH,
            Material::Dielectric { .. } | Material::Emitter { .. } => false,
        }
    }

    /// Albedo written to the auxiliary buffer.
    pub fn albedo(&self, uv: Vec2) -> Vec3A {
        match self {
            Material::Diffuse { albedo } | Material::Plastic { albedo, .. } => albedo.eval(uv),
            Material::Conductor { f0, .. } => f0.eval(uv),
            Material::Dielectric { .. } | Material::Emitter { .. } => Vec3A::ONE,
        }
    }

    /// Roughness written to the auxiliary buffer (diffuse and emitters: 1).
    pub fn roughness(&self) -> f32 {
        match self {
            Material::Conductor { roughness, .. } | Material::Dielectric { roughness, .. } | Material::Plastic { roughness, .. } => {
                *roughness
            }
            Material::Diffuse { .. } | Material::Emitter { .. } => 1.0,
        }
    }

    /// (f * cos(wi), pdf of sampling wi) for a non-delta material; `wo.z > 0`.
    pub fn eval(&self, wo: Vec3A, wi: Vec3A, uv: Vec2) -> (Vec3A, f32) {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return (Vec3A::ZERO, 0.0);
        }
        match self {
            Material::Diffuse { albedo } => (albedo.eval(uv) * wi.z / PI, wi.z / PI),
            Material::Conductor { f0, roughness } => {
                let f0 = f0.eval(uv);
                ggx_reflect_eval(wo, wi, alpha(*roughness), |c| schlick(f0, c))
            }
            Material::Plastic { albedo, roughness } => {
                let p = plastic_spec_probability(*roughness);
                let (spec, spec_pdf) = ggx_reflect_eval(wo, wi, alpha(*roughness), |c| Vec3A::splat(schlick(Vec3A::splat(COAT_F0), c).x));
                let through = (1.0 - schlick(Vec3A::splat(COAT_F0), wo.z).x) * (1.0 - schlick(Vec3A::splat(COAT_F0), wi.z).x);
                let diffuse = albedo.eval(uv) * through * wi.z / PI;
                (spec + diffuse, p * spec_pdf + (1.0 - p) * wi.z / PI)
            }
            Material::Dielectric { .. } | Material::Emitter { .. } => (Vec3A::ZERO, 0.0),
        }
    }

    /// Sample an incoming direction. `wo` may be below the surface only for dielectrics.
    pub fn sample(&self, wo: Vec3A, uv: Vec2, s: &mut Sampler) -> Option<BsdfSample> {
        match self {
            Material::Emitter { .. } => None,
            Material::Diffuse { albedo } => {
                let wi = cosine_hemisphere(s.uniform2());
                (wi.z > 0.0).then(|| BsdfSample { wi, weight: albedo.eval(uv), pdf: wi.z / PI, specular: false })
            }
            Material::Conductor { f0, roughness } => {
                let f0 = f0.eval(uv);
                if *roughness < SMOOTH {
                    let wi = vec3a(-wo.x, -wo.y, wo.z);
                    return Some(BsdfSample { wi, weight: schlick(f0, wo.z), pdf: 0.0, specular: true });
                }
                let a = alpha(*roughness);
                let h = sample_vndf(wo, a, s.uniform2());
                let wi = reflect(wo, h);
                if wi.z <= 0.0 {
                    return None;
                }
                let (f_cos, pdf) = ggx_reflect_eval(wo, wi, a, |c| schlick(f0, c));
                (pdf > 0.0).then(|| BsdfSample { wi, weight: f_cos / pdf, pdf, specular: false })
            }
            Material::Plastic { roughness, .. } => {
                let p = plastic_spec_probability(*roughness);
                let wi = if s.uniform() < p {
                    reflect(wo, sample_vndf(wo, alpha(*roughness), s.uniform2()))
                } else {
                    cosine_hemisphere(s.uniform2())
                };
                let (f_cos, pdf) = self.eval(wo, wi, uv);
                (pdf > 0.0).then(|| BsdfSample { wi, weight: f_cos / pdf, pdf, specular: false })
            }
            Material::Dielectric { ior, roughness } => {
                // Work on the side wo is on: entering when wo.z > 0.
                let entering = wo.z > 0.0;
                let flip = if entering { 1.0 } else { -1.0 };
                let wo_up = wo * flip;
                let eta = if entering { 1.0 / ior } else { *ior };
                let (h, g1_weight) = if *roughness < SMOOTH {
                    (Vec3A::Z, None)
                } else {
                    (sample_vndf(wo_up, alpha(*roughness), s.uniform2()), Some(alpha(*roughness)))
                };
                let cos_i = wo_up.dot(h);
                if cos_i <= 0.0 {
                    return None;
                }
                let fr = fresnel_dielectric(cos_i, eta);
                let reflect_chosen = s.uniform() < fr;
                let wi_up = if reflect_chosen {
                    reflect(wo_up, h)
                } else {
                    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
                    -wo_up * eta + h * (eta * cos_i - (1.0 - sin2_t).max(0.0).sqrt())
                };
                // Reflection must stay above, refraction below the macro surface.
                if reflect_chosen != (wi_up.z > 0.0) {
                    return None;
                }
                let weight = g1_weight.map_or(1.0, |a| ggx_g1(wi_up * if wi_up.z < 0.0 { -1.0 } else { 1.0 }, a));
                Some(BsdfSample { wi: wi_up * flip, weight: Vec3A::splat(weight), pdf: 0.0, specular: true })
            }
        }
    }
}

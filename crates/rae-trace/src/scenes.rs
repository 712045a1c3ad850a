//! The fixed scenes and the seeded procedural generator.

use glam::Vec3A;
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg32;

use crate::geometry::{Prim, Shape, cuboid, quad};
use crate::material::Material;
use crate::scene::{Camera, CameraPath, Environment, Scene, v};
use crate::texture::Texture;

/// Names accepted by [`by_name`].
pub const NAMES: &[&str] = &["cornell", "glossy", "firefly", "cornell-moving", "glossy-moving"];

/// A fixed scene by name.
pub fn by_name(name: &str) -> Option<Scene> {
    match name {
        "cornell" => Some(cornell()),
        "glossy" => Some(glossy()),
        "firefly" => Some(firefly()),
        "cornell-moving" => Some(cornell_moving()),
        "glossy-moving" => Some(glossy_moving()),
        _ => None,
    }
}

struct Builder {
    prims: Vec<Prim>,
    materials: Vec<Material>,
}

impl Builder {
    fn new() -> Self {
        Self { prims: Vec::new(), materials: Vec::new() }
    }

    fn material(&mut self, m: Material) -> u32 {
        self.materials.push(m);
        self.materials.len() as u32 - 1
    }

    fn sphere(&mut self, center: Vec3A, radius: f32, m: u32) {
        self.moving_sphere(center, radius, m, Vec3A::ZERO);
    }

    /// A sphere at `center` on frame 0 that moves by `velocity` each frame.
    fn moving_sphere(&mut self, center: Vec3A, radius: f32, m: u32, velocity: Vec3A) {
        self.prims.push(Prim { shape: Shape::Sphere { center, radius }, material: m, velocity });
    }

    /// Primitives that move together by `velocity` each frame (a box's faces).
    fn moving(&mut self, prims: impl IntoIterator<Item = Prim>, velocity: Vec3A) {
        self.prims.extend(prims.into_iter().map(|p| Prim { velocity, ..p }));
    }

    fn finish(self, env: Environment, keys: Vec<Camera>) -> Scene {
        Scene::new(self.prims, self.materials, env, CameraPath { keys })
    }
}

fn diffuse(c: Vec3A) -> Material {
    Material::Diffuse { albedo: Texture::Constant(c) }
}

/// The Cornell box: red and green walls, a ceiling light, a tall box and a glass sphere; the
/// camera dollies in slowly.
pub fn cornell() -> Scene {
    let mut b = Builder::new();
    let white = b.material(diffuse(v(0.73, 0.73, 0.73)));
    let red = b.material(diffuse(v(0.65, 0.05, 0.05)));
    let green = b.material(diffuse(v(0.12, 0.45, 0.15)));
    let light = b.material(Material::Emitter { radiance: v(17.0, 12.0, 4.0) });
    let glass = b.material(Material::Dielectric { ior: 1.5, roughness: 0.0 });
    // Room [-1,1] x [0,2] x [-1,1], open toward +z (the camera).
    b.prims.extend(quad(v(-1.0, 0.0, 1.0), v(2.0, 0.0, 0.0), v(0.0, 0.0, -2.0), 1.0, white)); // floor, up
    b.prims.extend(quad(v(-1.0, 2.0, -1.0), v(2.0, 0.0, 0.0), v(0.0, 0.0, 2.0), 1.0, white)); // ceiling, down
    b.prims.extend(quad(v(-1.0, 0.0, -1.0), v(2.0, 0.0, 0.0), v(0.0, 2.0, 0.0), 1.0, white)); // back, +z
    b.prims.extend(quad(v(-1.0, 0.0, 1.0), v(0.0, 0.0, -2.0), v(0.0, 2.0, 0.0), 1.0, red)); // left, +x
    b.prims.extend(quad(v(1.0, 0.0, -1.0), v(0.0, 0.0, 2.0), v(0.0, 2.0, 0.0), 1.0, green)); // right, -x
    b.prims.extend(quad(v(-0.25, 1.999, -0.25), v(0.5, 0.0, 0.0), v(0.0, 0.0, 0.5), 1.0, light)); // light, down
    b.prims.extend(cuboid(v(-0.35, 0.6, -0.35), v(0.28, 0.6, 0.28), 0.3, white));
    b.sphere(v(0.4, 0.35, 0.3), 0.35, glass);
    let cam = |z: f32, x: f32| Camera { position: v(x, 1.0, z), target: v(0.0, 0.9, 0.0), vfov: 40.0 };
    b.finish(Environment::Black, vec![cam(3.9, -0.15), cam(3.6, 0.0), cam(3.4, 0.15)])
}

/// Glossy spheres of increasing roughness, metal and plastic, on a textured floor under a sky
/// and an area light; the camera orbits.
pub fn glossy() -> Scene {
    let mut b = Builder::new();
    let floor = b.material(Material::Plastic {
        albedo: Texture::Checker { a: v(0.8, 0.8, 0.8), b: v(0.15, 0.15, 0.2), scale: 4.0 },
        roughness: 0.4,
    });
    let wall = b.material(Material::Diffuse { albedo: Texture::bricks(v(0.6, 0.25, 0.15), v(0.75, 0.75, 0.7)) });
    b.prims.extend(quad(v(-6.0, 0.0, 6.0), v(12.0, 0.0, 0.0), v(0.0, 0.0, -12.0), 3.0, floor));
    b.prims.extend(quad(v(-6.0, 0.0, -3.0), v(12.0, 0.0, 0.0), v(0.0, 4.0, 0.0), 3.0, wall));
    for i in 0..5 {
        let r = [0.03, 0.15, 0.3, 0.5, 0.8][i];
        let x = -2.0 + i as f32;
        let metal = b.material(Material::Conductor { f0: Texture::Constant(v(0.95, 0.64, 0.54)), roughness: r });
        let plastic = b.material(Material::Plastic { albedo: Texture::Constant(v(0.1, 0.3, 0.8)), roughness: r });
        b.sphere(v(x, 0.4, 0.0), 0.4, metal);
        b.sphere(v(x, 0.3, 1.2), 0.3, plastic);
    }
    let glass = b.material(Material::Dielectric { ior: 1.5, roughness: 0.1 });
    b.sphere(v(0.5, 0.5, -1.6), 0.5, glass);
    let light = b.material(Material::Emitter { radiance: v(12.0, 12.0, 11.0) });
    b.prims.extend(quad(v(-1.0, 4.0, -1.0), v(2.0, 0.0, 0.0), v(0.0, 0.0, 2.0), 1.0, light)); // facing down
    let sky = Environment::Sky { zenith: v(0.3, 0.45, 0.9), horizon: v(0.9, 0.9, 1.0), ground: v(0.1, 0.1, 0.1) };
    let keys = (0..4)
        .map(|k| {
            let a = -0.5 + 0.33 * k as f32;
            Camera { position: v(5.5 * a.sin(), 2.0, 5.5 * a.cos()), target: v(0.0, 0.4, 0.0), vfov: 38.0 }
        })
        .collect();
    b.finish(sky, keys)
}

/// The Cornell box with a textured ball rolling across the floor in front of the tall box and
/// a small glossy sphere dropping past the back wall: moving objects over a moving camera, and
/// the background each uncovers.
pub fn cornell_moving() -> Scene {
    let mut b = Builder::new();
    let white = b.material(diffuse(v(0.73, 0.73, 0.73)));
    let red = b.material(diffuse(v(0.65, 0.05, 0.05)));
    let green = b.material(diffuse(v(0.12, 0.45, 0.15)));
    let light = b.material(Material::Emitter { radiance: v(17.0, 12.0, 4.0) });
    let ball = b.material(Material::Diffuse { albedo: Texture::Checker { a: v(0.8, 0.5, 0.1), b: v(0.1, 0.2, 0.6), scale: 6.0 } });
    let gold = b.material(Material::Conductor { f0: Texture::Constant(v(0.95, 0.64, 0.54)), roughness: 0.2 });
    b.prims.extend(quad(v(-1.0, 0.0, 1.0), v(2.0, 0.0, 0.0), v(0.0, 0.0, -2.0), 1.0, white));
    b.prims.extend(quad(v(-1.0, 2.0, -1.0), v(2.0, 0.0, 0.0), v(0.0, 0.0, 2.0), 1.0, white));
    b.prims.extend(quad(v(-1.0, 0.0, -1.0), v(2.0, 0.0, 0.0), v(0.0, 2.0, 0.0), 1.0, white));
    b.prims.extend(quad(v(-1.0, 0.0, 1.0), v(0.0, 0.0, -2.0), v(0.0, 2.0, 0.0), 1.0, red));
    b.prims.extend(quad(v(1.0, 0.0, -1.0), v(0.0, 0.0, 2.0), v(0.0, 2.0, 0.0), 1.0, green));
    b.prims.extend(quad(v(-0.25, 1.999, -0.25), v(0.5, 0.0, 0.0), v(0.0, 0.0, 0.5), 1.0, light));
    b.prims.extend(cuboid(v(-0.35, 0.6, -0.35), v(0.28, 0.6, 0.28), 0.3, white));
    b.moving_sphere(v(-0.7, 0.25, 0.3), 0.25, ball, v(0.09, 0.0, 0.0));
    b.moving_sphere(v(0.5, 1.6, -0.6), 0.15, gold, v(0.0, -0.08, 0.0));
    let cam = |z: f32, x: f32| Camera { position: v(x, 1.0, z), target: v(0.0, 0.9, 0.0), vfov: 40.0 };
    b.finish(Environment::Black, vec![cam(3.9, -0.15), cam(3.6, 0.0), cam(3.4, 0.15)])
}

/// The glossy scene with a mirror-like sphere crossing in front of the row of spheres and a
/// plastic one crossing back behind it, under the orbiting camera.
pub fn glossy_moving() -> Scene {
    let mut scene = glossy();
    let mut prims = std::mem::take(&mut scene.prims);
    let mut materials = std::mem::take(&mut scene.materials);
    materials.push(Material::Conductor { f0: Texture::Constant(v(0.9, 0.9, 0.9)), roughness: 0.05 });
    materials.push(Material::Plastic { albedo: Texture::Constant(v(0.8, 0.15, 0.1)), roughness: 0.3 });
    let (mirror, red) = (materials.len() as u32 - 2, materials.len() as u32 - 1);
    prims.push(Prim { shape: Shape::Sphere { center: v(-2.6, 0.35, 2.2), radius: 0.35 }, material: mirror, velocity: v(0.3, 0.0, 0.0) });
    prims.push(Prim { shape: Shape::Sphere { center: v(2.4, 0.45, -0.9), radius: 0.45 }, material: red, velocity: v(-0.25, 0.0, 0.05) });
    Scene::new(prims, materials, scene.environment, scene.camera)
}

/// A closed room lit by a tiny, very bright light behind a glass sphere: caustics, a dark
/// corner behind a wall, and the fireflies 1 spp renders of such a light produce.
pub fn firefly() -> Scene {
    let mut b = Builder::new();
    let white = b.material(diffuse(v(0.7, 0.7, 0.7)));
    let blue = b.material(diffuse(v(0.2, 0.3, 0.7)));
    let floor = b.material(Material::Diffuse { albedo: Texture::Noise { a: v(0.3, 0.25, 0.2), b: v(0.7, 0.6, 0.5), scale: 6.0, seed: 3 } });
    let light = b.material(Material::Emitter { radiance: v(40000.0, 36000.0, 30000.0) });
    let glass = b.material(Material::Dielectric { ior: 1.5, roughness: 0.0 });
    let metal = b.material(Material::Conductor { f0: Texture::Constant(v(0.9, 0.9, 0.9)), roughness: 0.05 });
    // Room [-3,3] x [0,3] x [-3,3], inward-facing walls.
    b.prims.extend(quad(v(-3.0, 0.0, 3.0), v(6.0, 0.0, 0.0), v(0.0, 0.0, -6.0), 2.0, floor));
    b.prims.extend(quad(v(-3.0, 3.0, -3.0), v(6.0, 0.0, 0.0), v(0.0, 0.0, 6.0), 1.0, white));
    b.prims.extend(quad(v(-3.0, 0.0, -3.0), v(6.0, 0.0, 0.0), v(0.0, 3.0, 0.0), 1.0, white));
    b.prims.extend(quad(v(3.0, 0.0, 3.0), v(-6.0, 0.0, 0.0), v(0.0, 3.0, 0.0), 1.0, white));
    b.prims.extend(quad(v(-3.0, 0.0, 3.0), v(0.0, 0.0, -6.0), v(0.0, 3.0, 0.0), 1.0, blue));
    b.prims.extend(quad(v(3.0, 0.0, -3.0), v(0.0, 0.0, 6.0), v(0.0, 3.0, 0.0), 1.0, white));
    // A free-standing wall that leaves the right-hand corner in shadow.
    b.prims.extend(cuboid(v(1.6, 1.2, -1.2), v(0.05, 1.2, 1.0), 0.0, white));
    b.sphere(v(-1.0, 2.2, -1.0), 0.02, light);
    b.sphere(v(-0.8, 0.6, -0.6), 0.6, glass);
    b.sphere(v(0.6, 0.35, 0.4), 0.35, metal);
    let keys = vec![
        Camera { position: v(-2.2, 1.5, 2.7), target: v(0.5, 0.8, -1.5), vfov: 60.0 },
        Camera { position: v(-1.5, 1.4, 2.8), target: v(0.8, 0.8, -1.6), vfov: 60.0 },
        Camera { position: v(-0.6, 1.3, 2.7), target: v(1.2, 0.7, -1.6), vfov: 60.0 },
    ];
    b.finish(Environment::Black, keys)
}

fn color(r: &mut Pcg32) -> Vec3A {
    v(r.random_range(0.05..0.9), r.random_range(0.05..0.9), r.random_range(0.05..0.9))
}

fn texture(r: &mut Pcg32) -> Texture {
    match r.random_range(0..4) {
        0 => Texture::Constant(color(r)),
        1 => Texture::Checker { a: color(r), b: color(r), scale: r.random_range(1.0..8.0) },
        2 => Texture::Noise { a: color(r), b: color(r), scale: r.random_range(2.0..16.0), seed: r.random() },
        _ => Texture::bricks(color(r), color(r)),
    }
}

/// A seeded random scene for training variety: a textured floor and back wall, 4-12 spheres
/// and boxes of random materials, one or two area lights, sometimes a tiny bright light and a
/// sky, and a smooth camera path through 4 random keys.
pub fn random(seed: u64) -> Scene {
    let mut r = Pcg32::seed_from_u64(seed);
    let mut b = Builder::new();
    let floor_tex = texture(&mut r);
    let floor = b.material(Material::Plastic { albedo: floor_tex, roughness: r.random_range(0.2..1.0) });
    let wall_tex = texture(&mut r);
    let wall = b.material(Material::Diffuse { albedo: wall_tex });
    b.prims.extend(quad(v(-8.0, 0.0, 8.0), v(16.0, 0.0, 0.0), v(0.0, 0.0, -16.0), 4.0, floor));
    b.prims.extend(quad(v(-8.0, 0.0, -4.0), v(16.0, 0.0, 0.0), v(0.0, 6.0, 0.0), 3.0, wall));
    for _ in 0..r.random_range(4..13) {
        let m = match r.random_range(0..5) {
            0 | 1 => {
                let t = texture(&mut r);
                Material::Diffuse { albedo: t }
            }
            2 => Material::Conductor { f0: Texture::Constant(color(&mut r) + v(0.1, 0.1, 0.1)), roughness: r.random_range(0.0..0.7) },
            3 => Material::Dielectric { ior: r.random_range(1.3..1.8), roughness: r.random_range(0.0..0.3) },
            _ => {
                let t = texture(&mut r);
                Material::Plastic { albedo: t, roughness: r.random_range(0.05..0.8) }
            }
        };
        let m = b.material(m);
        let (x, z) = (r.random_range(-3.0..3.0), r.random_range(-3.0..2.5));
        if r.random_bool(0.6) {
            let rad = r.random_range(0.2..0.8);
            b.sphere(v(x, rad, z), rad, m);
        } else {
            let half = v(r.random_range(0.15..0.7), r.random_range(0.15..1.0), r.random_range(0.15..0.7));
            // A yaw in [0, 3.14): not PI, which would change every generated scene after it.
            #[allow(clippy::approx_constant)]
            let yaw = r.random_range(0.0..3.14);
            b.prims.extend(cuboid(v(x, half.y, z), half, yaw, m));
        }
    }
    for _ in 0..r.random_range(1..3) {
        let e = r.random_range(4.0..30.0);
        let tint = v(r.random_range(0.7..1.0), r.random_range(0.7..1.0), r.random_range(0.7..1.0));
        let light = b.material(Material::Emitter { radiance: tint * e });
        let (x, z, s) = (r.random_range(-3.0..3.0), r.random_range(-3.0..3.0), r.random_range(0.3..1.5));
        b.prims.extend(quad(v(x, 4.5, z), v(s, 0.0, 0.0), v(0.0, 0.0, s), 1.0, light)); // facing down
    }
    if r.random_bool(0.4) {
        let light = b.material(Material::Emitter { radiance: v(1.0, 0.9, 0.8) * r.random_range(5e3..5e4) });
        b.sphere(v(r.random_range(-3.0..3.0), r.random_range(1.0..3.5), r.random_range(-3.0..2.0)), 0.03, light);
    }
    let env = if r.random_bool(0.5) {
        let s = r.random_range(0.2..1.5);
        Environment::Sky { zenith: v(0.3, 0.45, 0.9) * s, horizon: v(0.9, 0.85, 0.8) * s, ground: v(0.1, 0.1, 0.1) * s }
    } else {
        Environment::Black
    };
    let center = v(r.random_range(-1.0..1.0), 0.5, r.random_range(-1.0..1.0));
    let (a0, da) = (r.random_range(-0.8..0.8), r.random_range(-0.5..0.5));
    let (dist, height) = (r.random_range(4.5..8.0), r.random_range(1.0..3.5));
    let vfov = r.random_range(35.0..60.0);
    let keys = (0..4)
        .map(|k| {
            let a = a0 + da * k as f32 / 3.0;
            let jitter = v(r.random_range(-0.3..0.3), r.random_range(-0.2..0.2), r.random_range(-0.3..0.3));
            Camera { position: v(dist * a.sin(), height, dist * a.cos()) + jitter, target: center, vfov }
        })
        .collect();
    b.finish(env, keys)
}

/// A texture from a wider range than [`random`]'s: patterns from coarse to a few pixels wide.
fn detailed_texture(r: &mut Pcg32) -> Texture {
    match r.random_range(0..5) {
        0 => Texture::Constant(color(r)),
        1 => Texture::Checker { a: color(r), b: color(r), scale: r.random_range(1.0..40.0) },
        2 | 3 => Texture::Noise { a: color(r), b: color(r), scale: r.random_range(2.0..80.0), seed: r.random() },
        _ => Texture::bricks(color(r), color(r)),
    }
}

/// A material for an object of [`varied`]: diffuse, plastic, metal (plain or textured, smooth
/// to rough), glass (smooth or frosted) or, now and then, an emitter.
fn varied_material(r: &mut Pcg32) -> Material {
    match r.random_range(0..20) {
        0..=4 => Material::Diffuse { albedo: detailed_texture(r) },
        5..=9 => Material::Plastic { albedo: detailed_texture(r), roughness: r.random_range(0.02..0.9) },
        10..=14 => {
            let tint = color(r) * 0.5 + v(0.45, 0.45, 0.45);
            let f0 = if r.random_bool(0.5) {
                Texture::Constant(tint)
            } else {
                Texture::Noise { a: tint, b: tint * r.random_range(0.3..0.8), scale: r.random_range(2.0..40.0), seed: r.random() }
            };
            Material::Conductor { f0, roughness: r.random_range(0.0..0.8) }
        }
        15..=18 => Material::Dielectric {
            ior: r.random_range(1.3..1.9),
            roughness: if r.random_bool(0.6) { 0.0 } else { r.random_range(0.05..0.4) },
        },
        _ => {
            let tint = v(r.random_range(0.4..1.0), r.random_range(0.4..1.0), r.random_range(0.4..1.0));
            Material::Emitter { radiance: tint * r.random_range(1.0..20.0) }
        }
    }
}

/// A seeded scene from a wider space than [`random`]'s, for training at scale: an open floor
/// (with or without a back wall) or a closed room; 5-16 objects (spheres, boxes, thin poles and
/// panels) of diffuse, plastic, metal, glass or emissive materials, up to three of them moving;
/// one to eight area lights from small to large, sometimes a tiny bright one, a sky or darkness;
/// and a camera that stands still, drifts, pans fast or dollies (from 0 to about 30 pixels a
/// frame at 128x128 over 8 frames).
pub fn varied(seed: u64) -> Scene {
    // Its own stream: `varied(s)` shares nothing with `random(s)`.
    let mut r = Pcg32::seed_from_u64(seed ^ 0x9e37_79b9_7f4a_7c15);
    let mut b = Builder::new();
    let room = r.random_bool(0.3);
    let floor = match r.random_range(0..4) {
        0 => Material::Diffuse { albedo: detailed_texture(&mut r) },
        1 => Material::Conductor {
            f0: Texture::Noise { a: v(0.6, 0.6, 0.6), b: v(0.3, 0.3, 0.3), scale: r.random_range(2.0..30.0), seed: r.random() },
            roughness: r.random_range(0.1..0.6),
        },
        _ => Material::Plastic { albedo: detailed_texture(&mut r), roughness: r.random_range(0.05..1.0) },
    };
    let floor = b.material(floor);
    let uv = r.random_range(1.0..6.0);
    b.prims.extend(quad(v(-8.0, 0.0, 8.0), v(16.0, 0.0, 0.0), v(0.0, 0.0, -16.0), uv, floor));
    let wall = b.material(Material::Diffuse { albedo: detailed_texture(&mut r) });
    if room {
        // Walls and ceiling of [-6, 6] x [0, 5] x [-6, 6], facing in.
        b.prims.extend(quad(v(-6.0, 0.0, -6.0), v(12.0, 0.0, 0.0), v(0.0, 5.0, 0.0), uv, wall));
        b.prims.extend(quad(v(6.0, 0.0, 6.0), v(-12.0, 0.0, 0.0), v(0.0, 5.0, 0.0), uv, wall));
        b.prims.extend(quad(v(-6.0, 0.0, 6.0), v(0.0, 0.0, -12.0), v(0.0, 5.0, 0.0), uv, wall));
        b.prims.extend(quad(v(6.0, 0.0, -6.0), v(0.0, 0.0, 12.0), v(0.0, 5.0, 0.0), uv, wall));
        b.prims.extend(quad(v(-6.0, 5.0, -6.0), v(12.0, 0.0, 0.0), v(0.0, 0.0, 12.0), uv, wall));
    } else if r.random_bool(0.7) {
        b.prims.extend(quad(v(-8.0, 0.0, -4.0), v(16.0, 0.0, 0.0), v(0.0, 6.0, 0.0), uv, wall));
    }
    let objects = r.random_range(5..17);
    let movers = if r.random_bool(0.5) { r.random_range(1..4) } else { 0 };
    for i in 0..objects {
        let m = varied_material(&mut r);
        let m = b.material(m);
        let velocity =
            if i < movers { v(r.random_range(-0.25..0.25), r.random_range(-0.03..0.03), r.random_range(-0.25..0.25)) } else { Vec3A::ZERO };
        let (x, z) = (r.random_range(-3.5..3.5), r.random_range(-3.5..2.5));
        #[allow(clippy::approx_constant)]
        let yaw = r.random_range(0.0..3.14);
        match r.random_range(0..20) {
            0..=8 => {
                let rad = r.random_range(0.1..0.9);
                b.moving_sphere(v(x, rad + velocity.y.abs() * 8.0, z), rad, m, velocity);
            }
            9..=14 => {
                let half = v(r.random_range(0.1..0.8), r.random_range(0.1..1.0), r.random_range(0.1..0.8));
                b.moving(cuboid(v(x, half.y, z), half, yaw, m), velocity);
            }
            15..=17 => {
                // A thin pole: a few pixels wide.
                let (w, h) = (r.random_range(0.015..0.06), r.random_range(0.5..2.0));
                b.moving(cuboid(v(x, h, z), v(w, h, w), yaw, m), velocity);
            }
            _ => {
                // A thin panel on edge.
                let half = v(r.random_range(0.4..1.2), r.random_range(0.3..1.0), r.random_range(0.01..0.03));
                b.moving(cuboid(v(x, half.y, z), half, yaw, m), velocity);
            }
        }
    }
    let top = if room { 4.95 } else { 4.5 };
    for _ in 0..r.random_range(1..9) {
        let s: f32 = r.random_range(0.1..2.5);
        let tint = v(r.random_range(0.6..1.0), r.random_range(0.6..1.0), r.random_range(0.6..1.0));
        let light = b.material(Material::Emitter { radiance: tint * r.random_range(3.0..20.0) / s.max(0.4).powi(2) });
        let (x, z) = (r.random_range(-4.0..4.0), r.random_range(-4.0..4.0));
        b.prims.extend(quad(v(x, top, z), v(s, 0.0, 0.0), v(0.0, 0.0, s), 1.0, light)); // facing down
    }
    if r.random_bool(0.3) {
        let light = b.material(Material::Emitter { radiance: v(1.0, 0.9, 0.8) * r.random_range(5e3..5e4) });
        b.sphere(v(r.random_range(-3.0..3.0), r.random_range(1.0..3.5), r.random_range(-3.0..2.0)), 0.03, light);
    }
    let env = if !room && r.random_bool(0.6) {
        let s = r.random_range(0.1..2.0);
        Environment::Sky { zenith: v(0.3, 0.45, 0.9) * s, horizon: v(0.9, 0.85, 0.8) * s, ground: v(0.1, 0.1, 0.1) * s }
    } else {
        Environment::Black
    };
    // Orbit angle over the whole sequence: still, drifting, panning or fast.
    let sweep = match r.random_range(0..4) {
        0 => 0.0,
        1 => r.random_range(0.02..0.2),
        2 => r.random_range(0.2..0.7),
        _ => r.random_range(0.7..1.5),
    } * if r.random_bool(0.5) { 1.0 } else { -1.0 };
    let dolly = if r.random_bool(0.3) { r.random_range(-0.35..0.35) } else { 0.0 };
    let shake = if sweep == 0.0 && dolly == 0.0 { 0.0 } else { r.random_range(0.0..0.3) };
    let center = v(r.random_range(-1.0..1.0), r.random_range(0.3..1.0), r.random_range(-1.0..1.0));
    let a0 = r.random_range(-0.8..0.8);
    let (dist, height) =
        if room { (r.random_range(2.5..4.0), r.random_range(1.0..3.0)) } else { (r.random_range(4.0..8.0), r.random_range(0.6..3.5)) };
    let vfov = r.random_range(30.0..65.0);
    let keys = (0..4)
        .map(|k| {
            let f = k as f32 / 3.0;
            let a = a0 + sweep * f;
            let d = dist * (1.0 + dolly * f);
            let jitter = v(r.random_range(-1.0..1.0), r.random_range(-0.6..0.6), r.random_range(-1.0..1.0)) * shake;
            Camera { position: v(d * a.sin(), height, d * a.cos()) + jitter, target: center, vfov }
        })
        .collect();
    b.finish(env, keys)
}

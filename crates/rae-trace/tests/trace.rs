//! rae-trace: determinism, convergence, auxiliary buffers on known geometry, motion vectors.

use glam::Vec3A;
use rae_trace::geometry::{Prim, Shape, quad};
use rae_trace::material::Material;
use rae_trace::scene::{Camera, CameraPath, Environment, v};
use rae_trace::texture::Texture;
use rae_trace::{Aux, Scene, Settings, render_frame, scenes};

fn settings(w: u32, h: u32, spp: u32, ref_spp: u32, seed: u64) -> Settings {
    Settings { width: w, height: h, spp, ref_spp, seed, max_depth: 8, aux: Aux::Centre }
}

#[test]
fn a_seed_reproduces_a_frame_bit_for_bit() {
    let scene = scenes::random(5);
    let a = render_frame(&scene, 1, 3, &settings(24, 16, 2, 0, 9));
    let b = render_frame(&scene, 1, 3, &settings(24, 16, 2, 0, 9));
    assert_eq!(a, b, "same seed, same frame: identical buffers");
    let other_seed = render_frame(&scene, 1, 3, &settings(24, 16, 2, 0, 10));
    assert_ne!(a.color, other_seed.color, "another seed draws other noise");
    let scene2 = scenes::random(5);
    let next_frame = render_frame(&scene2, 2, 3, &settings(24, 16, 2, 0, 9));
    assert_ne!(a.color, next_frame.color, "every frame draws new random numbers");
}

fn mse(a: &[f32], b: &[f32]) -> f64 {
    a.iter().zip(b).map(|(x, y)| ((x - y) as f64).powi(2)).sum::<f64>() / a.len() as f64
}

#[test]
fn error_against_the_reference_falls_like_one_over_spp() {
    // A diffuse room lit by an area light and the sky: every estimator term is bounded.
    let scene = scenes::by_name("glossy").unwrap();
    let reference = render_frame(&scene, 0, 1, &settings(32, 24, 1, 2048, 1)).reference;
    let err: Vec<f64> =
        [4u32, 16, 64].iter().map(|&spp| mse(&render_frame(&scene, 0, 1, &settings(32, 24, spp, 0, 2)).color, &reference)).collect();
    eprintln!("MSE against a 2048 spp reference at 4, 16, 64 spp: {err:?}");
    for k in 0..2 {
        let ratio = err[k] / err[k + 1];
        // Expected (1/n + 1/2048) / (1/4n + 1/2048): about 3.9 and 3.6 for 4x the samples.
        assert!((2.5..6.0).contains(&ratio), "MSE at {:?} spp: {err:?}; ratio {ratio} is not ~4", [4, 16, 64]);
    }
}

/// A large textured floor (y = 0) seen from above at an angle.
fn floor_scene(cameras: Vec<Camera>) -> Scene {
    let tex = Texture::Checker { a: v(0.9, 0.1, 0.1), b: v(0.1, 0.2, 0.9), scale: 4.0 };
    let mut materials = vec![Material::Diffuse { albedo: tex.clone() }];
    materials.push(Material::Emitter { radiance: Vec3A::ONE });
    let prims = quad(v(-50.0, 0.0, 50.0), v(100.0, 0.0, 0.0), v(0.0, 0.0, -100.0), 25.0, 0).to_vec();
    Scene::new(
        prims,
        materials,
        Environment::Sky { zenith: Vec3A::ONE, horizon: Vec3A::ONE, ground: Vec3A::ZERO },
        CameraPath { keys: cameras },
    )
}

#[test]
fn auxiliary_buffers_are_right_on_a_textured_plane() {
    let cam = Camera { position: v(0.3, 2.0, 3.0), target: v(0.0, 0.0, 0.0), vfov: 50.0 };
    let scene = floor_scene(vec![cam]);
    let (w, h) = (31u32, 23u32);
    let fb = render_frame(&scene, 0, 1, &settings(w, h, 1, 0, 0));
    let tex = Texture::Checker { a: v(0.9, 0.1, 0.1), b: v(0.1, 0.2, 0.9), scale: 4.0 };
    let mut hits = 0;
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            let dir = cam.direction(x as f32 + 0.5, y as f32 + 0.5, w, h);
            if dir.y >= -1e-3 {
                assert!(fb.depth[i].is_infinite(), "pixel ({x},{y}) misses: depth marked +inf");
                continue;
            }
            // Analytic intersection with y = 0 and the quad's uv (corner (-50, 0, 50), 25 repeats).
            let t = -cam.position.y / dir.y;
            let p = cam.position + dir * t;
            let uv = glam::Vec2::new((p.x + 50.0) / 100.0 * 25.0, (50.0 - p.z) / 100.0 * 25.0);
            let want = tex.eval(uv);
            hits += 1;
            assert!((fb.depth[i] - t).abs() < 1e-3 * t, "pixel ({x},{y}): depth {} vs {t}", fb.depth[i]);
            assert_eq!(&fb.normal[3 * i..3 * i + 3], &[0.0, 1.0, 0.0], "pixel ({x},{y}): plane normal");
            assert_eq!(fb.roughness[i], 1.0);
            // Skip texels on a checker edge, where rounding may pick either colour.
            let f = (uv * 4.0).fract();
            if f.min_element() > 0.02 && f.max_element() < 0.98 {
                assert_eq!(&fb.albedo[3 * i..3 * i + 3], &want.to_array(), "pixel ({x},{y}): albedo at uv {uv}");
            }
        }
    }
    assert!(hits > 300, "most pixels see the floor");
}

#[test]
fn sampled_auxiliary_buffers_average_the_pixel_and_keep_the_color_s_noise() {
    // Looking toward the horizon: the floor's far edge crosses the view.
    let cam = Camera { position: v(0.3, 1.0, 3.0), target: v(0.0, 0.5, -10.0), vfov: 50.0 };
    let scene = floor_scene(vec![cam]);
    let (w, h) = (31u32, 23u32);
    let centre = render_frame(&scene, 0, 1, &settings(w, h, 16, 0, 4));
    let sampled = render_frame(&scene, 0, 1, &Settings { aux: Aux::Samples, ..settings(w, h, 16, 0, 4) });
    assert_eq!(centre.color, sampled.color, "the auxiliary buffers draw from a stream of their own");
    assert_eq!(centre.motion, sampled.motion);
    let (mut mixed_albedo, mut edge_pixels) = (0, 0);
    for i in 0..(w * h) as usize {
        let n = Vec3A::from_slice(&sampled.normal[3 * i..3 * i + 3]);
        if centre.depth[i] < 8.0 {
            // Away from the horizon the plane's depth over the pixel's footprint is near the
            // centre's.
            assert!(
                (sampled.depth[i] - centre.depth[i]).abs() < 0.1 * centre.depth[i],
                "pixel {i}: {} vs {}",
                sampled.depth[i],
                centre.depth[i]
            );
        }
        if n.length() > 0.0 && n.length() < 0.999 {
            // Some of its samples missed the plane: a horizon pixel, its normal shorter than 1.
            edge_pixels += 1;
            assert!((n.normalize() - Vec3A::Y).length() < 1e-5);
        }
        let a = &sampled.albedo[3 * i..3 * i + 3];
        if centre.depth[i].is_finite() && a != &centre.albedo[3 * i..3 * i + 3] {
            mixed_albedo += 1;
        }
    }
    assert!(edge_pixels > 0, "the horizon's pixels average hits and misses");
    assert!(mixed_albedo > 20, "checker edges are averaged over the pixel: {mixed_albedo} pixels differ from the centre's");
}

#[test]
fn sampled_auxiliary_buffers_look_through_a_mirror_to_what_it_reflects() {
    // A polished metal floor under a diffuse ceiling: the centre's buffers see the metal, the
    // sampled ones (as Cycles writes them) the ceiling in it, tinted by the metal.
    let cam = Camera { position: v(0.0, 2.0, 3.0), target: v(0.0, 0.0, 0.0), vfov: 40.0 };
    let f0 = v(0.9, 0.8, 0.5);
    let green = v(0.2, 0.7, 0.3);
    let materials =
        vec![Material::Conductor { f0: Texture::Constant(f0), roughness: 0.0 }, Material::Diffuse { albedo: Texture::Constant(green) }];
    let mut prims = quad(v(-50.0, 0.0, 50.0), v(100.0, 0.0, 0.0), v(0.0, 0.0, -100.0), 1.0, 0).to_vec();
    prims.extend(quad(v(-50.0, 5.0, -50.0), v(100.0, 0.0, 0.0), v(0.0, 0.0, 100.0), 1.0, 1));
    let scene = Scene::new(
        prims,
        materials,
        Environment::Sky { zenith: Vec3A::ONE, horizon: Vec3A::ONE, ground: Vec3A::ZERO },
        CameraPath { keys: vec![cam] },
    );
    let (w, h) = (16u32, 12u32);
    let centre = render_frame(&scene, 0, 1, &settings(w, h, 4, 0, 1));
    let sampled = render_frame(&scene, 0, 1, &Settings { aux: Aux::Samples, ..settings(w, h, 4, 0, 1) });
    let i = (h / 2 * w + w / 2) as usize;
    let close = |a: &[f32], b: Vec3A| (Vec3A::from_slice(a) - b).length() < 1e-4;
    assert!(close(&centre.albedo[3 * i..3 * i + 3], f0), "centre: the metal's albedo");
    assert!(
        close(&sampled.albedo[3 * i..3 * i + 3], f0 * green),
        "sampled: the ceiling's, tinted: {:?}",
        &sampled.albedo[3 * i..3 * i + 3]
    );
    assert!(close(&centre.normal[3 * i..3 * i + 3], Vec3A::Y));
    assert!(close(&sampled.normal[3 * i..3 * i + 3], -Vec3A::Y), "the ceiling's normal, facing the reflected ray");
    assert_eq!((centre.roughness[i], sampled.roughness[i]), (0.0, 1.0));
    assert!((centre.depth[i] - sampled.depth[i]).abs() < 0.05 * centre.depth[i], "depth stays the first surface's");
}

#[test]
fn motion_vectors_point_to_where_a_static_point_was() {
    // The camera slides sideways (position and target alike) over a wall at z = 0.
    let key = |x: f32| Camera { position: v(x, 1.0, 4.0), target: v(x, 1.0, 0.0), vfov: 45.0 };
    let tex = Texture::Constant(v(0.5, 0.5, 0.5));
    let materials = vec![Material::Diffuse { albedo: tex }];
    let wall = quad(v(-50.0, -50.0, 0.0), v(100.0, 0.0, 0.0), v(0.0, 100.0, 0.0), 1.0, 0).to_vec();
    let scene = Scene::new(wall, materials, Environment::Black, CameraPath { keys: vec![key(0.0), key(1.0)] });
    let (w, h, frames) = (40u32, 30u32, 5u32);
    for f in [0u32, 2, 4] {
        let fb = render_frame(&scene, f, frames, &settings(w, h, 1, 0, 0));
        let now = scene.camera.frame(f as i64, frames);
        let before = scene.camera.frame(f as i64 - 1, frames);
        let shift = (now.position.x - before.position.x) * now.focal_pixels(h) / 4.0;
        for i in [0usize, 17 * 40 + 9, (w * h - 1) as usize] {
            let (mx, my) = (fb.motion[2 * i], fb.motion[2 * i + 1]);
            // Moving right, a static point was further right in the previous frame.
            assert!((mx - shift).abs() < 1e-2 && my.abs() < 1e-2, "frame {f} pixel {i}: motion ({mx}, {my}), expected ({shift}, 0)");
        }
        if f == 0 {
            assert!(fb.motion.iter().all(|m| m.abs() < 1e-4), "no motion before the first frame");
        } else {
            assert!(shift > 0.5, "the test moves the camera by a visible amount");
        }
    }
}

#[test]
fn motion_vectors_follow_a_moving_object_and_not_the_wall_behind_it() {
    // A still camera over a wall at z = 0 and a sphere in front of it moving right by 0.2 each
    // frame: on the sphere a point was 0.2 further left (its motion is that step projected at
    // its depth), on the wall motion is zero, and the sphere covers other pixels frame to frame.
    let cam = Camera { position: v(0.0, 1.0, 4.0), target: v(0.0, 1.0, 0.0), vfov: 45.0 };
    let materials = vec![Material::Diffuse { albedo: Texture::Constant(v(0.5, 0.5, 0.5)) }];
    let mut prims = quad(v(-50.0, -50.0, 0.0), v(100.0, 0.0, 0.0), v(0.0, 100.0, 0.0), 1.0, 0).to_vec();
    let step = v(0.2, 0.0, 0.0);
    prims.push(Prim { shape: Shape::Sphere { center: v(-0.6, 1.0, 1.5), radius: 0.5 }, material: 0, velocity: step });
    let scene = Scene::new(prims, materials, Environment::Black, CameraPath { keys: vec![cam] });
    let (w, h) = (48u32, 36u32);
    let focal = cam.focal_pixels(h);
    let mut covered = Vec::new();
    for f in [1u32, 3] {
        let fb = render_frame(&scene, f, 5, &settings(w, h, 1, 0, 0));
        let (mut on_sphere, mut on_wall) = (0, 0);
        let mut here = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as usize;
                let (mx, my) = (fb.motion[2 * i], fb.motion[2 * i + 1]);
                let p = cam.position + cam.direction(x as f32 + 0.5, y as f32 + 0.5, w, h) * fb.depth[i];
                if p.z > 0.01 {
                    // The sphere: the step back, projected at this point's distance from the camera.
                    let want = -step.x * focal / (cam.position.z - p.z);
                    assert!(
                        (mx - want).abs() < 0.05 * want.abs() && my.abs() < 0.05,
                        "frame {f} ({x},{y}): motion ({mx}, {my}), expected ({want}, 0)"
                    );
                    on_sphere += 1;
                    here.push(i);
                } else if fb.depth[i].is_finite() {
                    assert!(mx.abs() < 1e-3 && my.abs() < 1e-3, "frame {f} ({x},{y}) on the wall: motion ({mx}, {my})");
                    on_wall += 1;
                }
            }
        }
        assert!(on_sphere > 40 && on_wall > 500, "frame {f}: {on_sphere} sphere and {on_wall} wall pixels");
        covered.push(here);
    }
    assert!(covered[1].iter().filter(|i| !covered[0].contains(i)).count() > 20, "the sphere moves over the wall");
}

#[test]
fn the_moving_scenes_move_and_the_fixed_ones_do_not() {
    for name in scenes::NAMES {
        let scene = scenes::by_name(name).unwrap();
        assert_eq!(scene.at_frame(3).is_some(), name.ends_with("-moving"), "{name}");
    }
}

#[test]
fn varied_scenes_span_still_to_fast_cameras_moving_objects_and_every_material() {
    let (mut still, mut fast, mut moving, mut emissive_objects) = (0, 0, 0, 0);
    let mut materials = [0usize; 5];
    for seed in 1..=60 {
        let scene = scenes::varied(seed);
        assert!(scene.has_lights(), "varied {seed} has a light");
        // The camera's sweep, in radians of view direction over the sequence.
        let (first, last) = (scene.camera.frame(0, 8), scene.camera.frame(7, 8));
        let turn = (first.target - first.position).normalize().angle_between((last.target - last.position).normalize());
        if (first.position - last.position).length() < 1e-4 && turn < 1e-4 {
            still += 1;
        }
        if turn > 0.6 {
            fast += 1;
        }
        moving += scene.at_frame(1).is_some() as usize;
        for m in &scene.materials {
            materials[match m {
                Material::Diffuse { .. } => 0,
                Material::Plastic { .. } => 1,
                Material::Conductor { .. } => 2,
                Material::Dielectric { .. } => 3,
                Material::Emitter { .. } => 4,
            }] += 1;
        }
        let glowing_sphere = |(i, p): (usize, &Prim)| {
            matches!(scene.material(i), Material::Emitter { .. }) && matches!(p.shape, Shape::Sphere { radius, .. } if radius > 0.05)
        };
        emissive_objects += scene.prims.iter().enumerate().any(glowing_sphere) as usize;
    }
    assert!(still >= 5 && fast >= 5 && moving >= 15, "still {still}, fast {fast}, with moving objects {moving} of 60");
    assert!(materials.iter().all(|&n| n >= 10), "materials (diffuse, plastic, metal, glass, emitter): {materials:?}");
    assert!(emissive_objects >= 1, "some scene has an emissive sphere");
    let (a, b) = (
        render_frame(&scenes::varied(3), 1, 3, &settings(16, 16, 1, 0, 1)),
        render_frame(&scenes::varied(3), 1, 3, &settings(16, 16, 1, 0, 1)),
    );
    assert_eq!(a, b, "a seed reproduces its scene");
}

#[test]
fn dataset_renders_varied_sequences_at_cycling_sample_counts_and_continues_where_it_stopped() {
    let out = tempfile::tempdir().unwrap();
    let run = |count: &str| {
        let status = std::process::Command::new(env!("CARGO_BIN_EXE_rae-trace"))
            .args(["dataset", "--count", count, "--first-seed", "3", "--frames", "2", "--ref-spp", "2", "--size", "16x8"])
            .arg(out.path())
            .output()
            .unwrap();
        assert!(status.status.success(), "{}", String::from_utf8_lossy(&status.stderr));
        String::from_utf8_lossy(&status.stdout).to_string()
    };
    run("2");
    let mut names: Vec<String> = std::fs::read_dir(out.path()).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into()).collect();
    names.sort();
    assert_eq!(
        names,
        ["v00003-8spp", "v00004-1spp-aux-samples"],
        "seed 3 at 8 spp, seed 4 at 1 spp: the counts cycle 1, 2, 4, 8 by seed, the auxiliary buffers every four seeds"
    );
    let four = out.path().join("v00004-1spp-aux-samples");
    assert!(four.join("reference_0001.exr").exists() && four.join("motion_0000.exr").exists());
    let again = run("3");
    assert!(again.contains("1 rendered now, 2 already there"), "{again}");
}

//! Sequence reading: motion from per-buffer files as written, and from Blender's Vector pass
//! converted to rae's convention; files held in memory (a browser's) read as from disk.

use std::path::PathBuf;

use exr::prelude::*;
use rae_core::InputBuffer;
use rae_core::io::{self, MotionSource, Sequence, Slot};

/// A fresh folder under the system's temporary one.
fn folder(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rae-io-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn write(path: PathBuf, (w, h): (usize, usize), channels: &[(&str, f32)]) {
    let ch: Vec<AnyChannel<FlatSamples>> = channels.iter().map(|(n, v)| AnyChannel::new(*n, FlatSamples::F32(vec![*v; w * h]))).collect();
    let layer = Layer::new((w, h), LayerAttributes::default(), Encoding::FAST_LOSSLESS, AnyChannels::sort(ch.into_iter().collect()));
    Image::from_layer(layer).write().to_file(path).unwrap();
}

#[test]
fn motion_is_read_in_rae_convention_from_files_and_from_blender() {
    let size = (6, 4);
    let blender = folder("blender");
    write(
        blender.join("shot_0000.exr"),
        size,
        &[
            ("ViewLayer.Combined.R", 1.0),
            ("ViewLayer.Combined.G", 1.0),
            ("ViewLayer.Combined.B", 1.0),
            ("ViewLayer.Vector.X", 1.5),
            ("ViewLayer.Vector.Y", 0.75),
            ("ViewLayer.Vector.Z", -1.5),
            ("ViewLayer.Vector.W", -0.75),
        ],
    );
    let seq = Sequence::scan(&blender).unwrap();
    assert_eq!(seq.motion_source(), Some(MotionSource::BlenderVector));
    let frame = seq.load(0).unwrap();
    assert_eq!(&frame.inputs().motion.unwrap()[..2], &[1.5, -0.75], "Blender's y is up: rae's motion is (X, -Y)");
    let files = folder("files");
    write(files.join("color_0000.exr"), size, &[("R", 1.0), ("G", 1.0), ("B", 1.0)]);
    write(files.join("motion_0000.exr"), size, &[("R", 1.5), ("G", 0.75)]);
    let seq = Sequence::scan(&files).unwrap();
    assert_eq!(seq.motion_source(), Some(MotionSource::Files));
    assert_eq!(&seq.load(0).unwrap().inputs().motion.unwrap()[..2], &[1.5, 0.75], "motion files are read as written");
    for d in [blender, files] {
        std::fs::remove_dir_all(d).unwrap();
    }
}

/// `rgb` (w x h, 3 per pixel) fetched at x + motion, bilinear between pixel centres; the second
/// value per pixel is whether all four taps were inside.
fn fetch(rgb: &[f32], motion: &[f32], w: usize, h: usize) -> Vec<([f32; 3], bool)> {
    (0..w * h)
        .map(|i| {
            let (sx, sy) = ((i % w) as f32 + motion[2 * i], (i / w) as f32 + motion[2 * i + 1]);
            let (x0, y0) = (sx.floor(), sy.floor());
            let (fx, fy) = (sx - x0, sy - y0);
            let inside = x0 >= 0.0 && y0 >= 0.0 && x0 + 1.0 < w as f32 && y0 + 1.0 < h as f32;
            let mut out = [0.0; 3];
            if inside {
                let (x0, y0) = (x0 as usize, y0 as usize);
                for (dy, wy) in [(0, 1.0 - fy), (1, fy)] {
                    for (dx, wx) in [(0, 1.0 - fx), (1, fx)] {
                        let j = (y0 + dy) * w + x0 + dx;
                        for c in 0..3 {
                            out[c] += rgb[3 * j + c] * wx * wy;
                        }
                    }
                }
            }
            (out, inside)
        })
        .collect()
}

#[test]
fn blender_vector_pass_warps_the_previous_frame_onto_the_current() {
    // Two frames of a Cycles render (scripts/blender_vector_fixture.py: a camera that pans, a
    // cube that moves on its own over a checkered floor). The Vector pass as rae reads it
    // (X, -Y) brings the previous frame onto the current one: the mean error where the fetch
    // is inside the frame is under half of no warp's, and each other sign choice is worse.
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures/blender_vector");
    let seq = Sequence::scan(&dir).unwrap();
    assert_eq!(seq.motion_source(), Some(MotionSource::BlenderVector));
    let (w, h) = (seq.width as usize, seq.height as usize);
    let (prev, now) = (seq.load(0).unwrap(), seq.load(1).unwrap());
    let (prev, now) = (prev.inputs(), now.inputs());
    let motion = now.motion.unwrap();
    let error = |sx: f32, sy: f32| {
        let m: Vec<f32> = motion.chunks(2).flat_map(|v| [sx * v[0], sy * v[1]]).collect();
        let (mut sum, mut n) = (0.0f64, 0usize);
        for (i, (v, inside)) in fetch(prev.color, &m, w, h).into_iter().enumerate() {
            if inside {
                sum += (0..3).map(|c| (v[c] - now.color[3 * i + c]).abs() as f64).sum::<f64>();
                n += 3;
            }
        }
        assert!(n > w * h * 3 / 2, "most fetches inside the frame");
        sum / n as f64
    };
    let none = prev.color.iter().zip(now.color).map(|(a, b)| (a - b).abs() as f64).sum::<f64>() / now.color.len() as f64;
    let rae = error(1.0, 1.0);
    assert!(rae < 0.5 * none, "warped {rae} against no warp {none}");
    for (sx, sy) in [(1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
        let other = error(sx, sy);
        assert!(rae < 0.6 * other, "rae's reading {rae} against the sign choice ({sx}, {sy}) {other}");
    }
}

#[test]
fn files_in_memory_read_as_their_folder_does() {
    // A browser hands over files without a folder: the same values as the disk's reader, the
    // buffer and frame number from the name, and errors that name the file.
    let dir = folder("bytes");
    let size = (5, 3);
    write(dir.join("color_0007.exr"), size, &[("R", 0.25), ("G", 0.5), ("B", 2.0)]);
    write(dir.join("motion_0007.exr"), size, &[("R", 1.5), ("G", -0.5)]);
    let seq = Sequence::scan(&dir).unwrap();
    let frame = seq.load(0).unwrap();
    for (name, slot) in [("color_0007.exr", Slot::Input(InputBuffer::Color)), ("motion_0007.exr", Slot::Motion)] {
        assert_eq!(io::per_buffer_name(name), Some((slot, 7)));
        let bytes = std::fs::read(dir.join(name)).unwrap();
        let (read_size, values) = io::read_buffer_bytes(name, &bytes, slot).unwrap();
        assert_eq!(read_size, (5, 3));
        assert_eq!(values.as_slice(), frame.buffers[&slot].as_slice(), "{name}: as Sequence::load reads it");
    }
    for name in ["color.exr", "shot_0001.exr", "color_0001.txt", "0001.exr"] {
        assert_eq!(io::per_buffer_name(name), None, "{name} names no buffer");
    }
    let err = io::read_buffer_bytes("albedo_0003.exr", b"not an EXR", Slot::Input(InputBuffer::Albedo)).unwrap_err().to_string();
    assert!(err.contains("albedo_0003.exr") && err.contains("not a readable EXR"), "{err}");
    let err = io::read_buffer_bytes("albedo_0003.png", b"\x89PNG broken", Slot::Input(InputBuffer::Albedo)).unwrap_err().to_string();
    assert!(err.contains("albedo_0003.png"), "{err}");
    std::fs::remove_dir_all(dir).unwrap();
}

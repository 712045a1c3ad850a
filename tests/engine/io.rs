//! Sequence reading: motion from per-buffer files as written, and from Blender's Vector pass
//! converted to rae's convention.

use std::path::PathBuf;

use exr::prelude::*;
use rae_core::io::{MotionSource, Sequence};

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

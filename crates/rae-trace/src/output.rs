//! Writing a frame in rae-cli's per-buffer layout: `color_0007.exr`, `albedo_0007.exr`, ...
//! (ZIP-compressed EXR, float or half; RGB buffers as R, G, B; depth and roughness as Y; motion as
//! R, G). Every file is written under a temporary name and renamed, so an interrupted render
//! leaves no partial file.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use rae_core::io::write_exr_channels;

use crate::render::FrameBuffers;

/// Sample precision of written files.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Precision {
    /// 32-bit float.
    F32,
    /// 16-bit half (depth beyond 65504 becomes +inf, i.e. a miss).
    F16,
}

/// Write one buffer: `data` interleaved over `names` (R, G, B; Y; R, G).
fn write(path: &Path, width: usize, height: usize, names: &[&str], data: &[f32], precision: Precision) -> Result<()> {
    write_exr_channels(path, width as u32, height as u32, names, data, precision == Precision::F16)
        .with_context(|| format!("writing {}", path.display()))
}

/// Path of buffer `name` of frame `index` in `dir`.
pub fn frame_path(dir: &Path, name: &str, index: u32) -> PathBuf {
    dir.join(format!("{name}_{index:04}.exr"))
}

/// Write every buffer of a frame.
pub fn write_frame(dir: &Path, index: u32, width: usize, height: usize, fb: &FrameBuffers, precision: Precision) -> Result<()> {
    let (rgb, y, rg) = (&["R", "G", "B"][..], &["Y"][..], &["R", "G"][..]);
    let mut buffers = vec![("color", rgb, &fb.color)];
    if !fb.reference.is_empty() {
        buffers.push(("reference", rgb, &fb.reference));
    }
    buffers.extend([
        ("albedo", rgb, &fb.albedo),
        ("normal", rgb, &fb.normal),
        ("depth", y, &fb.depth),
        ("roughness", y, &fb.roughness),
        ("motion", rg, &fb.motion),
    ]);
    for (name, channels, data) in buffers {
        write(&frame_path(dir, name, index), width, height, channels, data, precision)?;
    }
    Ok(())
}

//! Writing a frame in rae-cli's per-buffer layout: `color_0007.exr`, `albedo_0007.exr`, ...
//! (float EXR; RGB buffers as R, G, B; depth and roughness as Y; motion as R, G). Every file is
//! written under a temporary name and renamed, so an interrupted render leaves no partial file.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use exr::prelude::*;

use crate::render::FrameBuffers;

fn atomic(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let name = path.file_name().context("output path has no file name")?.to_string_lossy();
    let tmp = path.with_file_name(format!(".{name}.tmp"));
    let result = write(&tmp).and_then(|_| std::fs::rename(&tmp, path).with_context(|| format!("renaming to {}", path.display())));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Write RGB f32 data (`width * height * 3`).
pub fn write_rgb(path: &Path, width: usize, height: usize, data: &[f32]) -> Result<()> {
    atomic(path, |tmp| {
        write_rgb_file(tmp, width, height, |x, y| {
            let i = 3 * (y * width + x);
            (data[i], data[i + 1], data[i + 2])
        })
        .with_context(|| format!("writing {}", path.display()))
    })
}

/// Write one channel named `Y` (`width * height`).
pub fn write_gray(path: &Path, width: usize, height: usize, data: &[f32]) -> Result<()> {
    atomic(path, |tmp| {
        let channels = SpecificChannels::build().with_channel("Y").with_pixel_fn(|p: Vec2<usize>| (data[p.y() * width + p.x()],));
        Image::from_channels((width, height), channels).write().to_file(tmp).with_context(|| format!("writing {}", path.display()))
    })
}

/// Write two channels `R`, `G` (`width * height * 2`).
pub fn write_rg(path: &Path, width: usize, height: usize, data: &[f32]) -> Result<()> {
    atomic(path, |tmp| {
        let channels = SpecificChannels::build()
            .with_channel("R")
            .with_channel("G")
            .with_pixel_fn(|p: Vec2<usize>| (data[2 * (p.y() * width + p.x())], data[2 * (p.y() * width + p.x()) + 1]));
        Image::from_channels((width, height), channels).write().to_file(tmp).with_context(|| format!("writing {}", path.display()))
    })
}

/// Path of buffer `name` of frame `index` in `dir`.
pub fn frame_path(dir: &Path, name: &str, index: u32) -> PathBuf {
    dir.join(format!("{name}_{index:04}.exr"))
}

/// Write every buffer of a frame.
pub fn write_frame(dir: &Path, index: u32, width: usize, height: usize, fb: &FrameBuffers) -> Result<()> {
    write_rgb(&frame_path(dir, "color", index), width, height, &fb.color)?;
    if !fb.reference.is_empty() {
        write_rgb(&frame_path(dir, "reference", index), width, height, &fb.reference)?;
    }
    write_rgb(&frame_path(dir, "albedo", index), width, height, &fb.albedo)?;
    write_rgb(&frame_path(dir, "normal", index), width, height, &fb.normal)?;
    write_gray(&frame_path(dir, "depth", index), width, height, &fb.depth)?;
    write_gray(&frame_path(dir, "roughness", index), width, height, &fb.roughness)?;
    write_rg(&frame_path(dir, "motion", index), width, height, &fb.motion)
}

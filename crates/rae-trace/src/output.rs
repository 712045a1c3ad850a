//! Writing a frame in rae-cli's per-buffer layout: `color_0007.exr`, `albedo_0007.exr`, ...
//! (ZIP-compressed EXR, float or half; RGB buffers as R, G, B; depth and roughness as Y; motion as
//! R, G). Every file is written under a temporary name and renamed, so an interrupted render
//! leaves no partial file.

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

/// Sample precision of written files.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Precision {
    /// 32-bit float.
    F32,
    /// 16-bit half (depth beyond 65504 becomes +inf, i.e. a miss).
    F16,
}

fn finish(path: &Path, result: exr::error::UnitResult) -> Result<()> {
    result.with_context(|| format!("writing {}", path.display()))
}

/// Write RGB data (`width * height * 3`).
pub fn write_rgb(path: &Path, width: usize, height: usize, data: &[f32], precision: Precision) -> Result<()> {
    let at = move |p: Vec2<usize>| 3 * (p.y() * width + p.x());
    atomic(path, |tmp| {
        let size = (width, height);
        let enc = Encoding::SMALL_LOSSLESS;
        finish(
            path,
            match precision {
                Precision::F32 => {
                    Image::from_encoded_channels(size, enc, SpecificChannels::rgb(|p| (data[at(p)], data[at(p) + 1], data[at(p) + 2])))
                        .write()
                        .to_file(tmp)
                }
                Precision::F16 => Image::from_encoded_channels(
                    size,
                    enc,
                    SpecificChannels::rgb(|p| (f16::from_f32(data[at(p)]), f16::from_f32(data[at(p) + 1]), f16::from_f32(data[at(p) + 2]))),
                )
                .write()
                .to_file(tmp),
            },
        )
    })
}

/// Write one channel named `Y` (`width * height`).
pub fn write_gray(path: &Path, width: usize, height: usize, data: &[f32], precision: Precision) -> Result<()> {
    let at = move |p: Vec2<usize>| p.y() * width + p.x();
    atomic(path, |tmp| {
        let (size, enc) = ((width, height), Encoding::SMALL_LOSSLESS);
        finish(
            path,
            match precision {
                Precision::F32 => {
                    Image::from_encoded_channels(size, enc, SpecificChannels::build().with_channel("Y").with_pixel_fn(|p| (data[at(p)],)))
                        .write()
                        .to_file(tmp)
                }
                Precision::F16 => Image::from_encoded_channels(
                    size,
                    enc,
                    SpecificChannels::build().with_channel("Y").with_pixel_fn(|p| (f16::from_f32(data[at(p)]),)),
                )
                .write()
                .to_file(tmp),
            },
        )
    })
}

/// Write two channels `R`, `G` (`width * height * 2`).
pub fn write_rg(path: &Path, width: usize, height: usize, data: &[f32], precision: Precision) -> Result<()> {
    let at = move |p: Vec2<usize>| 2 * (p.y() * width + p.x());
    atomic(path, |tmp| {
        let (size, enc) = ((width, height), Encoding::SMALL_LOSSLESS);
        finish(
            path,
            match precision {
                Precision::F32 => {
                    let ch =
                        SpecificChannels::build().with_channel("R").with_channel("G").with_pixel_fn(|p| (data[at(p)], data[at(p) + 1]));
                    Image::from_encoded_channels(size, enc, ch).write().to_file(tmp)
                }
                Precision::F16 => {
                    let ch = SpecificChannels::build()
                        .with_channel("R")
                        .with_channel("G")
                        .with_pixel_fn(|p| (f16::from_f32(data[at(p)]), f16::from_f32(data[at(p) + 1])));
                    Image::from_encoded_channels(size, enc, ch).write().to_file(tmp)
                }
            },
        )
    })
}

/// Path of buffer `name` of frame `index` in `dir`.
pub fn frame_path(dir: &Path, name: &str, index: u32) -> PathBuf {
    dir.join(format!("{name}_{index:04}.exr"))
}

/// Write every buffer of a frame.
pub fn write_frame(dir: &Path, index: u32, width: usize, height: usize, fb: &FrameBuffers, precision: Precision) -> Result<()> {
    let p = precision;
    write_rgb(&frame_path(dir, "color", index), width, height, &fb.color, p)?;
    if !fb.reference.is_empty() {
        write_rgb(&frame_path(dir, "reference", index), width, height, &fb.reference, p)?;
    }
    write_rgb(&frame_path(dir, "albedo", index), width, height, &fb.albedo, p)?;
    write_rgb(&frame_path(dir, "normal", index), width, height, &fb.normal, p)?;
    write_gray(&frame_path(dir, "depth", index), width, height, &fb.depth, p)?;
    write_gray(&frame_path(dir, "roughness", index), width, height, &fb.roughness, p)?;
    write_rg(&frame_path(dir, "motion", index), width, height, &fb.motion, p)
}

//! Frame sequences on disk: finding, validating and reading them, and writing results.
//!
//! A folder holds one sequence in one of three layouts, detected by [`Sequence::scan`]:
//! 1. **Per-buffer files**: `color_0001.exr`, `albedo_0001.exr`, `normal_0001.exr`,
//!    `depth_0001.exr`, `roughness_0001.exr`, `reference_0001.exr` (EXR half or float, any
//!    compression the exr crate reads; PNG/JPEG read as sRGB LDR).
//! 2. **Multi-layer EXR**, one file per frame, layers named by buffer: rae's names, or Blender
//!    Cycles' (`Combined`/`Image`/`Noisy Image`, `Denoising Albedo`, `Denoising Normal`,
//!    `Denoising Depth`), with or without a view-layer prefix (`ViewLayer.Combined.R`).
//! 3. **Mosaic PNG** of the reference code: 2 columns x 3 rows of tiles, noisy shading |
//!    reference shading, albedo | normal, depth | roughness. Shading times albedo gives color.
//!
//! Frame numbers come from the digits at the end of the file name; frames are sorted
//! numerically and a gap is an error. The reference buffer is never a network input: it is
//! there to measure error. Outputs are written under a temporary name in the destination folder
//! and renamed, so an interrupted run leaves no partial file.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::frame::FrameInputs;
use crate::model::InputBuffer;

/// How a folder lays out its frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    /// One file per buffer per frame.
    PerBuffer,
    /// One multi-layer EXR per frame.
    MultiLayer,
    /// One mosaic PNG per frame (reference code).
    Mosaic,
}

impl std::fmt::Display for Layout {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Layout::PerBuffer => "per-buffer files (color_NNNN.exr, ...)",
            Layout::MultiLayer => "multi-layer EXR per frame",
            Layout::Mosaic => "mosaic PNG per frame (reference code)",
        })
    }
}

/// A buffer a sequence may carry: a network input, motion, or the reference.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Slot {
    /// A renderer buffer.
    Input(InputBuffer),
    /// The clean reference (never fed to the network).
    Reference,
    /// Motion vectors, two values per pixel, in rae's convention once read
    /// ([`FrameInputs::motion`]): `motion_NNNN.exr` (R, G: rae's convention) or a multi-layer
    /// EXR's `motion` layer (likewise) or Blender's `Vector` pass (X, Y with y up: converted to
    /// (X, -Y)).
    Motion,
}

impl From<InputBuffer> for Slot {
    fn from(b: InputBuffer) -> Self {
        Slot::Input(b)
    }
}

impl Slot {
    /// The input buffer, if this is one.
    pub fn input(self) -> Option<InputBuffer> {
        match self {
            Slot::Input(b) => Some(b),
            Slot::Reference | Slot::Motion => None,
        }
    }

    /// Values per pixel.
    pub fn channels(self) -> usize {
        match self {
            Slot::Input(b) => b.channels(),
            Slot::Reference => 3,
            Slot::Motion => 2,
        }
    }

    /// rae's name.
    pub fn name(self) -> &'static str {
        match self {
            Slot::Input(b) => b.name(),
            Slot::Reference => "reference",
            Slot::Motion => "motion",
        }
    }

    fn from_name(name: &str) -> Option<Slot> {
        let lower = name.to_ascii_lowercase();
        match lower.as_str() {
            "color" | "combined" | "image" | "noisy image" | "noisy" => Some(InputBuffer::Color.into()),
            "albedo" | "denoising albedo" => Some(InputBuffer::Albedo.into()),
            "normal" | "denoising normal" => Some(InputBuffer::Normal.into()),
            "depth" | "denoising depth" => Some(InputBuffer::Depth.into()),
            "roughness" => Some(InputBuffer::Roughness.into()),
            "reference" | "clean" => Some(Slot::Reference),
            "motion" | "vector" => Some(Slot::Motion),
            _ => None,
        }
    }
}

/// Where one frame's data lives.
#[derive(Debug, Clone)]
enum FrameFiles {
    PerBuffer(BTreeMap<Slot, PathBuf>),
    MultiLayer(PathBuf),
    Mosaic(PathBuf),
}

/// Where a sequence's motion comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MotionSource {
    /// `motion_NNNN.exr` (R, G), read as written.
    Files,
    /// A multi-layer EXR's `motion` layer, read as written.
    Layer,
    /// Blender's `Vector` pass, converted to rae's convention (X, -Y) whatever the caller says.
    BlenderVector,
}

impl std::fmt::Display for MotionSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            MotionSource::Files => "motion_NNNN.exr",
            MotionSource::Layer => "the motion layer",
            MotionSource::BlenderVector => "the Vector pass, converted from Blender's convention (X, -Y)",
        })
    }
}

/// A validated sequence: every frame has the same buffers and size, numbers are contiguous.
#[derive(Debug, Clone)]
pub struct Sequence {
    /// The folder.
    pub dir: PathBuf,
    /// Its layout.
    pub layout: Layout,
    /// Frame width.
    pub width: u32,
    /// Frame height.
    pub height: u32,
    /// Frame numbers, ascending and contiguous.
    pub numbers: Vec<u32>,
    /// Buffers every frame carries (the reference included if present).
    pub slots: BTreeSet<Slot>,
    /// Layers of multi-layer EXRs that stand for no buffer rae reads (a renderer's other passes:
    /// Mist, Diffuse Direct, Cryptomatte, ...): skipped when frames are read.
    pub ignored: BTreeSet<String>,
    files: Vec<FrameFiles>,
}

/// One frame read from disk: `width * height * channels` f32 per buffer, top row first.
#[derive(Debug, Clone)]
pub struct LoadedFrame {
    /// Frame number.
    pub number: u32,
    /// Buffers by slot.
    pub buffers: BTreeMap<Slot, Vec<f32>>,
    /// Non-finite values found (a depth of +inf, a miss, is not counted): (buffer, file, count).
    pub nonfinite: Vec<(&'static str, PathBuf, usize)>,
}

impl LoadedFrame {
    /// The renderer buffers as denoiser inputs (color must be present).
    pub fn inputs(&self) -> FrameInputs<'_> {
        let get = |b: InputBuffer| self.buffers.get(&b.into()).map(|v| v.as_slice());
        FrameInputs {
            color: get(InputBuffer::Color).unwrap_or(&[]),
            albedo: get(InputBuffer::Albedo),
            normal: get(InputBuffer::Normal),
            depth: get(InputBuffer::Depth),
            roughness: get(InputBuffer::Roughness),
            motion: self.buffers.get(&Slot::Motion).map(|v| v.as_slice()),
        }
    }

    /// The reference, if the sequence has one.
    pub fn reference(&self) -> Option<&[f32]> {
        self.buffers.get(&Slot::Reference).map(|v| v.as_slice())
    }
}

fn input_err(path: &Path, reason: impl Into<String>) -> Error {
    Error::Input { path: path.to_path_buf(), reason: reason.into() }
}

/// Split `name_0012.ext` into ("name", 12); a stem of digits only gives ("", n).
fn split_number(stem: &str) -> Option<(&str, u32)> {
    let digits = stem.len() - stem.bytes().rev().take_while(|b| b.is_ascii_digit()).count();
    let n = stem[digits..].parse().ok()?;
    Some((stem[..digits].trim_end_matches(['_', '-', '.']), n))
}

fn extension(path: &Path) -> Option<String> {
    path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase())
}

/// An EXR file's channel groups (a layer or name prefix such as `albedo`), each with its
/// channel names.
type ChannelGroups = Vec<(String, Vec<String>)>;

/// An EXR file's pixels by channel group: each group's channels by name, with their values.
type GroupPixels = BTreeMap<String, Vec<(String, Vec<f32>)>>;

/// The largest frame side rae reads; a file that declares more is refused before its pixels
/// are read.
pub const MAX_SIDE: u32 = 16384;

/// The most samples (pixels times channels, over every layer) rae reads from one EXR file:
/// 4 GiB as f32. A header that declares more is refused before any pixel is read, so a
/// malformed or hostile file cannot make the reader allocate without bound.
pub const MAX_SAMPLES: u64 = 1 << 30;

/// An EXR file's headers, refused if they declare a frame past [`MAX_SIDE`] or
/// [`MAX_SAMPLES`].
fn exr_meta(path: &Path) -> Result<exr::meta::MetaData> {
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(|e| input_err(path, format!("not a readable EXR file: {e}")))?;
    check_exr_meta(path, meta)
}

fn check_exr_meta(path: &Path, meta: exr::meta::MetaData) -> Result<exr::meta::MetaData> {
    let mut samples = 0u64;
    for h in meta.headers.iter() {
        let (w, h_) = (h.layer_size.width() as u64, h.layer_size.height() as u64);
        if w > MAX_SIDE as u64 || h_ > MAX_SIDE as u64 {
            return Err(input_err(path, format!("{w}x{h_} is larger than rae reads ({MAX_SIDE} pixels a side)")));
        }
        samples += w * h_ * h.channels.list.len() as u64;
    }
    if samples > MAX_SAMPLES {
        return Err(input_err(
            path,
            format!("{samples} samples (pixels times channels) is more than rae reads from one file ({MAX_SAMPLES})"),
        ));
    }
    Ok(meta)
}

fn exr_size_and_groups(path: &Path) -> Result<((u32, u32), ChannelGroups)> {
    let meta = exr_meta(path)?;
    let mut groups: BTreeMap<String, Vec<String>> = BTreeMap::new();
    let mut size = None;
    for h in meta.headers.iter() {
        let s = (h.layer_size.width() as u32, h.layer_size.height() as u32);
        if *size.get_or_insert(s) != s {
            return Err(input_err(path, "layers of different sizes"));
        }
        let layer = h.own_attributes.layer_name.as_ref().map(|t| t.to_string());
        for c in &h.channels.list {
            let full = match &layer {
                Some(l) => format!("{l}.{}", c.name),
                None => c.name.to_string(),
            };
            let (group, chan) = match full.rsplit_once('.') {
                Some((g, c)) => (g.to_string(), c.to_string()),
                None => (String::new(), full.clone()),
            };
            groups.entry(group).or_default().push(chan);
        }
    }
    Ok((size.ok_or_else(|| input_err(path, "no layers"))?, groups.into_iter().collect()))
}

fn image_size(path: &Path) -> Result<(u32, u32)> {
    if extension(path).as_deref() == Some("exr") {
        return Ok(exr_size_and_groups(path)?.0);
    }
    let (w, h) = image::image_dimensions(path).map_err(|e| input_err(path, format!("not a readable image: {e}")))?;
    if w > MAX_SIDE || h > MAX_SIDE {
        return Err(input_err(path, format!("{w}x{h} is larger than rae reads ({MAX_SIDE} pixels a side)")));
    }
    Ok((w, h))
}

/// The buffer a multi-layer group name stands for ("ViewLayer.Denoising Albedo" -> albedo).
fn slot_of_group(group: &str) -> Option<Slot> {
    Slot::from_name(group).or_else(|| group.rsplit_once('.').and_then(|(_, last)| Slot::from_name(last)))
}

/// [`slot_of_group`], where channels with no layer name (R, G, B) are color.
fn group_slot(group: &str) -> Option<Slot> {
    if group.is_empty() { Some(InputBuffer::Color.into()) } else { slot_of_group(group) }
}

impl Sequence {
    /// Find and validate the sequence in `dir`.
    pub fn scan(dir: &Path) -> Result<Sequence> {
        let entries = std::fs::read_dir(dir).map_err(|e| input_err(dir, format!("cannot read the folder: {e}")))?;
        let mut files: Vec<PathBuf> = Vec::new();
        for e in entries {
            let p = e.map_err(|e| input_err(dir, e.to_string()))?.path();
            let hidden = p.file_name().is_some_and(|n| n.to_string_lossy().starts_with('.'));
            if p.is_file() && !hidden && matches!(extension(&p).as_deref(), Some("exr" | "png" | "jpg" | "jpeg")) {
                files.push(p);
            }
        }
        files.sort();
        if files.is_empty() {
            return Err(input_err(
                dir,
                "no frames: expected color_0001.exr (and albedo_, normal_, depth_, roughness_, reference_), one multi-layer .exr per frame, or mosaic .png frames",
            ));
        }
        // Per-buffer files are named after a buffer.
        let mut per_buffer: BTreeMap<u32, BTreeMap<Slot, PathBuf>> = BTreeMap::new();
        for f in &files {
            if let Some((slot, n)) = per_buffer_name(&f.file_name().unwrap_or_default().to_string_lossy()) {
                if let Some(prev) = per_buffer.entry(n).or_default().insert(slot, f.clone()) {
                    return Err(input_err(f, format!("frame {n} of `{}` is also in {}", slot.name(), prev.display())));
                }
            }
        }
        let (layout, numbered): (Layout, Vec<(u32, FrameFiles)>) = if !per_buffer.is_empty() {
            (Layout::PerBuffer, per_buffer.into_iter().map(|(n, m)| (n, FrameFiles::PerBuffer(m))).collect())
        } else {
            let exrs: Vec<&PathBuf> = files.iter().filter(|f| extension(f).as_deref() == Some("exr")).collect();
            let (layout, chosen) = if !exrs.is_empty() {
                (Layout::MultiLayer, exrs)
            } else {
                (Layout::Mosaic, files.iter().filter(|f| extension(f).as_deref() == Some("png")).collect())
            };
            let mut v = Vec::new();
            for f in chosen {
                let stem = f.file_stem().unwrap_or_default().to_string_lossy().to_string();
                let (_, n) = split_number(&stem).ok_or_else(|| input_err(f, "no frame number at the end of the file name"))?;
                if v.iter().any(|(m, _)| *m == n) {
                    return Err(input_err(f, format!("a second file for frame {n}")));
                }
                v.push((n, if layout == Layout::MultiLayer { FrameFiles::MultiLayer(f.clone()) } else { FrameFiles::Mosaic(f.clone()) }));
            }
            v.sort_by_key(|(n, _)| *n);
            (layout, v)
        };
        if numbered.is_empty() {
            return Err(input_err(dir, "no frames found (no color_NNNN, multi-layer EXR or mosaic PNG)"));
        }
        // Contiguous numbering.
        for w in numbered.windows(2) {
            if w[1].0 != w[0].0 + 1 {
                return Err(input_err(dir, format!("frame {} is missing (frames {} and {} are present)", w[0].0 + 1, w[0].0, w[1].0)));
            }
        }
        let first = &numbered[0];
        let (mut width, mut height) = (0, 0);
        let mut slots: Option<BTreeSet<Slot>> = None;
        let mut ignored = BTreeSet::new();
        for (n, ff) in &numbered {
            let (here, size, at) = match ff {
                FrameFiles::PerBuffer(m) => {
                    let color = m
                        .get(&InputBuffer::Color.into())
                        .ok_or_else(|| input_err(dir, format!("frame {n} has no color buffer (color_{n:04}.exr); color is required")))?;
                    let size = image_size(color)?;
                    for (slot, p) in m {
                        let s = image_size(p)?;
                        if s != size {
                            return Err(input_err(p, format!("{}x{} differs from {}x{} of {}", s.0, s.1, size.0, size.1, color.display())));
                        }
                        let _ = slot;
                    }
                    (m.keys().copied().collect::<BTreeSet<_>>(), size, color.clone())
                }
                FrameFiles::MultiLayer(p) => {
                    let (size, groups) = exr_size_and_groups(p)?;
                    let mut here = BTreeSet::new();
                    for (g, _) in &groups {
                        match group_slot(g) {
                            Some(s) => {
                                here.insert(s);
                            }
                            None => {
                                ignored.insert(g.clone());
                            }
                        }
                    }
                    if !here.contains(&InputBuffer::Color.into()) {
                        return Err(input_err(
                            p,
                            format!(
                                "no color layer (color, Combined, Image or Noisy Image) among the layers {:?}; known: color, albedo (Denoising Albedo), normal (Denoising Normal), depth (Denoising Depth), roughness, reference, motion (Vector)",
                                groups.iter().map(|(g, _)| g).collect::<Vec<_>>()
                            ),
                        ));
                    }
                    (here, size, p.clone())
                }
                FrameFiles::Mosaic(p) => {
                    let (w, h) = image_size(p)?;
                    if w % 2 != 0 || h % 3 != 0 {
                        return Err(input_err(p, format!("{w}x{h} is not a 2x3 mosaic of equal tiles")));
                    }
                    let all = [InputBuffer::Color, InputBuffer::Albedo, InputBuffer::Normal, InputBuffer::Depth, InputBuffer::Roughness];
                    let mut here: BTreeSet<Slot> = all.into_iter().map(Slot::from).collect();
                    here.insert(Slot::Reference);
                    (here, (w / 2, h / 3), p.clone())
                }
            };
            if *n == first.0 {
                (width, height) = size;
            } else if size != (width, height) {
                return Err(input_err(&at, format!("frame {n} is {}x{}, frame {} is {width}x{height}", size.0, size.1, first.0)));
            }
            match &slots {
                None => slots = Some(here),
                Some(s) if *s != here => {
                    let missing: Vec<_> = s.symmetric_difference(&here).map(|s| s.name()).collect();
                    return Err(input_err(&at, format!("frame {n} differs from frame {} in buffers {missing:?}", first.0)));
                }
                _ => {}
            }
        }
        Ok(Sequence {
            dir: dir.to_path_buf(),
            layout,
            width,
            height,
            numbers: numbered.iter().map(|(n, _)| *n).collect(),
            slots: slots.unwrap_or_default(),
            ignored,
            files: numbered.into_iter().map(|(_, f)| f).collect(),
        })
    }

    /// Whether the sequence has a reference to measure error against.
    pub fn has_reference(&self) -> bool {
        self.slots.contains(&Slot::Reference)
    }

    /// Whether the frames carry motion.
    pub fn has_motion(&self) -> bool {
        self.slots.contains(&Slot::Motion)
    }

    /// Where the frames' motion comes from, if they have any.
    pub fn motion_source(&self) -> Option<MotionSource> {
        if !self.has_motion() {
            return None;
        }
        Some(match (&self.layout, self.files.first()) {
            (Layout::MultiLayer, Some(FrameFiles::MultiLayer(p))) => {
                if exr_size_and_groups(p).is_ok_and(|(_, g)| g.iter().any(|(name, _)| is_blender_vector(name))) {
                    MotionSource::BlenderVector
                } else {
                    MotionSource::Layer
                }
            }
            _ => MotionSource::Files,
        })
    }

    /// Input buffers present.
    pub fn inputs(&self) -> Vec<InputBuffer> {
        self.slots.iter().filter_map(|s| s.input()).collect()
    }

    /// The file holding `buffer` of frame index `i` (for messages).
    pub fn file_of(&self, i: usize, slot: Slot) -> PathBuf {
        match &self.files[i] {
            FrameFiles::PerBuffer(m) => m.get(&slot).cloned().unwrap_or_else(|| self.dir.clone()),
            FrameFiles::MultiLayer(p) | FrameFiles::Mosaic(p) => p.clone(),
        }
    }

    /// Read frame index `i` (not number).
    pub fn load(&self, i: usize) -> Result<LoadedFrame> {
        let (w, h) = (self.width as usize, self.height as usize);
        let mut buffers = BTreeMap::new();
        match &self.files[i] {
            FrameFiles::PerBuffer(m) => {
                for (slot, p) in m {
                    buffers.insert(*slot, read_buffer_file(p, *slot)?);
                }
            }
            FrameFiles::MultiLayer(p) => {
                for (slot, data) in read_multilayer(p, w, h)? {
                    buffers.insert(slot, data);
                }
            }
            FrameFiles::Mosaic(p) => buffers = read_mosaic(p, w, h)?,
        }
        let mut nonfinite = Vec::new();
        for (slot, data) in &buffers {
            if *slot == Slot::Motion {
                // NaN or infinite motion drops that pixel's history (FrameInputs::motion).
                continue;
            }
            let depth = *slot == Slot::from(InputBuffer::Depth);
            let bad = data.iter().filter(|v| !(v.is_finite() || (depth && **v == f32::INFINITY))).count();
            if bad > 0 {
                nonfinite.push((slot.name(), self.file_of(i, *slot), bad));
            }
        }
        Ok(LoadedFrame { number: self.numbers[i], buffers, nonfinite })
    }
}

fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}

/// Channels of a slot from named EXR channels: RGB, XYZ, or one of Y, Z, R, V.
fn pick_channels(path: &Path, slot: Slot, chans: &[(String, Vec<f32>)], n: usize) -> Result<Vec<f32>> {
    let find = |name: &str| chans.iter().find(|(c, _)| c.eq_ignore_ascii_case(name)).map(|(_, d)| d);
    let picked: Vec<&Vec<f32>> = if slot.channels() == 3 {
        ["R", "G", "B"]
            .iter()
            .map(|c| find(c))
            .collect::<Option<Vec<_>>>()
            .or_else(|| ["X", "Y", "Z"].iter().map(|c| find(c)).collect::<Option<Vec<_>>>())
            .ok_or_else(|| {
                input_err(
                    path,
                    format!(
                        "`{}` needs R, G, B (or X, Y, Z) channels; found {:?}",
                        slot.name(),
                        chans.iter().map(|c| &c.0).collect::<Vec<_>>()
                    ),
                )
            })?
    } else if slot.channels() == 2 {
        ["R", "G"]
            .iter()
            .map(|c| find(c))
            .collect::<Option<Vec<_>>>()
            .or_else(|| ["X", "Y"].iter().map(|c| find(c)).collect::<Option<Vec<_>>>())
            .ok_or_else(|| {
                input_err(
                    path,
                    format!("`motion` needs R, G (or X, Y) channels; found {:?}", chans.iter().map(|c| &c.0).collect::<Vec<_>>()),
                )
            })?
    } else {
        vec![
            ["Y", "Z", "R", "V"]
                .iter()
                .find_map(|c| find(c))
                .or(chans.first().map(|(_, d)| d))
                .ok_or_else(|| input_err(path, format!("`{}` has no channel", slot.name())))?,
        ]
    };
    let mut out = vec![0f32; n * picked.len()];
    for (k, data) in picked.iter().enumerate() {
        for (i, v) in data.iter().enumerate().take(n) {
            out[i * picked.len() + k] = *v;
        }
    }
    Ok(out)
}

fn read_exr_groups(path: &Path) -> Result<GroupPixels> {
    exr_meta(path)?;
    let image = exr::prelude::read_all_flat_layers_from_file(path).map_err(|e| input_err(path, format!("cannot read EXR: {e}")))?;
    Ok(image_groups(&image))
}

/// The channel groups of a decoded EXR image.
fn image_groups(image: &exr::image::FlatImage) -> GroupPixels {
    let mut groups = GroupPixels::new();
    for layer in &image.layer_data {
        let lname = layer.attributes.layer_name.as_ref().map(|t| t.to_string());
        for c in &layer.channel_data.list {
            let full = match &lname {
                Some(l) => format!("{l}.{}", c.name),
                None => c.name.to_string(),
            };
            let (g, ch) = full.rsplit_once('.').map(|(g, c)| (g.to_string(), c.to_string())).unwrap_or((String::new(), full.clone()));
            groups.entry(g).or_default().push((ch, c.sample_data.values_as_f32().collect()));
        }
    }
    groups
}

fn read_buffer_file(path: &Path, slot: Slot) -> Result<Vec<f32>> {
    let file = std::fs::File::open(path).map_err(|e| input_err(path, format!("cannot open: {e}")))?;
    read_buffer(path, std::io::BufReader::new(file), slot).map(|(_, values)| values)
}

/// An 8-bit image's RGB values as a slot's: normals from [0, 1] to [-1, 1], depth and roughness
/// from the red channel, the rest from sRGB to linear.
fn ldr_values(px: &[f32], slot: Slot) -> Vec<f32> {
    match slot.input() {
        Some(InputBuffer::Normal) => px.iter().map(|v| v * 2.0 - 1.0).collect(),
        Some(InputBuffer::Depth | InputBuffer::Roughness) => px.chunks_exact(3).map(|c| c[0]).collect(),
        _ => px.iter().map(|v| srgb_to_linear(*v)).collect(),
    }
}

/// The buffer and frame number a per-buffer file's name gives (`albedo_0012.exr`: albedo,
/// 12), for files that come without a folder (a browser's file picker); `None` for names that
/// are not an EXR, PNG or JPEG file named after a buffer.
pub fn per_buffer_name(file_name: &str) -> Option<(Slot, u32)> {
    let path = Path::new(file_name);
    if !matches!(extension(path).as_deref(), Some("exr" | "png" | "jpg" | "jpeg")) {
        return None;
    }
    let stem = path.file_stem()?.to_string_lossy();
    let (name, n) = split_number(&stem)?;
    if name.is_empty() {
        return None;
    }
    Some((Slot::from_name(name)?, n))
}

/// Read one buffer of a per-buffer file held in memory (a fetched or picked file), as
/// [`Sequence::load`] reads it from disk: `file_name` gives the format (by extension) and
/// names the file in errors. Returns the image's size and the slot's values, interleaved.
pub fn read_buffer_bytes(file_name: &str, bytes: &[u8], slot: Slot) -> Result<((u32, u32), Vec<f32>)> {
    read_buffer(Path::new(file_name), std::io::Cursor::new(bytes), slot)
}

/// One buffer of a per-buffer file from `source` (`path` gives the format and names it in
/// errors): its size and the slot's values. An EXR's headers are checked against [`MAX_SIDE`]
/// and [`MAX_SAMPLES`] before its pixels are read (decoded on every core, or on the one thread a
/// browser has); an 8-bit image's size against [`MAX_SIDE`].
fn read_buffer<R: std::io::BufRead + std::io::Seek>(path: &Path, mut source: R, slot: Slot) -> Result<((u32, u32), Vec<f32>)> {
    use exr::prelude::{ReadChannels, ReadLayers};
    if extension(path).as_deref() == Some("exr") {
        let meta = exr::meta::MetaData::read_from_buffered(&mut source, false)
            .map_err(|e| input_err(path, format!("not a readable EXR file: {e}")))?;
        let meta = check_exr_meta(path, meta)?;
        let mut sizes = meta.headers.iter().map(|h| (h.layer_size.width() as u32, h.layer_size.height() as u32));
        let size = sizes.next().ok_or_else(|| input_err(path, "no layers"))?;
        if sizes.any(|s| s != size) {
            return Err(input_err(path, "layers of different sizes"));
        }
        source.seek(std::io::SeekFrom::Start(0)).map_err(|e| input_err(path, e.to_string()))?;
        let reader = exr::prelude::read().no_deep_data().largest_resolution_level().all_channels().all_layers().all_attributes();
        #[cfg(target_arch = "wasm32")]
        let reader = reader.non_parallel();
        let image = reader.from_buffered(source).map_err(|e| input_err(path, format!("cannot read EXR: {e}")))?;
        let groups = image_groups(&image);
        let chans = groups.get("").or_else(|| groups.values().next()).ok_or_else(|| input_err(path, "no channels"))?;
        let values = pick_channels(path, slot, chans, size.0 as usize * size.1 as usize)?;
        return Ok((size, values));
    }
    let img = image::ImageReader::new(source)
        .with_guessed_format()
        .map_err(|e| input_err(path, format!("cannot read image: {e}")))?
        .decode()
        .map_err(|e| input_err(path, format!("cannot read image: {e}")))?
        .to_rgb32f();
    if img.width() > MAX_SIDE || img.height() > MAX_SIDE {
        return Err(input_err(path, format!("{}x{} is larger than rae reads ({MAX_SIDE} pixels a side)", img.width(), img.height())));
    }
    Ok(((img.width(), img.height()), ldr_values(img.as_raw(), slot)))
}

/// Whether a multi-layer EXR's motion group is Blender's `Vector` pass (`ViewLayer.Vector`).
fn is_blender_vector(group: &str) -> bool {
    group.rsplit('.').next().is_some_and(|last| last.eq_ignore_ascii_case("vector"))
}

fn read_multilayer(path: &Path, w: usize, h: usize) -> Result<Vec<(Slot, Vec<f32>)>> {
    let groups = read_exr_groups(path)?;
    groups
        .iter()
        .filter_map(|(g, chans)| group_slot(g).map(|slot| (g, chans, slot)))
        .map(|(g, chans, slot)| {
            let mut data = pick_channels(path, slot, chans, w * h)?;
            if slot == Slot::Motion && is_blender_vector(g) {
                // Blender's raster y points up: rae's motion is (X, -Y).
                data.iter_mut().skip(1).step_by(2).for_each(|y| *y = -*y);
            }
            Ok((slot, data))
        })
        .collect()
}

fn read_mosaic(path: &Path, w: usize, h: usize) -> Result<BTreeMap<Slot, Vec<f32>>> {
    let img = image::open(path).map_err(|e| input_err(path, format!("cannot read image: {e}")))?.to_rgb32f();
    let tile = |col: usize, row: usize| -> Vec<f32> {
        let mut v = Vec::with_capacity(w * h * 3);
        for y in 0..h {
            for x in 0..w {
                v.extend_from_slice(&img.get_pixel((col * w + x) as u32, (row * h + y) as u32).0);
            }
        }
        v
    };
    let lin = |v: Vec<f32>| -> Vec<f32> { v.into_iter().map(srgb_to_linear).collect() };
    let albedo = lin(tile(0, 1));
    // Shading tiles are demodulated: color = shading * albedo.
    let remodulate = |s: Vec<f32>| -> Vec<f32> { s.iter().zip(&albedo).map(|(s, a)| s * a).collect() };
    let mut out = BTreeMap::new();
    out.insert(InputBuffer::Color.into(), remodulate(lin(tile(0, 0))));
    out.insert(Slot::Reference, remodulate(lin(tile(1, 0))));
    out.insert(InputBuffer::Normal.into(), tile(1, 1).into_iter().map(|v| v * 2.0 - 1.0).collect());
    out.insert(InputBuffer::Depth.into(), tile(0, 2).chunks_exact(3).map(|c| c[0]).collect());
    out.insert(InputBuffer::Roughness.into(), tile(1, 2).chunks_exact(3).map(|c| c[0]).collect());
    out.insert(InputBuffer::Albedo.into(), albedo);
    Ok(out)
}

fn atomic_write(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let name = path.file_name().map(|n| n.to_string_lossy().to_string()).unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.partial"));
    let result = write(&tmp).and_then(|_| {
        std::fs::rename(&tmp, path).map_err(|e| Error::Output { path: path.into(), reason: format!("cannot rename into place: {e}") })
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Write a text file (a CSV, a report) atomically.
pub fn write_text(path: &Path, text: &str) -> Result<()> {
    atomic_write(path, |tmp| std::fs::write(tmp, text).map_err(|e| Error::Output { path: path.into(), reason: e.to_string() }))
}

/// Write RGB radiance as an EXR (f32, or f16 with `half`), atomically.
pub fn write_exr(path: &Path, width: u32, height: u32, rgb: &[f32], half: bool) -> Result<()> {
    write_exr_channels(path, width, height, &["R", "G", "B"], rgb, half)
}

/// Write an EXR of the named channels, `data` interleaved (`width * height * names.len()`,
/// top row first), ZIP-compressed, f32 or f16 with `half` (beyond 65504 becomes infinite),
/// atomically: under a temporary name, renamed into place once whole.
pub fn write_exr_channels(path: &Path, width: u32, height: u32, names: &[&str], data: &[f32], half: bool) -> Result<()> {
    use exr::prelude::*;
    let n = names.len();
    debug_assert_eq!(data.len(), width as usize * height as usize * n);
    let channels: SmallVec<[AnyChannel<FlatSamples>; 4]> = names
        .iter()
        .enumerate()
        .map(|(c, name)| {
            let values = data.iter().skip(c).step_by(n);
            let samples = if half {
                FlatSamples::F16(values.map(|&v| f16::from_f32(v)).collect())
            } else {
                FlatSamples::F32(values.copied().collect())
            };
            AnyChannel::new(*name, samples)
        })
        .collect();
    let size = (width as usize, height as usize);
    let layer = Layer::new(size, LayerAttributes::default(), Encoding::SMALL_LOSSLESS, AnyChannels::sort(channels));
    atomic_write(path, |tmp| {
        Image::from_layer(layer).write().to_file(tmp).map_err(|e| crate::error::Error::Output { path: path.into(), reason: e.to_string() })
    })
}

/// Tone map (x / (1 + x), then sRGB) to 8 bits: what previews and the metrics look at.
pub fn tonemap(v: f32) -> f32 {
    let x = if v.is_finite() { v.max(0.0) } else { 0.0 };
    let t = x / (1.0 + x);
    if t <= 0.0031308 { 12.92 * t } else { 1.055 * t.powf(1.0 / 2.4) - 0.055 }
}

/// [`tonemap`] to an 8-bit value, as previews show it.
pub fn tonemap_u8(v: f32) -> u8 {
    (tonemap(v) * 255.0 + 0.5) as u8
}

/// Write a tonemapped sRGB PNG preview, atomically.
pub fn write_png(path: &Path, width: u32, height: u32, rgb: &[f32]) -> Result<()> {
    let bytes: Vec<u8> = rgb.iter().map(|&v| tonemap_u8(v)).collect();
    atomic_write(path, |tmp| {
        image::save_buffer_with_format(tmp, &bytes, width, height, image::ExtendedColorType::Rgb8, image::ImageFormat::Png)
            .map_err(|e| Error::Output { path: path.into(), reason: e.to_string() })
    })
}

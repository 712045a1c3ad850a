//! One frame's per-buffer files (`color_0007.exr`, `albedo_0007.exr`, ...), decoded by
//! rae-core's readers as the page hands them over.

use std::collections::BTreeMap;

use rae_core::io::{self, Slot};
use rae_core::{FrameInputs, InputBuffer};
use wasm_bindgen::prelude::*;

/// One frame of a per-buffer sequence, decoded file by file ([`Frame::add`]).
#[wasm_bindgen]
#[derive(Default)]
pub struct Frame {
    size: Option<(u32, u32)>,
    number: Option<u32>,
    /// Each buffer's file name and values (interleaved, top row first).
    buffers: BTreeMap<Slot, (String, Vec<f32>)>,
}

#[wasm_bindgen]
impl Frame {
    /// An empty frame.
    #[wasm_bindgen(constructor)]
    pub fn new() -> Frame {
        Frame::default()
    }

    /// Decode one of the frame's files. A name that is not a buffer's (`color_`, `albedo_`,
    /// `normal_`, `depth_`, `roughness_`, `motion_`, `reference_`, then the frame number, then
    /// `.exr`, `.png` or `.jpg`), a file that does not read, a buffer given twice, or a size
    /// or frame number unlike the frame's other files' is an error naming the file.
    pub fn add(&mut self, name: &str, bytes: &[u8]) -> Result<(), JsError> {
        let (slot, number) = io::per_buffer_name(name).ok_or_else(|| {
            JsError::new(&format!(
                "{name}: not a per-buffer file (color_0001.exr, albedo_, normal_, depth_, roughness_, motion_, reference_; EXR, PNG or JPEG)"
            ))
        })?;
        if let Some(n) = self.number.filter(|&n| n != number) {
            return Err(JsError::new(&format!("{name}: frame {number}, but this frame is {n}")));
        }
        if let Some((other, _)) = self.buffers.get(&slot) {
            return Err(JsError::new(&format!("{name}: `{}` of frame {number} is also in {other}", slot.name())));
        }
        let (size, values) = io::read_buffer_bytes(name, bytes, slot).map_err(|e| JsError::new(&e.to_string()))?;
        if let Some(s) = self.size.filter(|&s| s != size) {
            return Err(JsError::new(&format!("{name}: {}x{}, but the frame's other files are {}x{}", size.0, size.1, s.0, s.1)));
        }
        self.size = Some(size);
        self.number = Some(number);
        self.buffers.insert(slot, (name.to_string(), values));
        Ok(())
    }

    /// Frame width (0 before the first file).
    pub fn width(&self) -> u32 {
        self.size.map_or(0, |s| s.0)
    }

    /// Frame height (0 before the first file).
    pub fn height(&self) -> u32 {
        self.size.map_or(0, |s| s.1)
    }

    /// The frame number its files' names give.
    pub fn number(&self) -> Option<u32> {
        self.number
    }

    /// The buffers present, by rae's names.
    pub fn buffers(&self) -> Vec<String> {
        self.buffers.keys().map(|s| s.name().to_string()).collect()
    }

    /// Whether the frame has a reference to measure the error against.
    #[wasm_bindgen(js_name = hasReference)]
    pub fn has_reference(&self) -> bool {
        self.buffers.contains_key(&Slot::Reference)
    }

    /// Whether the frame has motion to reproject the hidden state with.
    #[wasm_bindgen(js_name = hasMotion)]
    pub fn has_motion(&self) -> bool {
        self.buffers.contains_key(&Slot::Motion)
    }

    /// `color` or `reference` tone mapped as rae's previews are, as RGBA bytes for a canvas.
    pub fn rgba(&self, buffer: &str) -> Result<Vec<u8>, JsError> {
        let slot = match buffer {
            "color" => Slot::Input(InputBuffer::Color),
            "reference" => Slot::Reference,
            _ => return Err(JsError::new(&format!("no preview of `{buffer}`: color or reference"))),
        };
        let (_, values) = self.buffers.get(&slot).ok_or_else(|| JsError::new(&format!("the frame has no {buffer}")))?;
        Ok(crate::rgba(values))
    }
}

impl Frame {
    /// A buffer's values, if present.
    pub(crate) fn get(&self, slot: Slot) -> Option<&[f32]> {
        self.buffers.get(&slot).map(|(_, v)| v.as_slice())
    }

    /// The frame as the denoiser takes it; an error without a color file.
    pub(crate) fn inputs(&self) -> Result<FrameInputs<'_>, String> {
        let input = |b: InputBuffer| self.get(Slot::Input(b));
        let color = input(InputBuffer::Color).ok_or_else(|| match self.number {
            Some(n) => format!("frame {n} has no color file (color_{n:04}.exr)"),
            None => "the frame has no files".to_string(),
        })?;
        Ok(FrameInputs {
            color,
            albedo: input(InputBuffer::Albedo),
            normal: input(InputBuffer::Normal),
            depth: input(InputBuffer::Depth),
            roughness: input(InputBuffer::Roughness),
            motion: self.get(Slot::Motion),
        })
    }
}

/// The frame number a per-buffer file's name gives (`albedo_0012.exr`: 12), for grouping
/// picked files into frames; `undefined` for other names.
#[wasm_bindgen(js_name = frameNumber)]
pub fn frame_number(name: &str) -> Option<u32> {
    io::per_buffer_name(name).map(|(_, n)| n)
}

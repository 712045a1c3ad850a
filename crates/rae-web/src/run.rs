//! A denoiser for one frame size and set of buffers, with the GPU buffers the page's frames
//! go through, and the GPU's verdicts on them as futures.

use std::cell::RefCell;
use std::future::Future;
use std::pin::Pin;
use std::rc::Rc;
use std::sync::{Arc, Mutex};

use rae_core::{Denoiser, FrameInputs, GpuFrameIo, InputBuffer, IoBinding, Options, Tile, TileChoice, Weights};
use wasm_bindgen::JsValue;

/// What a [`Run`] is built for: frames of another size, or with motion where the last had
/// none (or the reverse), need another.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct RunKey {
    pub width: u32,
    pub height: u32,
    pub motion: bool,
    /// Whether frames with motion have their output accumulated along it (the page's frames,
    /// as `rae-cli denoise`); the golden frames hold the network alone.
    pub accumulate: bool,
}

/// A denoiser and the buffers bound to it: one per input the model reads, motion, the output
/// and its readback. Made once per [`RunKey`]; a frame allocates nothing.
pub(crate) struct Run {
    pub key: RunKey,
    pub denoiser: Denoiser,
    inputs: Vec<(InputBuffer, wgpu::Buffer)>,
    motion: Option<wgpu::Buffer>,
    output: wgpu::Buffer,
    pub readback: wgpu::Buffer,
    binding: IoBinding,
}

impl Run {
    /// Build the denoiser and its buffers for `key`, inside error scopes whose verdict the
    /// caller awaits.
    pub fn build(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        weights: &Weights,
        key: RunKey,
        tile: Option<Tile>,
    ) -> rae_core::Result<(Run, GpuVerdict)> {
        let scopes = Scopes::push(device);
        let run = Self::make(device, queue, weights, key, tile);
        let verdict = scopes.pop();
        run.map(|r| (r, verdict))
    }

    fn make(device: &wgpu::Device, queue: &wgpu::Queue, weights: &Weights, key: RunKey, tile: Option<Tile>) -> rae_core::Result<Run> {
        let tiles = tile.map_or(TileChoice::Auto, TileChoice::Fixed);
        let options = Options { motion: key.motion, accumulate: key.accumulate, tiles, ..Default::default() };
        let denoiser = Denoiser::with_options(device, queue, weights, key.width, key.height, options)?;
        let pixels = key.width as u64 * key.height as u64;
        let buffer = |label: &str, channels: u64, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: pixels * channels * 4,
                usage,
                mapped_at_creation: false,
            })
        };
        let input = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let inputs: Vec<_> =
            weights.arch.required_buffers().into_iter().map(|b| (b, buffer(b.name(), b.channels() as u64, input))).collect();
        let motion = key.motion.then(|| buffer("motion", 2, input));
        let output = buffer("output", 3, wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC);
        let readback = buffer("readback", 3, wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST);
        let binding = denoiser.bind_io(&GpuFrameIo::from_inputs(&inputs, motion.as_ref(), &output))?;
        Ok(Run { key, denoiser, inputs, motion, output, readback, binding })
    }

    /// Upload a frame (validated against the model's buffers), record it and its readback
    /// copy into one encoder and submit it, inside error scopes whose verdict the caller awaits.
    pub fn submit(&mut self, queue: &wgpu::Queue, device: &wgpu::Device, frame: &FrameInputs) -> rae_core::Result<GpuVerdict> {
        let needed: Vec<_> = self.inputs.iter().map(|(b, _)| *b).collect();
        frame.validate(&needed, self.key.width, self.key.height)?;
        let scopes = Scopes::push(device);
        for (b, buf) in &self.inputs {
            queue.write_buffer(buf, 0, bytemuck::cast_slice(frame.get(*b).expect("validated")));
        }
        if let (Some(buf), Some(m)) = (&self.motion, frame.motion) {
            queue.write_buffer(buf, 0, bytemuck::cast_slice(m));
        }
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("rae frame") });
        let recorded = self.denoiser.record(&mut encoder, &self.binding);
        encoder.copy_buffer_to_buffer(&self.output, 0, &self.readback, 0, self.output.size());
        queue.submit(Some(encoder.finish()));
        let verdict = scopes.pop();
        recorded.map(|_| verdict)
    }

    /// The last submitted frame's output, once the GPU has written it.
    pub async fn read(&self) -> Result<Vec<f32>, String> {
        read_buffer(&self.readback).await
    }
}

/// Map a MAP_READ buffer of f32s, copy it out and unmap it; the browser maps it when the GPU
/// is done, and the page's event loop runs meanwhile.
pub(crate) async fn read_buffer(buffer: &wgpu::Buffer) -> Result<Vec<f32>, String> {
    let mapped = Rc::new(RefCell::new(None));
    let promise = js_sys::Promise::new(&mut |resolve, _reject| {
        let mapped = mapped.clone();
        buffer.map_async(wgpu::MapMode::Read, .., move |r| {
            *mapped.borrow_mut() = Some(r);
            let _ = resolve.call0(&JsValue::UNDEFINED);
        });
    });
    wasm_bindgen_futures::JsFuture::from(promise).await.map_err(|e| format!("reading the output back: {e:?}"))?;
    let result = mapped.borrow_mut().take().expect("set before the promise resolves");
    result.map_err(|e| format!("reading the output back: {e}"))?;
    let out = {
        let view = buffer.get_mapped_range(..).map_err(|e| format!("reading the output back: {e:?}"))?;
        bytemuck::pod_collect_to_vec::<u8, f32>(&view)
    };
    buffer.unmap();
    Ok(out)
}

/// A validation and an out-of-memory scope, pushed before some GPU work.
struct Scopes {
    oom: wgpu::ErrorScopeGuard,
    validation: wgpu::ErrorScopeGuard,
}

impl Scopes {
    fn push(device: &wgpu::Device) -> Scopes {
        let oom = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
        Scopes { oom, validation }
    }

    /// Pop both now (the innermost first); their verdicts come later.
    fn pop(self) -> GpuVerdict {
        let validation: VerdictFuture = Box::pin(self.validation.pop());
        let oom: VerdictFuture = Box::pin(self.oom.pop());
        GpuVerdict { scopes: vec![validation, oom] }
    }
}

type VerdictFuture = Pin<Box<dyn Future<Output = Option<wgpu::Error>>>>;

/// Error scopes popped around GPU work, whose verdicts the page's event loop delivers.
pub(crate) struct GpuVerdict {
    scopes: Vec<VerdictFuture>,
}

impl GpuVerdict {
    /// Both verdicts, `first`'s (where there is one) first.
    pub fn both(first: Option<GpuVerdict>, then: GpuVerdict) -> GpuVerdict {
        let mut scopes = first.map_or_else(Vec::new, |f| f.scopes);
        scopes.extend(then.scopes);
        GpuVerdict { scopes }
    }

    /// Await the verdicts: the first error any scope caught, or the first the device reported
    /// outside them (`errors`), is an error saying what was being done.
    pub async fn check(self, errors: &Arc<Mutex<Vec<String>>>, what: &str) -> Result<(), JsValue> {
        for scope in self.scopes {
            if let Some(e) = scope.await {
                return Err(crate::js_err(format!("{what}: {e}")).into());
            }
        }
        match errors.lock().unwrap_or_else(|e| e.into_inner()).first() {
            Some(e) => Err(crate::js_err(format!("{what}: {e}")).into()),
            None => Ok(()),
        }
    }
}

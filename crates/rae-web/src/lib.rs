//! rae in a web page: rae-core on the browser's WebGPU, driven from JavaScript through
//! wasm-bindgen. `www/` holds the page; `bash scripts/web.sh` builds and serves it.
//!
//! A [`Session`] opens the browser's GPU ([`Session::open`]), holds a model
//! ([`Session::load_weights`]) and a [`rae_core::Denoiser`] for the current frame size and
//! buffers, built again when they change. A [`Frame`] decodes one frame's per-buffer files with
//! rae-core's readers. [`Session::denoise`] uploads a frame, records it into one encoder, submits
//! it and resolves, once the GPU is done, to a [`Denoised`]: the output and its error against the
//! reference. [`Session::verify_golden`] holds the browser to PyTorch's golden frames.
//!
//! Everything runs on the page's one thread: the GPU's verdicts (error scopes, mapped buffers)
//! come back as promises the page awaits, never by blocking. What the kernels would use and a
//! browser may lack (subgroups, f16, timestamps inside passes) is chosen from the device's
//! features as on native: wgpu's WebGPU backend reports no subgroups, so the plain tiles run.
#![cfg(target_arch = "wasm32")]

mod frame;
mod run;

use std::cell::RefCell;
use std::rc::Rc;
use std::sync::{Arc, Mutex};

use rae_core::golden::{Golden, Tolerance};
use rae_core::io::Slot;
use rae_core::{InputBuffer, Weights, metrics};
use wasm_bindgen::prelude::*;

pub use frame::{Frame, frame_number};
use run::{GpuVerdict, Run, RunKey};

/// RGB radiance tone mapped as rae's previews are ([`rae_core::io::tonemap`]) to RGBA bytes.
pub(crate) fn rgba(rgb: &[f32]) -> Vec<u8> {
    rgb.chunks_exact(3).flat_map(|c| [c[0], c[1], c[2]].map(rae_core::io::tonemap_u8).into_iter().chain([255])).collect()
}

/// Panics reach the browser's console with their message.
fn install_panic_hook() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        std::panic::set_hook(Box::new(|info| web_sys::console::error_1(&info.to_string().into())));
    });
}

/// The browser's GPU, the model and the denoiser of the current frames.
#[wasm_bindgen]
pub struct Session {
    inner: Rc<RefCell<Inner>>,
}

struct Inner {
    /// The instance the adapter and device came from, held with them.
    _instance: wgpu::Instance,
    adapter: wgpu::Adapter,
    device: wgpu::Device,
    queue: wgpu::Queue,
    weights: Option<Weights>,
    run: Option<Run>,
    /// A frame is in flight: its readback is not mapped back yet.
    busy: bool,
    /// The conv tile every conv runs, where the page fixes one ([`Session::set_tile`]).
    tile: Option<rae_core::Tile>,
    /// Errors outside any error scope, and why the device was lost, as they come.
    errors: Arc<Mutex<Vec<String>>>,
}

impl Inner {
    /// The first error the device reported outside a scope, if any (then every later frame
    /// fails: the page must open a new session).
    fn device_error(&self) -> Option<String> {
        self.errors.lock().unwrap_or_else(|e| e.into_inner()).first().cloned()
    }
}

/// One denoised frame.
#[wasm_bindgen]
pub struct Denoised {
    output: Vec<f32>,
    width: u32,
    height: u32,
}

/// Errors of a frame's noisy input and of its denoised output against its reference
/// ([`rae_core::metrics`]: relMSE on radiance, PSNR and SSIM tone mapped).
#[wasm_bindgen]
#[derive(Clone, Copy)]
pub struct FrameErrors {
    /// relMSE of the input.
    #[wasm_bindgen(js_name = relmseIn)]
    pub relmse_in: f64,
    /// relMSE of the output.
    #[wasm_bindgen(js_name = relmseOut)]
    pub relmse_out: f64,
    /// PSNR of the input, dB.
    #[wasm_bindgen(js_name = psnrIn)]
    pub psnr_in: f64,
    /// PSNR of the output, dB.
    #[wasm_bindgen(js_name = psnrOut)]
    pub psnr_out: f64,
    /// SSIM of the input.
    #[wasm_bindgen(js_name = ssimIn)]
    pub ssim_in: f64,
    /// SSIM of the output.
    #[wasm_bindgen(js_name = ssimOut)]
    pub ssim_out: f64,
}

#[wasm_bindgen]
impl Denoised {
    /// RGB radiance, `width * height * 3`, top row first.
    pub fn output(&self) -> Vec<f32> {
        self.output.clone()
    }

    /// The output tone mapped to RGBA bytes for a canvas.
    pub fn rgba(&self) -> Vec<u8> {
        rgba(&self.output)
    }

    /// Frame width.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Frame height.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The errors of `frame` (the frame this was denoised from) and of this output against
    /// the frame's reference; `undefined` without one.
    pub fn errors(&self, frame: &Frame) -> Option<FrameErrors> {
        let color = frame.get(Slot::Input(InputBuffer::Color))?;
        let r = frame.get(Slot::Reference)?;
        if r.len() != self.output.len() {
            return None;
        }
        let (w, h) = (self.width, self.height);
        Some(FrameErrors {
            relmse_in: metrics::relmse(color, r),
            relmse_out: metrics::relmse(&self.output, r),
            psnr_in: metrics::psnr(color, r),
            psnr_out: metrics::psnr(&self.output, r),
            ssim_in: metrics::ssim(color, r, w, h),
            ssim_out: metrics::ssim(&self.output, r, w, h),
        })
    }
}

/// How a golden sequence compared with PyTorch in this browser.
#[wasm_bindgen]
pub struct GoldenResult {
    /// Frames compared.
    pub frames: u32,
    /// Largest error over the allowed `1e-4 * max(1, |torch|)` (at most 1 passes).
    pub worst: f32,
    /// Largest absolute difference.
    #[wasm_bindgen(js_name = maxAbs)]
    pub max_abs: f32,
}

fn js_err(e: impl std::fmt::Display) -> JsError {
    JsError::new(&e.to_string())
}

#[wasm_bindgen]
impl Session {
    /// Open the browser's GPU through WebGPU. `default_limits` asks for WebGPU's default
    /// limits rather than the adapter's (what every browser must give: the page's test runs
    /// with them). Without WebGPU, the error says so.
    pub async fn open(default_limits: bool) -> Result<Session, JsError> {
        install_panic_hook();
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = wgpu::Backends::BROWSER_WEBGPU;
        let instance = wgpu::Instance::new(desc);
        let adapter = instance
            .request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                force_fallback_adapter: false,
                compatible_surface: None,
                ..Default::default()
            })
            .await
            .map_err(|e| js_err(format!("this browser gives no WebGPU adapter ({e}): rae needs WebGPU")))?;
        // Optional features the kernels use where present; the rest fall back (module docs).
        let wanted = wgpu::Features::SHADER_F16 | wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::SUBGROUP;
        let required_limits = if default_limits { wgpu::Limits::default() } else { adapter.limits() };
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("rae"),
                required_features: adapter.features() & wanted,
                required_limits,
                ..Default::default()
            })
            .await
            .map_err(|e| js_err(format!("the WebGPU adapter gives no device: {e}")))?;
        let errors = Arc::new(Mutex::new(Vec::new()));
        let sink = errors.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            sink.lock().unwrap_or_else(|e| e.into_inner()).push(format!("GPU error: {e}"));
        }));
        let sink = errors.clone();
        device.set_device_lost_callback(move |reason, message| {
            sink.lock().unwrap_or_else(|e| e.into_inner()).push(format!("the GPU device was lost ({reason:?}): {message}"));
        });
        let inner = Inner { _instance: instance, adapter, device, queue, weights: None, run: None, busy: false, tile: None, errors };
        Ok(Session { inner: Rc::new(RefCell::new(inner)) })
    }

    /// The adapter, its features that matter to rae and the limits in force, for the page.
    pub fn adapter(&self) -> String {
        let inner = self.inner.borrow();
        let info = inner.adapter.get_info();
        let f = inner.device.features();
        let has = |x: wgpu::Features| if f.contains(x) { "yes" } else { "no" };
        let l = inner.device.limits();
        format!(
            "{} ({:?}, {:?}); shader-f16 {}, subgroups {}, timestamps {}; {} invocations a workgroup, {} storage textures a stage, textures up to {}",
            if info.name.is_empty() { "WebGPU adapter" } else { &info.name },
            info.backend,
            info.device_type,
            has(wgpu::Features::SHADER_F16),
            has(wgpu::Features::SUBGROUP),
            has(wgpu::Features::TIMESTAMP_QUERY),
            l.max_compute_invocations_per_workgroup,
            l.max_storage_textures_per_shader_stage,
            l.max_texture_dimension_2d,
        )
    }

    /// Load a weights file (safetensors with rae's metadata; `name` names it in errors);
    /// returns the buffers the model reads. The next frame builds its denoiser.
    #[wasm_bindgen(js_name = loadWeights)]
    pub fn load_weights(&self, name: &str, bytes: &[u8]) -> Result<Vec<String>, JsError> {
        let weights = Weights::from_bytes(bytes, name).map_err(js_err)?;
        let buffers = weights.arch.required_buffers().iter().map(|b| b.name().to_string()).collect();
        let mut inner = self.inner.borrow_mut();
        inner.weights = Some(weights);
        inner.run = None;
        Ok(buffers)
    }

    /// Run every conv with this tile (`16x2`, `4x1`, ...: rae-cli's names) instead of the one
    /// rae-core picks for the device, from the next frame; an empty text restores the choice.
    #[wasm_bindgen(js_name = setTile)]
    pub fn set_tile(&self, tile: &str) -> Result<(), JsError> {
        let tile = if tile.is_empty() { None } else { Some(tile.parse().map_err(js_err)?) };
        let mut inner = self.inner.borrow_mut();
        inner.tile = tile;
        inner.run = None;
        Ok(())
    }

    /// Forget the hidden state: the next frame starts a sequence.
    pub fn reset(&self) {
        if let Some(run) = self.inner.borrow_mut().run.as_mut() {
            run.denoiser.reset();
        }
    }

    /// Denoise `frame` with the hidden state of the frames before it (motion, where the frame
    /// has it, reprojects that state and accumulates the output along it), resolving to a [`Denoised`] once the GPU is done. Await
    /// each frame before the next: a frame in flight refuses another.
    pub fn denoise(&self, frame: &Frame) -> js_sys::Promise {
        let started = self.submit_frame(frame);
        let inner = self.inner.clone();
        let (width, height) = (frame.width(), frame.height());
        wasm_bindgen_futures::future_to_promise(async move {
            let output = finish(&inner, started).await?;
            Ok(Denoised { output, width, height }.into())
        })
    }

    /// Run a golden file of weights-tool (`python -m rae_weights golden`) with its weights
    /// and hold every frame to PyTorch's output; resolves to a [`GoldenResult`]. Uses a
    /// denoiser of its own: the session's frames and state are untouched.
    #[wasm_bindgen(js_name = verifyGolden)]
    pub fn verify_golden(&self, name: &str, golden: &[u8], weights: &[u8]) -> js_sys::Promise {
        let prepared = Golden::from_bytes(golden, name)
            .and_then(|g| Ok((Weights::from_bytes(weights, &g.weights)?, g)))
            .map_err(|e| JsValue::from(js_err(e)));
        let (device, queue, errors, tile) = {
            let i = self.inner.borrow();
            (i.device.clone(), i.queue.clone(), i.errors.clone(), i.tile)
        };
        wasm_bindgen_futures::future_to_promise(async move {
            let (weights, golden) = prepared?;
            let motion = golden.frames[0].contains_key("motion");
            let key = RunKey { width: golden.width, height: golden.height, motion, accumulate: false };
            let (mut run, built) = Run::build(&device, &queue, &weights, key, tile).map_err(js_err)?;
            built.check(&errors, &format!("{}: building the denoiser", golden.weights)).await?;
            let (mut worst, mut max_abs) = (0f32, 0f32);
            for f in 0..golden.frames.len() {
                let verdict = run.submit(&queue, &device, &golden.inputs(f)).map_err(js_err)?;
                verdict.check(&errors, &format!("golden frame {f}")).await?;
                let out = run.read().await.map_err(js_err)?;
                let (ratio, _, abs) = Tolerance::GOLDEN.worst(&out, golden.expected(f));
                worst = worst.max(ratio);
                max_abs = max_abs.max(abs);
            }
            Ok(GoldenResult { frames: golden.frames.len() as u32, worst, max_abs }.into())
        })
    }
}

impl Session {
    /// The synchronous part of a frame: the denoiser (built for this frame's size and
    /// buffers where the last one was not), the upload, the record and the submit.
    fn submit_frame(&self, frame: &Frame) -> Result<GpuVerdict, JsValue> {
        let mut inner = self.inner.borrow_mut();
        if inner.busy {
            return Err(js_err("a frame is still in flight: await each frame before the next").into());
        }
        if let Some(e) = inner.device_error() {
            return Err(js_err(e).into());
        }
        let inputs = frame.inputs().map_err(js_err)?;
        let inner = &mut *inner;
        let weights = inner.weights.as_ref().ok_or_else(|| js_err("no model loaded"))?;
        let motion = inputs.motion.is_some();
        let key = RunKey { width: frame.width(), height: frame.height(), motion, accumulate: motion };
        let mut built = None;
        if inner.run.as_ref().is_none_or(|r| r.key != key) {
            inner.run = None;
            let (run, verdict) = Run::build(&inner.device, &inner.queue, weights, key, inner.tile).map_err(js_err)?;
            inner.run = Some(run);
            built = Some(verdict);
        }
        let Inner { run, device, queue, .. } = inner;
        let verdict = run.as_mut().expect("built above").submit(queue, device, &inputs).map_err(js_err)?;
        inner.busy = true;
        Ok(GpuVerdict::both(built, verdict))
    }
}

/// The asynchronous part of a frame: the GPU's verdict on it, then its output read back.
async fn finish(inner: &Rc<RefCell<Inner>>, started: Result<GpuVerdict, JsValue>) -> Result<Vec<f32>, JsValue> {
    let verdict = started?;
    let (errors, readback) = {
        let i = inner.borrow();
        (i.errors.clone(), i.run.as_ref().expect("submitted").readback.clone())
    };
    let result = match verdict.check(&errors, "denoising the frame").await {
        Ok(()) => run::read_buffer(&readback).await.map_err(|e| JsValue::from(js_err(e))),
        Err(e) => Err(e),
    };
    let mut i = inner.borrow_mut();
    i.busy = false;
    if result.is_err() {
        // A denoiser that failed part way is built again for the next frame.
        i.run = None;
    }
    result
}

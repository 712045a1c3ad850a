//! Opening a GPU: adapter choice that honours `WGPU_BACKEND` and `WGPU_ADAPTER_NAME`.

use crate::error::{Error, Result};

/// An adapter with its device and queue.
pub struct Gpu {
    /// The adapter chosen.
    pub adapter: wgpu::Adapter,
    /// Its device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// Why the device was lost, once it is (its device-lost callback writes it).
    lost: std::sync::Arc<std::sync::Mutex<Option<String>>>,
}

/// Mesa's llvmpipe (lavapipe) variable for the width of its vectors in bits; a subgroup is that
/// many bits of 32-bit lanes.
pub const LAVAPIPE_VECTOR_WIDTH: &str = "LP_NATIVE_VECTOR_WIDTH";

/// Ask lavapipe for 512-bit vectors (16-lane subgroups) when the CPU has AVX-512F and
/// `LP_NATIVE_VECTOR_WIDTH` is unset; returns whether it set the variable.
///
/// Mesa 22.3 compiles for 256 bits on every AVX2 CPU, AVX-512 or not. On this project's
/// machines (AMD EPYC with AVX-512) a 256x256 frame of the default network takes about 0.7x
/// the time at 512 bits with bit-identical output (`docs/perf/lavapipe-2026-11-24-s11.log`): half
/// the instructions for the same work, where the unrolled conv bodies were bound by the CPU's
/// front end. Tiles without weights across the lanes (`16x4`, for devices without subgroups)
/// run 2x slower at 512 bits, their per-lane weight gathers twice as wide; lavapipe has
/// subgroups, so [`crate::Tile::cpu`] never picks one there. The driver reads the variable once, when the Vulkan loader opens it, so this must
/// run before the first [`Gpu::new`] or [`adapters`]. Other drivers ignore it.
///
/// Mesa's shader cache does not key on the width: shaders compiled at one width are served at
/// the other (correct, but at the speed they were compiled for). Clear the cache
/// (`MESA_SHADER_CACHE_DIR`, by default `~/.cache/mesa_shader_cache`) after changing it.
///
/// # Safety
///
/// Sets a process environment variable, so no other thread may be reading or writing the
/// environment: call it first thing in `main`, before any thread starts
/// ([`std::env::set_var`]'s contract).
pub unsafe fn prefer_wide_cpu_vectors() -> bool {
    if std::env::var_os(LAVAPIPE_VECTOR_WIDTH).is_some() || !cpu_has_avx512() {
        return false;
    }
    // SAFETY: the caller guarantees no other thread touches the environment.
    unsafe { std::env::set_var(LAVAPIPE_VECTOR_WIDTH, "512") };
    true
}

/// Whether the CPU has AVX-512F (the 512-bit vectors lavapipe can use).
fn cpu_has_avx512() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx512f")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Set to `0`, [`Gpu`] does not enable cooperative matrices, so Mma tiles run emulated on a
/// device that has matrix units: the same tiles' two paths side by side.
pub const MATRIX_UNITS_VAR: &str = "RAE_MATRIX_UNITS";

/// Whether an adapter has what [`crate::Method::Mma`] runs on in matrix units: wgpu's
/// cooperative matrices with a 16 x 16 x 16 configuration of f16 products summed in f32, and
/// subgroups of exactly 32 lanes (conv3x3_mma_coop.wgsl counts a workgroup's subgroups in 32s).
/// [`Gpu`] enables [`wgpu::Features::EXPERIMENTAL_COOPERATIVE_MATRIX`] only where this holds,
/// and [`crate::kernels::matrix_units_supported`] trusts a device with the feature to have it.
pub fn has_matrix_units(adapter: &wgpu::Adapter) -> bool {
    let info = adapter.get_info();
    adapter.features().contains(wgpu::Features::EXPERIMENTAL_COOPERATIVE_MATRIX | wgpu::Features::SHADER_F16 | wgpu::Features::SUBGROUP)
        && info.subgroup_min_size == 32
        && info.subgroup_max_size == 32
        && adapter.cooperative_matrix_properties().iter().any(|m| {
            (m.m_size, m.n_size, m.k_size) == (16, 16, 16)
                && m.ab_type == wgpu::CooperativeScalarType::F16
                && m.cr_type == wgpu::CooperativeScalarType::F32
        })
}

/// The adapters wgpu sees under the current `WGPU_BACKEND`.
pub fn adapters() -> Vec<wgpu::Adapter> {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::all());
    pollster::block_on(instance.enumerate_adapters(backends))
}

/// Preference among adapters (after the name filter): real GPUs, then CPU drivers; Vulkan first.
fn rank(info: &wgpu::AdapterInfo) -> (u8, u8) {
    let device = match info.device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Cpu => 3,
        wgpu::DeviceType::Other => 4,
    };
    let backend = if info.backend == wgpu::Backend::Vulkan { 0 } else { 1 };
    (device, backend)
}

impl Gpu {
    /// Open the adapter named by `WGPU_ADAPTER_NAME` (a case-insensitive substring, e.g.
    /// `llvmpipe` for lavapipe) or else the best one, with the optional features rae uses
    /// (SHADER_F16, TIMESTAMP_QUERY, SUBGROUP, SHADER_INT64) enabled where the adapter has them.
    pub fn new() -> Result<Self> {
        let wanted = std::env::var("WGPU_ADAPTER_NAME").ok().filter(|s| !s.is_empty());
        let all = adapters();
        let seen = all.iter().map(|a| format!("{} ({:?})", a.get_info().name, a.get_info().backend)).collect::<Vec<_>>();
        let name = wanted.as_ref().map(|w| w.to_lowercase()).unwrap_or_default();
        let chosen = all.into_iter().filter(|a| a.get_info().name.to_lowercase().contains(&name)).min_by_key(|a| rank(&a.get_info()));
        let adapter = chosen.ok_or_else(|| Error::NoAdapter {
            wanted: wanted.map(|w| format!(" matching WGPU_ADAPTER_NAME={w}")).unwrap_or_default(),
            seen: seen.join(", "),
        })?;
        Self::from_adapter(adapter)
    }

    /// Open a device on a given adapter, with wgpu's experimental cooperative matrices where
    /// the adapter has the configuration [`crate::Method::Mma`] runs on ([`has_matrix_units`])
    /// and [`MATRIX_UNITS_VAR`] is not `0`.
    pub fn from_adapter(adapter: wgpu::Adapter) -> Result<Self> {
        let mut optional = wgpu::Features::SHADER_F16
            | wgpu::Features::TIMESTAMP_QUERY
            | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS
            | wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES
            | wgpu::Features::SUBGROUP
            | wgpu::Features::SHADER_INT64;
        // RAE_MATRIX_UNITS=0 leaves them off: Mma tiles then run emulated, for comparison.
        let matrix_units = has_matrix_units(&adapter) && std::env::var(MATRIX_UNITS_VAR).map_or(true, |v| v != "0");
        if matrix_units {
            optional |= wgpu::Features::EXPERIMENTAL_COOPERATIVE_MATRIX;
        }
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("rae"),
            required_features: adapter.features() & optional,
            required_limits: adapter.limits(),
            // SAFETY: the one experimental feature asked for is cooperative matrices, and only
            // conv3x3_mma_coop.wgsl uses them (wgpu warns its experimental features may have
            // bugs; the golden tests hold that kernel's output to PyTorch's on such devices).
            experimental_features: if matrix_units {
                unsafe { wgpu::ExperimentalFeatures::enabled() }
            } else {
                wgpu::ExperimentalFeatures::disabled()
            },
            ..Default::default()
        }))?;
        let lost = std::sync::Arc::new(std::sync::Mutex::new(None));
        let record = lost.clone();
        device.set_device_lost_callback(move |reason, message| {
            *record.lock().unwrap_or_else(|e| e.into_inner()) = Some(format!("{reason:?}: {message}"));
        });
        Ok(Self { adapter, device, queue, lost })
    }

    /// Why the device was lost (a driver reset, a crash, [`wgpu::Device::destroy`]), if it
    /// was: after that every frame fails, and a new `Gpu` and `Denoiser` are needed.
    pub fn lost(&self) -> Option<String> {
        self.lost.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }

    /// Name and backend of the adapter, for reports.
    pub fn describe(&self) -> String {
        let i = self.adapter.get_info();
        format!("{} ({:?}, {:?})", i.name, i.backend, i.device_type)
    }
}

/// A second device that compiles a denoiser's pipelines from the other end while its first
/// frame runs, on CPU drivers and only when that frame is slow to come.
///
/// Lavapipe compiles a pipeline with LLVM at its first dispatch, on its device's one queue
/// thread, and keeps the result in Mesa's shader cache on disk. Into an empty cache a
/// denoiser's first frame compiles its pipelines first stage first on one core for tens of
/// seconds while the other core idles. The helper builds the same denoiser on a second device of
/// the same adapter and dispatches its stages last stage first
/// ([`crate::Denoiser::compile_backwards`]) on the other core: the two meet in the middle and the
/// frame finds the rest in the cache. With a warm cache the first frame comes about as soon as
/// any other, sooner than the helper could even build, so the helper starts only if the frame
/// has not come after [`CompileHelper::delay`]: a second plus the frame's arithmetic at
/// [`CompileHelper::SLOW_FLOPS`].
pub struct CompileHelper {
    /// Dropped when the first frame has come (the watcher then sees its channel closed).
    done: Option<std::sync::mpsc::Sender<()>>,
    watcher: std::thread::JoinHandle<()>,
}

impl CompileHelper {
    /// A rate (FLOP/s) below any CPU driver's for a warm frame: lavapipe runs the default
    /// network at 55-75 GFLOP/s on this project's 2-core machine at 512 bits, 40-55 at 256.
    pub const SLOW_FLOPS: f64 = 25e9;

    /// How long the first frame of a denoiser doing `frame_flops` may take before the helper
    /// starts: 1 s plus `frame_flops` at [`Self::SLOW_FLOPS`] (1.1 s at 128x128, 6.6 s at 720p
    /// for the default network), so that a warm cache never starts it.
    pub fn delay(frame_flops: f64) -> std::time::Duration {
        std::time::Duration::from_secs_f64(1.0 + frame_flops / Self::SLOW_FLOPS)
    }

    /// Watch for a slow first frame of a denoiser like `weights` x `options` at `width` x
    /// `height` on `gpu`, calling `on_start` (on the helper's thread) if the helper starts;
    /// `None` unless `gpu` is a CPU driver (GPU drivers compile when a pipeline is made, on the
    /// threads that make it).
    pub fn start(
        gpu: &Gpu,
        weights: &crate::Weights,
        width: u32,
        height: u32,
        options: crate::Options,
        on_start: impl FnOnce() + Send + 'static,
    ) -> Option<Self> {
        let info = gpu.adapter.get_info();
        if info.device_type != wgpu::DeviceType::Cpu {
            return None;
        }
        let multiple = 1u32 << weights.arch.levels();
        let pixels = width.next_multiple_of(multiple) as f64 * height.next_multiple_of(multiple) as f64;
        let delay = Self::delay(2.0 * crate::graph::Graph::new(&weights.arch).macs_per_pixel() * pixels);
        let weights = weights.clone();
        let (done, first_frame) = std::sync::mpsc::channel::<()>();
        let watcher = std::thread::spawn(move || {
            if first_frame.recv_timeout(delay) != Err(std::sync::mpsc::RecvTimeoutError::Timeout) {
                return;
            }
            // A second device on the same adapter (a fresh instance finds it by name), or none.
            let Some(adapter) = adapters().into_iter().find(|a| a.get_info().name == info.name && a.get_info().backend == info.backend)
            else {
                return;
            };
            on_start();
            // Failures only cost the first frame its speed-up: the frame compiles everything.
            let _ = Gpu::from_adapter(adapter)
                .and_then(|g| crate::Denoiser::with_options(&g.device, &g.queue, &weights, width, height, options)?.compile_backwards());
        });
        Some(Self { done: Some(done), watcher })
    }

    /// The first frame has come: a helper not started yet never starts (cheap to call after
    /// every frame).
    pub fn first_frame_done(&mut self) {
        self.done = None;
    }

    /// Wait for the helper to finish (its last dispatches find the frame's pipelines in the cache).
    pub fn finish(mut self) {
        self.done = None;
        let _ = self.watcher.join();
    }
}

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
    /// (SHADER_F16, TIMESTAMP_QUERY, SUBGROUP) enabled where the adapter has them.
    pub fn new() -> Result<Self> {
        let wanted = std::env::var("WGPU_ADAPTER_NAME").ok().filter(|s| !s.is_empty());
        let all = adapters();
        let seen = all.iter().map(|a| format!("{} ({:?})", a.get_info().name, a.get_info().backend)).collect::<Vec<_>>();
        let name = wanted.as_ref().map(|w| w.to_lowercase()).unwrap_or_default();
        let chosen = all
            .into_iter()
            .filter(|a| a.get_info().name.to_lowercase().contains(&name))
            .min_by_key(|a| rank(&a.get_info()));
        let adapter = chosen.ok_or_else(|| Error::NoAdapter {
            wanted: wanted.map(|w| format!(" matching WGPU_ADAPTER_NAME={w}")).unwrap_or_default(),
            seen: seen.join(", "),
        })?;
        Self::from_adapter(adapter)
    }

    /// Open a device on a given adapter.
    pub fn from_adapter(adapter: wgpu::Adapter) -> Result<Self> {
        let optional = wgpu::Features::SHADER_F16
            | wgpu::Features::TIMESTAMP_QUERY
            | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS
            | wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES
            | wgpu::Features::SUBGROUP;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("rae"),
            required_features: adapter.features() & optional,
            required_limits: adapter.limits(),
            ..Default::default()
        }))?;
        Ok(Self { adapter, device, queue })
    }

    /// Name and backend of the adapter, for reports.
    pub fn describe(&self) -> String {
        let i = self.adapter.get_info();
        format!("{} ({:?}, {:?})", i.name, i.backend, i.device_type)
    }
}

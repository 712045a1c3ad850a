//! Faults beyond parsing: a device that is lost, a frame larger than the device takes, and
//! GPU memory that runs out each give an error, never a panic or a hang.

use std::panic::AssertUnwindSafe;
use std::sync::mpsc;
use std::time::Duration;

use rae_core::{Denoiser, FrameInputs, Gpu, Options, Weights};

use crate::fixture;

/// Runs `f` on a thread of its own: its result, or a failure if it panics or takes more than
/// two minutes (a hang).
fn within_two_minutes<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let r = std::panic::catch_unwind(AssertUnwindSafe(f));
        let _ = tx.send(r);
    });
    match rx.recv_timeout(Duration::from_secs(120)) {
        Ok(Ok(v)) => v,
        Ok(Err(panic)) => {
            panic!("it panicked: {:?}", panic.downcast_ref::<String>().map(String::as_str).or(panic.downcast_ref::<&str>().copied()))
        }
        Err(_) => panic!("it hung: no result in two minutes"),
    }
}

#[test]
fn a_lost_device_is_an_error_and_not_a_panic_or_a_hang() {
    let message = within_two_minutes(|| {
        // A device of its own: losing it must not take other tests' devices with it.
        let gpu = Gpu::new().unwrap();
        let weights = Weights::load(fixture("weights_color_tiny.safetensors")).unwrap();
        let mut d = Denoiser::with_options(&gpu.device, &gpu.queue, &weights, 16, 16, Options::default()).unwrap();
        let color = vec![0.5f32; 16 * 16 * 3];
        let frame = FrameInputs { color: &color, albedo: None, normal: None, depth: None, roughness: None, motion: None };
        d.denoise(&frame).expect("a frame before the loss");
        assert_eq!(gpu.lost(), None);
        gpu.device.destroy();
        (d.denoise(&frame).err().map(|e| e.to_string()), gpu.lost())
    });
    assert!(message.0.is_some(), "a frame on a lost device is an error");
    let reason = message.1.expect("the Gpu knows its device was lost");
    assert!(reason.contains("Destroyed"), "{reason}");
}

#[test]
fn buffers_past_the_device_limits_are_an_error_not_a_panic() {
    let message = within_two_minutes(|| {
        // The adapter's own device, asked for 1 MiB buffers at most: a 256x256 frame of the
        // full model needs more than that for its activations and input pack.
        let adapter = crate::gpu().adapter.clone();
        let limits = wgpu::Limits { max_buffer_size: 1 << 20, max_storage_buffer_binding_size: 1 << 20, ..adapter.limits() };
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("small limits"),
            required_features: adapter.features() & wgpu::Features::SUBGROUP,
            required_limits: limits,
            ..Default::default()
        }))
        .unwrap();
        let weights = Weights::load(fixture("weights_full.safetensors")).unwrap();
        Denoiser::with_options(&device, &queue, &weights, 256, 256, Options::default()).err().map(|e| e.to_string())
    });
    let message = message.expect("a denoiser past the device's limits is an error");
    assert!(message.contains("256x256"), "{message}");
}

#[test]
fn a_frame_past_the_device_texture_limit_is_an_error_naming_the_limit() {
    let g = crate::gpu();
    let weights = Weights::load(fixture("weights_color_tiny.safetensors")).unwrap();
    let max = g.device.limits().max_texture_dimension_2d;
    for (w, h) in [(max + 1, 16), (16, max + 1), (0, 16)] {
        let err = Denoiser::with_options(&g.device, &g.queue, &weights, w, h, Options::default()).err().map(|e| e.to_string());
        let err = err.unwrap_or_else(|| panic!("{w}x{h} is refused"));
        assert!(err.contains(&format!("{w}x{h}")) && (err.contains(&max.to_string()) || err.contains("empty")), "{err}");
    }
}

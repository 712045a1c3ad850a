//! rae-core's tests, in three tiers: no GPU (naga validation of every shader, weights files),
//! each kernel against the CPU reference on lavapipe, and end-to-end goldens from PyTorch.
//!
//! Fixtures in tests/fixtures are written by weights-tool:
//!     cd weights-tool && python -m rae_weights golden --out ../tests/fixtures

mod accumulate;
mod faults;
mod frame_path;
mod generated;
mod golden;
mod io;
mod kernels;
mod metrics;
mod mma;
mod shaders;
mod stability;
mod state;
mod tiles;
mod weights;
mod winograd;

use std::path::PathBuf;
use std::sync::Mutex;

use rae_core::Gpu;
pub use rae_core::golden::{Golden, Tolerance};

/// The fixtures folder.
pub fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures").join(name)
}

/// The cases of a shared-vectors fixture (tensors named `caseK.what`), sorted, each once.
pub fn vector_cases(st: &safetensors::SafeTensors) -> Vec<String> {
    let mut cases: Vec<String> = st.names().iter().map(|n| n.split('.').next().unwrap().to_string()).collect();
    cases.sort();
    cases.dedup();
    cases
}

/// Devices no running test holds.
static IDLE: Mutex<Vec<&'static Gpu>> = Mutex::new(Vec::new());

/// A test thread's device, back to [`IDLE`] when the thread ends.
struct Lease(&'static Gpu);

impl Drop for Lease {
    fn drop(&mut self) {
        IDLE.lock().unwrap_or_else(|e| e.into_inner()).push(self.0);
    }
}

thread_local! {
    static LEASE: Lease = Lease(IDLE.lock().unwrap_or_else(|e| e.into_inner()).pop().unwrap_or_else(|| {
        let gpu = Gpu::new().unwrap_or_else(|e| panic!("{e}"));
        eprintln!("GPU tests run on {}", gpu.describe());
        Box::leak(Box::new(gpu))
    }));
}

/// The device of this test (lavapipe in CI): one per test running at the same time, reused by
/// later tests. Lavapipe compiles a pipeline at its first dispatch, on its device's one queue
/// thread, so tests sharing one device would compile one after another while the other core
/// idles (most of the suite's time in CI goes to compiling); libtest runs each test on a
/// thread of its own, and a device per running test compiles side by side.
pub fn gpu() -> &'static Gpu {
    LEASE.with(|l| l.0)
}

/// Load a golden fixture by file name.
pub fn golden(name: &str) -> Golden {
    Golden::load(fixture(name)).unwrap_or_else(|e| panic!("{e}"))
}

/// Panic with the place and values of the worst violation of `tol`, if any.
pub fn assert_close(tol: Tolerance, what: &str, actual: &[f32], expected: &[f32]) {
    let (ratio, i, max_abs) = tol.worst(actual, expected);
    assert!(
        ratio <= 1.0,
        "{what}: value {i}: got {}, expected {} (error {ratio:.3}x the tolerance {tol:?}; max abs error {max_abs:e})",
        actual[i],
        expected[i],
    );
}

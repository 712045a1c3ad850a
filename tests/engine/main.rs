//! rae-core's tests, in three tiers: no GPU (naga validation of every shader, weights files),
//! each kernel against the CPU reference on lavapipe, and end-to-end goldens from PyTorch.
//!
//! Fixtures in tests/fixtures are written by weights-tool:
//!     cd weights-tool && python -m rae_weights golden --out ../tests/fixtures

mod golden;
mod kernels;
mod shaders;
mod stability;
mod state;
mod weights;

use std::path::PathBuf;
use std::sync::OnceLock;

pub use rae_core::golden::{Golden, Tolerance};
use rae_core::Gpu;

/// The fixtures folder.
pub fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures").join(name)
}

/// One device shared by every GPU test of this binary (lavapipe in CI).
pub fn gpu() -> &'static Gpu {
    static GPU: OnceLock<Gpu> = OnceLock::new();
    GPU.get_or_init(|| {
        let gpu = Gpu::new().unwrap_or_else(|e| panic!("{e}"));
        eprintln!("GPU tests run on {}", gpu.describe());
        gpu
    })
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

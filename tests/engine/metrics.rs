//! rae-core's metrics against the vectors weights-tool's metrics are held to
//! (tests/fixtures/metrics_vectors.safetensors, written by `python -m rae_weights golden`).

use rae_core::metrics;
use safetensors::SafeTensors;

use crate::{fixture, vector_cases};

/// Tensor `name` of `st` as f32 or f64 values, widened to f64.
fn values(st: &SafeTensors, name: &str) -> Vec<f64> {
    let t = st.tensor(name).unwrap_or_else(|e| panic!("{name}: {e}"));
    match t.dtype() {
        safetensors::Dtype::F32 => t.data().chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().unwrap()) as f64).collect(),
        safetensors::Dtype::F64 => t.data().chunks_exact(8).map(|b| f64::from_le_bytes(b.try_into().unwrap())).collect(),
        d => panic!("{name}: dtype {d:?}"),
    }
}

#[test]
fn metrics_give_the_shared_vectors_values() {
    let bytes = std::fs::read(fixture("metrics_vectors.safetensors")).unwrap();
    let st = SafeTensors::deserialize(&bytes).unwrap();
    let cases = vector_cases(&st);
    assert!(cases.len() >= 4, "{cases:?}");
    for case in cases {
        let image = |k: &str| values(&st, &format!("{case}.{k}")).into_iter().map(|v| v as f32).collect::<Vec<f32>>();
        let (xp, x, rp, r) = (image("x_prev"), image("x"), image("r_prev"), image("r"));
        let shape = st.tensor(&format!("{case}.x")).unwrap().shape().to_vec();
        let (h, w) = (shape[0] as u32, shape[1] as u32);
        let got = [metrics::relmse(&x, &r), metrics::psnr(&x, &r), metrics::ssim(&x, &r, w, h), metrics::temporal_error(&xp, &x, &rp, &r)];
        let want = values(&st, &format!("{case}.expected"));
        // rae-core tone maps in f32, weights-tool in f64.
        for ((name, g), e) in ["relmse", "psnr", "ssim", "temporal"].iter().zip(got).zip(want) {
            assert!((g - e).abs() <= 1e-5 * e.abs().max(1e-3), "{case} {name}: rae-core {g}, weights-tool {e}");
        }
    }
}

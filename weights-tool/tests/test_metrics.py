"""The metrics against the shared vectors (tests/fixtures/metrics_vectors.safetensors), which
rae-core's metrics.rs is held to as well (tests/engine/metrics.rs)."""

from pathlib import Path

import numpy as np
from safetensors.numpy import load_file

from rae_weights import metrics

VECTORS = Path(__file__).resolve().parents[2] / "tests" / "fixtures" / metrics.VECTORS_FILE


def test_metrics_give_the_shared_vectors_values() -> None:
    v = load_file(str(VECTORS))
    cases = sorted({k.split(".")[0] for k in v})
    assert len(cases) >= 4
    for c in cases:
        xp, x, rp, r = (v[f"{c}.{k}"] for k in ("x_prev", "x", "r_prev", "r"))
        got = [metrics.relmse(x, r), metrics.psnr(x, r), metrics.ssim(x, r), metrics.temporal_error(xp, x, rp, r)]
        np.testing.assert_allclose(got, v[f"{c}.expected"], rtol=1e-12, err_msg=c)


def test_the_shared_vectors_are_what_the_generator_writes() -> None:
    v, fresh = load_file(str(VECTORS)), metrics.shared_vectors()
    assert sorted(v) == sorted(fresh)
    # Inputs are seeded and equal bit for bit; the expected metrics are float64 reductions whose
    # last bit may differ between machines and thread counts.
    for k in v:
        np.testing.assert_allclose(v[k], fresh[k], rtol=1e-12, atol=0, err_msg=k)

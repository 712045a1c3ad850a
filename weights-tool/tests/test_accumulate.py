"""The output's temporal accumulation: its properties, and the shared vectors
(tests/fixtures/accumulate_vectors.safetensors) that rae-core's accumulate.rs is held to as well
(tests/engine/accumulate.rs)."""

from pathlib import Path

import numpy as np
import torch
from safetensors.numpy import load_file

from rae_weights import accumulate

VECTORS = Path(__file__).resolve().parents[2] / "tests" / "fixtures" / accumulate.VECTORS_FILE


def _frames(seed: int = 1) -> tuple[torch.Tensor, torch.Tensor]:
    g = torch.Generator().manual_seed(seed)
    return torch.rand(1, 3, 8, 10, generator=g) * 4, torch.rand(1, 3, 8, 10, generator=g) * 4


def test_without_history_or_motion_the_output_is_the_networks() -> None:
    cur, prev = _frames()
    assert torch.equal(accumulate.accumulate(cur, None, torch.zeros(1, 2, 8, 10)), cur)
    assert torch.equal(accumulate.accumulate(cur, prev, None), cur)


def test_invalid_or_off_screen_motion_keeps_the_current_output() -> None:
    cur, prev = _frames()
    motion = torch.zeros(1, 2, 8, 10)
    motion[0, 0, 0, 0] = float("nan")
    motion[0, 1, 1, 1] = float("inf")
    motion[0, 0, 2, 2] = 1e6
    motion[0, 0, 3, 9] = 0.5  # off the right edge
    out = accumulate.accumulate(cur, prev, motion)
    for y, x in ((0, 0), (1, 1), (2, 2), (3, 9)):
        assert torch.equal(out[..., y, x], cur[..., y, x])
    assert not torch.equal(out[..., 4, 4], cur[..., 4, 4])


def test_history_is_clipped_to_the_neighbourhood() -> None:
    """A previous frame far brighter everywhere (a light switched off) moves the output no
    further than GAMMA deviations of the current neighbourhood: no ghost."""
    cur, _ = _frames()
    out = accumulate.accumulate(cur, cur + 1000.0, torch.zeros(1, 2, 8, 10))
    t = accumulate.tonemap(cur)
    mean, std = accumulate.neighbourhood(t)
    bound = accumulate.ALPHA * t + (1 - accumulate.ALPHA) * (mean + accumulate.GAMMA * std)
    assert torch.all(accumulate.tonemap(out) <= bound + 1e-6)
    # Nor past the neighbourhood's largest value: the output stage's bounds hold.
    assert torch.all(out <= torch.nn.functional.max_pool2d(cur, 3, 1, 1) * (1 + 1e-5))
    assert torch.any(out > cur + 1e-3)  # moved towards the history where it is allowed to


def test_a_static_sequence_converges_and_stays_finite_on_extremes() -> None:
    cur, prev = _frames()
    cur[0, :, 0, 0] = 1e8
    out = accumulate.accumulate(cur, prev, torch.zeros(1, 2, 8, 10))
    assert torch.isfinite(out).all() and out.max() <= accumulate.RADIANCE_MAX
    flat = torch.full((1, 3, 8, 10), 2.5)
    torch.testing.assert_close(accumulate.accumulate(flat, flat, torch.zeros(1, 2, 8, 10)), flat, rtol=1e-6, atol=0)


def test_the_shared_vectors_are_what_the_generator_writes() -> None:
    v, fresh = load_file(str(VECTORS)), accumulate.shared_vectors()
    assert sorted(v) == sorted(fresh)
    assert len({k.split(".")[0] for k in v}) >= 4
    for k in v:
        np.testing.assert_allclose(v[k], fresh[k], rtol=1e-6, atol=1e-6, err_msg=k)

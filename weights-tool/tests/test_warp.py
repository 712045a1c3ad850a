"""The hidden-state reprojection (rae_weights.warp), as rae-core's motion.wgsl implements it."""

import torch

from rae_weights import warp


def test_zero_motion_keeps_the_state_and_integer_motion_shifts_it() -> None:
    g = torch.Generator().manual_seed(1)
    state = torch.rand(1, 3, 6, 8, generator=g, dtype=torch.float64)
    zero = torch.zeros(1, 2, 6, 8, dtype=torch.float64)
    m, v = warp.pyramid(zero, 0)[0]
    assert torch.equal(warp.warp(state, m, v), state)
    # Motion (+2, -1): this pixel was 2 right and 1 up in the previous frame.
    shift = zero.clone()
    shift[:, 0], shift[:, 1] = 2.0, -1.0
    m, v = warp.pyramid(shift, 0)[0]
    out = warp.warp(state, m, v)
    assert torch.equal(out[:, :, 1:, :6], state[:, :, :5, 2:])
    assert torch.equal(out[:, :, 0, :], torch.zeros_like(out[:, :, 0, :])), "off the top: zero"
    assert torch.equal(out[:, :, :, 6:], torch.zeros_like(out[:, :, :, 6:])), "off the right: zero"


def test_half_pixel_motion_is_bilinear_and_bad_motion_drops_history() -> None:
    state = torch.arange(12, dtype=torch.float64).view(1, 1, 3, 4)
    m = torch.zeros(1, 2, 3, 4, dtype=torch.float64)
    m[:, 0] = 0.5
    m[0, :, 2, 1] = float("nan")
    m[0, 1, 2, 2] = 1e9
    lm, v = warp.pyramid(m, 0)[0]
    out = warp.warp(state, lm, v)
    assert out[0, 0, 0, 0] == 0.5, "halfway between 0 and 1"
    assert out[0, 0, 0, 3] == 0.5 * 3, "half of the last column, half outside"
    assert out[0, 0, 2, 1] == 0 and out[0, 0, 2, 2] == 0, "NaN and absurd motion: no history"
    assert torch.isfinite(out).all()


def test_the_pyramid_averages_blocks_in_level_pixels() -> None:
    m = torch.zeros(1, 2, 4, 4, dtype=torch.float64)
    m[:, 0] = 4.0
    m[0, 0, 0, 0] = float("inf")
    levels = warp.pyramid(m, 2)
    m1, v1 = levels[1]
    assert v1[0, 0, 0, 0] == 0.75 and m1[0, 0, 0, 0] == 0.75 * 4.0 / 2, "one of four invalid, counted as zero"
    assert v1[0, 0, 1, 1] == 1 and m1[0, 0, 1, 1] == 2.0
    m2, v2 = levels[2]
    assert m2.shape[-1] == 1 and v2[0, 0, 0, 0] == 15 / 16


def test_the_history_test_drops_what_the_previous_frame_did_not_see() -> None:
    # A background at prepared depth 1.5 with a foreground square at 1.0 that moves 2 pixels
    # right: the pixels it uncovers fetch the square from the previous frame and fail the test;
    # the square's own pixels (motion -2) and the rest of the background pass.
    def frame(left: int) -> torch.Tensor:
        x = torch.zeros(1, 4, 6, 10, dtype=torch.float64)
        x[:, 2] = 1.0  # normal (0, 0, 1)
        x[:, 3] = 1.5
        x[:, 3, 2:4, left : left + 3] = 1.0
        return x

    previous, now = warp.guide(frame(2), 0, 3), warp.guide(frame(4), 0, 3)
    motion = torch.zeros(1, 2, 6, 10, dtype=torch.float64)
    motion[:, 0, 2:4, 4:7] = -2.0
    levels = warp.pyramid(motion, 0, now, previous)
    v = levels[0][1][0, 0]
    assert (v[2:4, 2:4] == 0).all(), "uncovered background: no history"
    assert (v[2:4, 4:7] == 1).all(), "the square, followed by its motion"
    assert v[0].eq(1).all() and v[:, 8:].eq(1).all(), "still background"
    # The ramps: depth off by 1.5 tolerances keeps half the history, a normal off by 0.75 of its
    # tolerance all of it; a model without a guide keeps everything.
    off = now.clone()
    off[:, 3] += 1.5 * warp.DEPTH_TOLERANCE
    assert torch.allclose(warp.history(off, now, torch.zeros_like(motion)), torch.full_like(v, 0.5))
    tilted = now.clone()
    tilted[:, 0] += 0.75 * warp.NORMAL_TOLERANCE
    assert warp.history(tilted, now, torch.zeros_like(motion)).eq(1).all()
    assert warp.guide(frame(2), None, None) is None

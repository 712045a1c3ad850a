"""Reprojection of the hidden state with motion vectors, exactly as rae-core's
``shaders/motion.wgsl`` does it: the golden tests hold the two to each other.

Motion is rae's convention: per pixel, where its surface point was in the previous frame minus
where it is now, in pixels, x right, y down (NCHW, 2 channels). A pixel's motion is *valid* when
both components are finite and at most ``ABSURD`` times the frame's larger side; an invalid
pixel moves nothing and keeps no history.

Per level k (0 = full resolution), each pixel's motion is the mean of its 2^k x 2^k block's
(invalid ones counted as zero), in level-k pixels, and its validity the fraction of valid
pixels in the block; both are built as a pyramid of 2x2 means. The previous hidden state of the
block at level k is fetched at ``x + motion`` (pixel centres at integers), bilinear, zero outside
the level, and scaled by the validity: where nothing is valid the block starts from zero, as on
a first frame.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F

#: Motion beyond this many times the frame's larger side is treated as invalid.
ABSURD = 4.0


def sanitize_motion(motion: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """(motion with invalid pixels zeroed, validity in {0, 1}) of an N x 2 x H x W motion field."""
    h, w = motion.shape[-2:]
    limit = ABSURD * max(h, w)
    ok = (torch.isfinite(motion) & (motion.abs() <= limit)).all(dim=1, keepdim=True)
    return torch.where(ok, motion, torch.zeros_like(motion)), ok.to(motion.dtype)


def pyramid(motion: torch.Tensor, levels: int) -> list[tuple[torch.Tensor, torch.Tensor]]:
    """(motion in level-k pixels, validity) for k = 0 .. levels."""
    m, v = sanitize_motion(motion)
    out = [(m, v)]
    for _ in range(levels):
        m = F.avg_pool2d(m, 2) * 0.5
        v = F.avg_pool2d(v, 2)
        out.append((m, v))
    return out


def warp(state: torch.Tensor, motion: torch.Tensor, valid: torch.Tensor) -> torch.Tensor:
    """``state`` (N x C x H x W, the previous frame's) fetched at ``x + motion``: bilinear, zero
    outside, scaled by ``valid``. ``motion`` and ``valid`` are at the state's resolution."""
    n, c, h, w = state.shape
    ys = torch.arange(h, dtype=state.dtype, device=state.device).view(1, h, 1)
    xs = torch.arange(w, dtype=state.dtype, device=state.device).view(1, 1, w)
    sx, sy = xs + motion[:, 0], ys + motion[:, 1]
    x0, y0 = torch.floor(sx), torch.floor(sy)
    fx, fy = sx - x0, sy - y0
    flat = state.reshape(n, c, h * w)
    out = torch.zeros_like(state)
    for dy, wy in ((0, 1 - fy), (1, fy)):
        for dx, wx in ((0, 1 - fx), (1, fx)):
            xi, yi = x0 + dx, y0 + dy
            inside = (xi >= 0) & (xi < w) & (yi >= 0) & (yi < h)
            idx = (yi.clamp(0, h - 1) * w + xi.clamp(0, w - 1)).long().view(n, 1, h * w).expand(n, c, h * w)
            tap = torch.gather(flat, 2, idx).view(n, c, h, w)
            out = out + tap * (wx * wy * inside).unsqueeze(1)
    return out * valid

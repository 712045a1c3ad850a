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

A pixel's validity is also scaled by its *history test* (disocclusion): its guide (normal and
prepared depth, read from the packed input; zero for the buffers the model does not read) against
the previous frame's guide fetched at ``x + motion`` (bilinear, edge taps clamped), a linear ramp
from 1 at ``DEPTH_TOLERANCE`` to 0 at twice that on the depth difference (prepared depth is
log1p, so the difference is relative), times one from 1 at ``NORMAL_TOLERANCE`` to 0 at twice
that on the distance between the normals. A model that reads neither has no guide, and every
history passes.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F

#: Motion beyond this many times the frame's larger side is treated as invalid.
ABSURD = 4.0
#: History is kept fully up to this difference of prepared depth, dropped from twice it.
DEPTH_TOLERANCE = 0.05
#: History is kept fully up to this distance between normals, dropped from twice it.
NORMAL_TOLERANCE = 0.5


def sanitize_motion(motion: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """(motion with invalid pixels zeroed, validity in {0, 1}) of an N x 2 x H x W motion field."""
    h, w = motion.shape[-2:]
    limit = ABSURD * max(h, w)
    ok = (torch.isfinite(motion) & (motion.abs() <= limit)).all(dim=1, keepdim=True)
    return torch.where(ok, motion, torch.zeros_like(motion)), ok.to(motion.dtype)


def guide(x: torch.Tensor, normal: int | None, depth: int | None) -> torch.Tensor | None:
    """The history test's guide of packed input ``x``: N x 4 (normal, prepared depth) from the
    channels at ``normal`` and ``depth`` (zero where ``None``); ``None`` if both are."""
    if normal is None and depth is None:
        return None
    n, _, h, w = x.shape
    g = x.new_zeros(n, 4, h, w)
    if normal is not None:
        g[:, :3] = x[:, normal : normal + 3]
    if depth is not None:
        g[:, 3:] = x[:, depth : depth + 1]
    return g.detach()


def _ramp(s: torch.Tensor) -> torch.Tensor:
    return (2.0 - s).clamp(0.0, 1.0)


def history(now: torch.Tensor, previous: torch.Tensor, motion: torch.Tensor) -> torch.Tensor:
    """The history test (N x 1 in [0, 1]) of guide ``now`` against the previous frame's guide
    fetched at ``x + motion`` (motion as ``sanitize_motion`` leaves it)."""
    p = bilinear(previous, motion, zero_outside=False)
    dz = (p[:, 3:] - now[:, 3:]).abs()
    dn = torch.sqrt(((p[:, :3] - now[:, :3]) ** 2).sum(dim=1, keepdim=True))
    return _ramp(dz / DEPTH_TOLERANCE) * _ramp(dn / NORMAL_TOLERANCE)


def pyramid(
    motion: torch.Tensor, levels: int, now: torch.Tensor | None = None, previous: torch.Tensor | None = None
) -> list[tuple[torch.Tensor, torch.Tensor]]:
    """(motion in level-k pixels, validity) for k = 0 .. levels; with guides ``now`` and
    ``previous`` (``guide``) the validity includes the history test."""
    m, v = sanitize_motion(motion)
    if now is not None and previous is not None:
        v = v * history(now, previous, m)
    out = [(m, v)]
    for _ in range(levels):
        m = F.avg_pool2d(m, 2) * 0.5
        v = F.avg_pool2d(v, 2)
        out.append((m, v))
    return out


def bilinear(state: torch.Tensor, motion: torch.Tensor, zero_outside: bool) -> torch.Tensor:
    """``state`` fetched at ``x + motion``, bilinear between pixel centres; taps outside weigh
    zero (``zero_outside``) or load the nearest edge pixel."""
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
            weight = wx * wy
            if zero_outside:
                weight = weight * ((xi >= 0) & (xi < w) & (yi >= 0) & (yi < h))
            idx = (yi.clamp(0, h - 1) * w + xi.clamp(0, w - 1)).long().view(n, 1, h * w).expand(n, c, h * w)
            tap = torch.gather(flat, 2, idx).view(n, c, h, w)
            out = out + tap * weight.unsqueeze(1)
    return out


def warp(state: torch.Tensor, motion: torch.Tensor, valid: torch.Tensor) -> torch.Tensor:
    """``state`` (N x C x H x W, the previous frame's) fetched at ``x + motion``: bilinear, zero
    outside, scaled by ``valid``. ``motion`` and ``valid`` are at the state's resolution."""
    return bilinear(state, motion, zero_outside=True) * valid

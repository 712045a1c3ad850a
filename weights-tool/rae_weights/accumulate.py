"""Temporal accumulation of the denoised output, exactly as rae-core's ``shaders/accumulate.wgsl``
(and ``cpu::accumulate``) do it: the engine tests hold them to each other.

After the network, each output pixel is blended with the previous frame's *accumulated* output
fetched at ``x + motion`` (rae's convention: where the pixel's surface point was in the previous
frame minus where it is now, in pixels). Real-time denoisers (SVGF, the OptiX temporal mode)
all reuse the previous result this way: the network's residual error changes from frame to
frame, and averaging it along the motion lowers both the error and the flicker.

Per pixel, on tonemapped values ``T(x) = x / (1 + x)`` (so one bright sample cannot dominate the
statistics or the blend):

1. The history is the previous accumulated output at ``x + motion``, tonemapped, then bilinear between pixel
   centres. It is used only where the motion is valid (finite, at most ``warp.ABSURD`` times the
   frame's larger side) and the point lies inside the frame (every tap with weight inside);
   elsewhere the output is the network's.
2. The history is clipped, per channel, to ``mean +- GAMMA * std`` of ``T`` over the current
   output's 3x3 neighbourhood (the pixels inside the frame), and to that neighbourhood's
   minimum and maximum: history that disagrees with what the network sees now (a disocclusion,
   a moving shadow, a light switched on) is pulled to it, so there is no ghosting, without a
   test on depth or normals; and the output stays within its neighbourhood's range, so every
   bound of the output stage holds for it too.
3. The result is ``T^-1(ALPHA * T(current) + (1 - ALPHA) * T(history))``, at most
   ``RADIANCE_MAX``.

Images are N x 3 x H x W float32 tensors of linear radiance, motion N x 2 x H x W.
"""

from __future__ import annotations

import numpy as np
import torch
import torch.nn.functional as F

from . import warp

#: The current output's share of the blend.
ALPHA = 0.5
#: The history is clipped to the neighbourhood's mean +- GAMMA standard deviations.
GAMMA = 0.5
#: The largest radiance the output stage passes (rae-core's ``limits::RADIANCE_MAX``).
RADIANCE_MAX = 1e8


def tonemap(x: torch.Tensor) -> torch.Tensor:
    """``x / (1 + x)`` of non-negative radiance."""
    return x / (1.0 + x)


def usable(motion: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """(motion with invalid pixels zeroed, usable) per pixel: usable (N x 1 x H x W bool) where
    the motion is valid (``warp.sanitize_motion``) and ``x + motion`` lies inside the frame."""
    h, w = motion.shape[-2:]
    m, ok = warp.sanitize_motion(motion)
    ys = torch.arange(h, dtype=motion.dtype, device=motion.device).view(1, 1, h, 1)
    xs = torch.arange(w, dtype=motion.dtype, device=motion.device).view(1, 1, 1, w)
    sx, sy = xs + m[:, :1], ys + m[:, 1:]
    inside = (sx >= 0) & (sx <= w - 1) & (sy >= 0) & (sy <= h - 1)
    return m, (ok > 0) & inside


def neighbourhood(t: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """(mean, standard deviation) per channel over each pixel's 3x3 neighbourhood inside the
    frame; the deviation from the mean in a second pass (no cancellation in flat regions)."""
    n, c, h, w = t.shape
    taps = F.unfold(t, 3, padding=1).view(n, c, 9, h, w)
    inside = F.unfold(torch.ones_like(t[:, :1]), 3, padding=1).view(n, 1, 9, h, w)
    count = inside.sum(dim=2)
    mean = taps.sum(dim=2) / count
    var = (((taps - mean.unsqueeze(2)) * inside) ** 2).sum(dim=2) / count
    return mean, var.sqrt()


def history_box(t: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """(lowest, highest) tonemapped history each pixel keeps: ``mean +- GAMMA * std`` of its 3x3
    neighbourhood in ``t``, within the neighbourhood's minimum and maximum."""
    mean, std = neighbourhood(t)
    lowest = -F.max_pool2d(-t, 3, 1, 1)
    highest = F.max_pool2d(t, 3, 1, 1)
    return torch.maximum(mean - GAMMA * std, lowest), torch.minimum(mean + GAMMA * std, highest)


def accumulate(current: torch.Tensor, previous: torch.Tensor | None, motion: torch.Tensor | None) -> torch.Tensor:
    """This frame's accumulated output from the network's ``current`` output, the previous
    frame's accumulated output and this frame's motion; ``current`` itself without either."""
    if previous is None or motion is None or previous.shape != current.shape:
        return current
    m, keep = usable(motion.to(current.dtype))
    t = tonemap(current)
    lowest, highest = history_box(t)
    # Every tap with weight lies inside where the history is used: edge taps clamped as the
    # history test's fetch does.
    h = torch.minimum(torch.maximum(warp.bilinear(tonemap(previous), m, zero_outside=False), lowest), highest)
    b = ALPHA * t + (1.0 - ALPHA) * h
    out = (b / (1.0 - b).clamp_min(1e-30)).clamp(max=RADIANCE_MAX)
    return torch.where(keep, out, current)


#: Shared test vectors (tests/fixtures/accumulate_vectors.safetensors): rae-core's
#: ``accumulate.rs`` and this module are both held to them.
VECTORS_FILE = "accumulate_vectors.safetensors"


def shared_vectors(seed: int = 2026) -> dict[str, np.ndarray]:
    """Cases of (``caseK.current``, ``previous`` [H, W, 3], ``motion`` [H, W, 2], float32) and
    this module's ``expected`` output: a sub-pixel pan over a noisy HDR image, motion pointing
    off screen at the edges; an object gone from the previous frame (a disocclusion: its history
    is clipped away); NaN, infinite and absurd motion beside radiance of 0 and 1e8; a 1-pixel-high
    strip."""
    rng = np.random.default_rng(seed)
    h, w = 9, 13
    ys, xs = np.mgrid[0:h, 0:w].astype(np.float32)
    base = np.stack([xs * 0.3, ys * 0.2 + 0.1, np.full_like(xs, 1.5)], axis=-1)
    cases = []
    pan = np.broadcast_to(np.array([0.37, -0.61], np.float32), (h, w, 2)).copy()
    cases.append((base + rng.normal(0, 0.2, base.shape), base + rng.normal(0, 0.2, base.shape), pan))
    gone = base.copy()
    gone[2:5, 3:7] = 40.0
    cases.append((base + rng.normal(0, 0.05, base.shape), gone, rng.normal(0, 0.8, (h, w, 2))))
    wild = rng.uniform(0.0, 3.0, (h, w, 3))
    wild[0, 0], wild[4, 5], wild[8, 12] = 1e8, 0.0, [1e8, 0.0, 7.0]
    motion = rng.normal(0, 1.5, (h, w, 2))
    motion[1, 1], motion[2, 2], motion[3, 3], motion[5, 5] = [np.nan, 0.0], [np.inf, 1.0], [0.0, 1e6], [-0.0, -60.0]
    cases.append((wild, np.roll(wild, 1, axis=1) * 0.9, motion))
    strip = rng.uniform(0.0, 4.0, (1, 17, 3))
    cases.append((strip, strip[:, ::-1], rng.normal(0, 2.0, (1, 17, 2)) * [[1.0, 0.0]]))
    out: dict[str, np.ndarray] = {}
    for k, (cur, prev, mot) in enumerate(cases):
        cur, prev, mot = (np.ascontiguousarray(a, dtype=np.float32) for a in (cur, prev, mot))
        out[f"case{k}.current"], out[f"case{k}.previous"], out[f"case{k}.motion"] = cur, prev, mot
        chw = lambda a: torch.from_numpy(a).permute(2, 0, 1)[None]
        got = accumulate(chw(cur), chw(prev), chw(mot))
        out[f"case{k}.expected"] = np.ascontiguousarray(got[0].permute(1, 2, 0).numpy())
    return out

"""The recurrent denoising autoencoder in PyTorch, with the reference code's module names.

``RecurrentAE`` keeps each recurrent block's hidden state between calls, like the reference code;
``reset()`` zeroes it. ``prepare_input`` and ``finish_output`` are the input and output stages that
rae-core runs in ``shaders/prep.wgsl`` and ``shaders/output.wgsl``; the three together are what the
golden tests hold the wgpu runtime to.
"""

from __future__ import annotations

import torch
import torch.nn as nn
import torch.nn.functional as F

from . import transfer, warp
from .arch import INPUT_CHANNELS, Arch

#: Bounds applied to input buffers before they reach the network (see docs in rae-core `frame`).
RADIANCE_MAX = 1e8
ALBEDO_MAX = 1e3
DEPTH_MAX = 1e6
#: The network output is clamped to [0, OUT_LOG_MAX] before the inverse transfer (no overflow).
OUT_LOG_MAX = 80.0
#: Denoised demodulated radiance is at most OUT_GAIN x the frame's largest demodulated input.
OUT_GAIN = 2.0


def _conv(cin: int, cout: int) -> nn.Conv2d:
    return nn.Conv2d(cin, cout, 3, padding=1)


class EncoderBlock(nn.Module):
    """A recurrent block: ``op1 = l1(x)``, ``hidden = l2(cat(op1, hidden))``."""

    def __init__(self, cin: int, cout: int, slope: float) -> None:
        super().__init__()
        self.width = cout
        self.l1 = nn.Sequential(_conv(cin, cout), nn.LeakyReLU(slope))
        self.l2 = nn.Sequential(_conv(2 * cout, cout), nn.LeakyReLU(slope), _conv(cout, cout), nn.LeakyReLU(slope))
        self.hidden: torch.Tensor | None = None

    def forward(self, x: torch.Tensor, motion: tuple[torch.Tensor, torch.Tensor] | None = None) -> torch.Tensor:
        """One frame; ``motion`` (level motion and validity, ``warp.pyramid``) reprojects the
        hidden state first."""
        op1 = self.l1(x)
        hidden = self.hidden
        if hidden is None or hidden.shape != op1.shape:
            hidden = torch.zeros_like(op1)
        elif motion is not None:
            hidden = warp.warp(hidden, *motion)
        op2 = self.l2(torch.cat((op1, hidden), dim=1))
        self.hidden = op2
        return op2


class DecoderBlock(nn.Module):
    """``l1 = (Upsample, conv, lrelu, conv, lrelu|identity)``, as in the reference code."""

    def __init__(self, cin: int, cout: int, slope: float, last_linear: bool) -> None:
        super().__init__()
        self.l1 = nn.Sequential(
            nn.Upsample(scale_factor=2, mode="nearest"),
            _conv(cin, cout),
            nn.LeakyReLU(slope),
            _conv(cout, cout),
            nn.Identity() if last_linear else nn.LeakyReLU(slope),
        )

    def forward(self, prev: torch.Tensor, skip: torch.Tensor, prepool: bool) -> torch.Tensor:
        if prepool:
            # Paper: upsample the coarser features, then concatenate the pre-pool skip.
            return self.l1[1:](torch.cat((self.l1[0](prev), skip), dim=1))
        # Reference code: concatenate the pooled skip, then upsample both.
        return self.l1(torch.cat((prev, skip), dim=1))


class RecurrentAE(nn.Module):
    """The network of an ``Arch``; parameter names match the reference code (d1.l1.0 ... u1.l1.3)."""

    def __init__(self, arch: Arch) -> None:
        super().__init__()
        self.arch = arch
        s = arch.negative_slope
        cin = arch.in_channels
        for k, w in enumerate(arch.encoder, start=1):
            setattr(self, f"d{k}", EncoderBlock(cin, w, s))
            cin = w
        self.bottleneck = EncoderBlock(cin, arch.bottleneck, s)
        dec = arch.decoder_widths()
        prev = arch.bottleneck
        for k in range(arch.levels, 0, -1):
            last = k == 1 and arch.output_activation == "linear"
            setattr(self, f"u{k}", DecoderBlock(prev + arch.encoder[k - 1], dec[k - 1], s, last))
            prev = dec[k - 1]

        # The history test's guide (warp.guide): channels of normal and depth in the input.
        offsets, ch = {}, 0
        for name in arch.inputs:
            offsets[name] = ch
            ch += INPUT_CHANNELS[name]
        self.guide_channels = (offsets.get("normal"), offsets.get("depth"))
        self.guide: torch.Tensor | None = None

    def encoders(self) -> list[EncoderBlock]:
        return [getattr(self, f"d{k}") for k in range(1, self.arch.levels + 1)] + [self.bottleneck]

    def reset(self) -> None:
        """Zero the hidden state (first frame of a sequence, scene cut)."""
        for block in self.encoders():
            block.hidden = None
        self.guide = None

    def forward(self, x: torch.Tensor, motion: torch.Tensor | None = None) -> torch.Tensor:
        """One frame of packed input (``prepare_input``); with ``motion`` (N x 2 x H x W, rae's
        convention, at the input's size) each block's hidden state is reprojected first
        (``warp``), where the history test against the previous frame's guide passes; without
        it the state is used as it is."""
        n = self.arch.levels
        prepool = self.arch.skip == "prepool"
        now = warp.guide(x, *self.guide_channels)
        previous = self.guide if self.guide is not None and now is not None and self.guide.shape == now.shape else None
        self.guide = now
        levels = warp.pyramid(motion.to(x.dtype), n, now, previous) if motion is not None else [None] * (n + 1)
        skips: list[torch.Tensor] = []
        for k in range(1, n + 1):
            d = getattr(self, f"d{k}")(x, levels[k - 1])
            x = F.max_pool2d(d, kernel_size=2)
            skips.append(d if prepool else x)
        y = self.bottleneck(x, levels[n])
        for k in range(n, 0, -1):
            y = getattr(self, f"u{k}")(y, skips[k - 1], prepool)
        return y


def _sanitize(x: torch.Tensor, lo: float, hi: float, posinf: float) -> torch.Tensor:
    """NaN -> 0, +Inf -> posinf, -Inf -> lo, then clamp to [lo, hi]."""
    return torch.nan_to_num(x, nan=0.0, posinf=posinf, neginf=lo).clamp(lo, hi)


def sanitize_buffers(frame: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
    """The input policy: every buffer made finite and bounded (NCHW tensors)."""
    out: dict[str, torch.Tensor] = {}
    for name, t in frame.items():
        if name == "color":
            out[name] = _sanitize(t, 0.0, RADIANCE_MAX, RADIANCE_MAX)
        elif name == "albedo":
            out[name] = _sanitize(t, 0.0, ALBEDO_MAX, 0.0)
        elif name == "normal":
            out[name] = _sanitize(t, -1.0, 1.0, 0.0)
        elif name == "depth":
            # A miss is a miss whatever the renderer writes for it: +inf (rae-trace), 0
            # (Blender's Denoising Depth), NaN or a negative value all become DEPTH_MAX.
            d = _sanitize(t, 0.0, DEPTH_MAX, DEPTH_MAX)
            out[name] = torch.where(d > 0.0, d, torch.full_like(d, DEPTH_MAX))
        elif name == "roughness":
            out[name] = _sanitize(t, 0.0, 1.0, 0.0)
    return out


def prepare_input(arch: Arch, frame: dict[str, torch.Tensor]) -> torch.Tensor:
    """Buffers (NCHW, raw renderer output) -> packed network input, as ``prep.wgsl`` does."""
    b = sanitize_buffers(frame)
    parts = []
    for name in arch.inputs:
        t = b[name]
        if name == "color":
            if arch.demodulate:
                t = t / (b["albedo"] + arch.albedo_eps)
            t = transfer.encode(arch.transfer, t)
        elif name == "depth":
            t = torch.log1p(t)
        assert t.shape[1] == INPUT_CHANNELS[name]
        parts.append(t)
    return torch.cat(parts, dim=1)


def prepared_color(arch: Arch, frame: dict[str, torch.Tensor]) -> torch.Tensor:
    """Color as the network sees it (sanitised, demodulated, transfer applied), NCHW."""
    b = sanitize_buffers({k: v for k, v in frame.items() if k in ("color", "albedo")})
    t = b["color"]
    if arch.demodulate:
        t = t / (b["albedo"] + arch.albedo_eps)
    return transfer.encode(arch.transfer, t)


def output_limit(arch: Arch, in_max: torch.Tensor) -> torch.Tensor:
    """Upper clamp of the network output given each frame's largest prepared color (rae-core
    ``cpu::output_limit``): output radiance <= OUT_GAIN x the brightest input, and finite."""
    return transfer.limit(arch.transfer, in_max, OUT_GAIN, RADIANCE_MAX, OUT_LOG_MAX)


def finish_output(arch: Arch, y: torch.Tensor, frame: dict[str, torch.Tensor]) -> torch.Tensor:
    """Network output -> radiance, as ``output.wgsl`` does: clamp to [0, output_limit], inverse
    transfer, remodulation."""
    in_max = prepared_color(arch, frame).to(y.dtype).amax(dim=(1, 2, 3), keepdim=True)
    y = torch.minimum(y.clamp(min=0.0), output_limit(arch, in_max))
    r = transfer.decode(arch.transfer, y)
    if arch.demodulate:
        albedo = sanitize_buffers({"albedo": frame["albedo"]})["albedo"]
        r = r * (albedo + arch.albedo_eps)
    return r

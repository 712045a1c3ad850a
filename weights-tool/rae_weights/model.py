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


def is_miss(arch: Arch, b: dict[str, torch.Tensor]) -> torch.Tensor | None:
    """N1HW bool: pixels whose camera ray hit nothing, told from the sanitised buffers the model
    reads: depth a miss (``DEPTH_MAX`` once sanitised, whatever the renderer wrote) or a normal of
    zero (rae-trace and Cycles write 0 where the ray misses). None when the model reads neither."""
    miss = None
    if "depth" in arch.inputs and "depth" in b:
        miss = b["depth"] >= DEPTH_MAX
    if "normal" in arch.inputs and "normal" in b:
        zero = (b["normal"] == 0.0).all(dim=1, keepdim=True)
        miss = zero if miss is None else miss | zero
    return miss


def canonical_buffers(arch: Arch, frame: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
    """The input policy (``sanitize_buffers``) plus one convention for misses: albedo is 1 where
    the ray hit nothing. Renderers write 0 there (rae-trace), the sky's colour (Cycles) or
    anything else; demodulating by 0 + eps turns the background into 1000x its radiance, which
    the network spreads into the geometry beside it. With albedo 1 the network sees the
    background's own radiance whatever the renderer wrote."""
    b = sanitize_buffers(frame)
    if "albedo" in b:
        miss = is_miss(arch, b)
        if miss is not None:
            b["albedo"] = torch.where(miss, torch.ones_like(b["albedo"]), b["albedo"])
    return b


def _prepared_color(arch: Arch, b: dict[str, torch.Tensor]) -> torch.Tensor:
    """Color of canonical buffers ``b`` as the network sees it: demodulated, transfer applied."""
    t = b["color"]
    if arch.demodulate:
        t = t / (b["albedo"] + arch.albedo_eps)
    return transfer.encode(arch.transfer, t)


def prepare_input(arch: Arch, frame: dict[str, torch.Tensor]) -> torch.Tensor:
    """Buffers (NCHW, raw renderer output) -> packed network input, as ``prep.wgsl`` does."""
    b = canonical_buffers(arch, frame)
    parts = []
    for name in arch.inputs:
        t = b[name]
        if name == "color":
            t = _prepared_color(arch, b)
        elif name == "depth":
            t = torch.log1p(t)
        assert t.shape[1] == INPUT_CHANNELS[name]
        parts.append(t)
    return torch.cat(parts, dim=1)


def demodulation_albedo(arch: Arch, frame: dict[str, torch.Tensor]) -> torch.Tensor:
    """What color is divided by before the network and multiplied by after: the canonical
    albedo (``canonical_buffers``) + eps."""
    keep = ("albedo", "normal", "depth")
    return canonical_buffers(arch, {k: v for k, v in frame.items() if k in keep})["albedo"] + arch.albedo_eps


def prepared_color(arch: Arch, frame: dict[str, torch.Tensor]) -> torch.Tensor:
    """Color as the network sees it (sanitised, demodulated, transfer applied), NCHW."""
    return _prepared_color(arch, canonical_buffers(arch, frame))


def output_limit(arch: Arch, in_max: torch.Tensor) -> torch.Tensor:
    """Upper clamp of the network output given each frame's largest prepared color (rae-core
    ``cpu::output_limit``): output radiance <= OUT_GAIN x the brightest input, and finite."""
    return transfer.limit(arch.transfer, in_max, OUT_GAIN, RADIANCE_MAX, OUT_LOG_MAX)


def pass_misses(arch: Arch, y: torch.Tensor, frame: dict[str, torch.Tensor]) -> torch.Tensor:
    """The network output (its own space) with the prepared input color at misses: where the ray
    hits nothing the renderer's color is the background's radiance, looked up, not estimated, so
    the output keeps it. Training composes its outputs so before the loss; ``finish_output``
    does the same in radiance."""
    b = canonical_buffers(arch, frame)
    miss = is_miss(arch, b)
    if miss is None:
        return y
    return torch.where(miss, _prepared_color(arch, b).to(y.dtype), y)


def finish_output(arch: Arch, y: torch.Tensor, frame: dict[str, torch.Tensor]) -> torch.Tensor:
    """Network output -> radiance, as ``output.wgsl`` does: clamp to [0, output_limit], inverse
    transfer, remodulation; at misses (``is_miss``) the sanitised input color itself."""
    b = canonical_buffers(arch, frame)
    in_max = _prepared_color(arch, b).to(y.dtype).amax(dim=(1, 2, 3), keepdim=True)
    y = torch.minimum(y.clamp(min=0.0), output_limit(arch, in_max))
    r = transfer.decode(arch.transfer, y)
    if arch.demodulate:
        r = r * (b["albedo"] + arch.albedo_eps).to(r.dtype)
    miss = is_miss(arch, b)
    if miss is not None:
        r = torch.where(miss, b["color"].to(r.dtype), r)
    return r

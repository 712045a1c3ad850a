"""Sequences rendered by rae-trace (per-buffer EXR: color_0000.exr, reference_0000.exr, ...),
loaded into memory as NCHW float32 tensors, and random training samples drawn from them."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

BUFFERS = ("color", "albedo", "normal", "depth", "roughness", "reference")
#: Buffers a sequence may have: motion (rae's convention, rae-trace's motion_NNNN.exr), which
#: reprojects the hidden state in training as rae-core does at run time.
OPTIONAL = ("motion",)


def read_exr(path: Path) -> np.ndarray:
    """HWC float32 (C = 3 for RGB files, 1 for single-channel ones)."""
    import OpenEXR  # imported here: only training needs it

    with OpenEXR.File(str(path)) as f:
        ch = f.channels()
        if "RGB" in ch:
            a = ch["RGB"].pixels
        elif "RGBA" in ch:
            a = ch["RGBA"].pixels[..., :3]
        else:
            a = next(iter(ch.values())).pixels
    a = np.asarray(a, dtype=np.float32)
    return a if a.ndim == 3 else a[..., None]


def read_motion(path: Path) -> np.ndarray:
    """HW x 2 float32: the R, G channels of a motion file."""
    import OpenEXR

    with OpenEXR.File(str(path)) as f:
        ch = f.channels()
        if "RG" in ch:
            return np.asarray(ch["RG"].pixels, dtype=np.float32)
        return np.stack([np.asarray(ch[c].pixels, dtype=np.float32) for c in ("R", "G")], -1)


@dataclass
class Sequence:
    """One sequence: buffer name -> [frames, C, H, W] float32."""

    name: str
    buffers: dict[str, torch.Tensor]

    @property
    def frames(self) -> int:
        return self.buffers["color"].shape[0]


def load_sequence(folder: Path) -> Sequence:
    frames = sorted(folder.glob("color_*.exr"))
    if not frames:
        raise ValueError(f"{folder}: no color_NNNN.exr frames")
    buffers: dict[str, torch.Tensor] = {}
    for name in BUFFERS:
        stack = []
        for c in frames:
            p = c.with_name(c.name.replace("color_", f"{name}_"))
            if not p.exists():
                raise ValueError(f"{p}: missing (training needs every buffer and the reference)")
            stack.append(torch.from_numpy(read_exr(p)).permute(2, 0, 1))
        buffers[name] = torch.stack(stack)
    motion = [c.with_name(c.name.replace("color_", "motion_")) for c in frames]
    if all(p.exists() for p in motion):
        buffers["motion"] = torch.stack([torch.from_numpy(read_motion(p)).permute(2, 0, 1) for p in motion])
    return Sequence(folder.name, buffers)


def load_sequences(root: Path) -> list[Sequence]:
    """Every sequence folder under root (folders holding color_NNNN.exr)."""
    folders = sorted({p.parent for p in root.rglob("color_0000.exr")})
    if not folders:
        raise ValueError(f"{root}: no sequences (folders with color_0000.exr); render some with rae-trace")
    return [load_sequence(f) for f in folders]


def transform(name: str, v: torch.Tensor, k: int, flip: bool) -> torch.Tensor:
    """Buffer `name` ([T, C, H, W]) flipped left-right (if `flip`), then turned by k quarter
    turns as ``torch.rot90(dims=(-2, -1))`` turns it. Motion is a vector field: its components
    turn with it (a flip negates x, each quarter turn maps (x, y) to (y, -x)), so that warping
    the turned previous frame with the turned motion turns the warp."""
    if flip:
        v = v.flip(-1)
    if name == "motion":
        mx, my = v[:, 0:1], v[:, 1:2]
        if flip:
            mx = -mx
        for _ in range(k % 4):
            mx, my = my, -mx
        v = torch.cat([mx, my], 1)
    return torch.rot90(v, k, dims=(-2, -1)).contiguous()


def sample(seqs: list[Sequence], frames: int, crop: int, rng: np.random.Generator) -> dict[str, torch.Tensor]:
    """A random clip: `frames` consecutive frames, a random crop, flip and 90-degree rotation
    (motion turned with it, ``transform``). Returns buffer -> [T, C, crop, crop]."""
    s = seqs[rng.integers(len(seqs))]
    t0 = rng.integers(s.frames - frames + 1)
    _, _, h, w = s.buffers["color"].shape
    c = min(crop, h, w)
    y, x = rng.integers(h - c + 1), rng.integers(w - c + 1)
    k, flip = int(rng.integers(4)), bool(rng.integers(2))
    out = {}
    for name, t in s.buffers.items():
        out[name] = transform(name, t[t0 : t0 + frames, :, y : y + c, x : x + c], k, flip)
    return out

"""Sequences rendered by rae-trace (per-buffer EXR: color_0000.exr, reference_0000.exr, ...) or
Blender (one multi-layer EXR per frame, ``scripts/render-blender.py``), loaded into memory as
NCHW float32 tensors, and random training samples drawn from them."""

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


#: Layer names of multi-layer EXRs (rae's and Blender Cycles'), as rae-core's ``io`` reads them.
LAYERS = {
    "color": "color", "combined": "color", "image": "color", "noisy image": "color", "noisy": "color",
    "albedo": "albedo", "denoising albedo": "albedo",
    "normal": "normal", "denoising normal": "normal",
    "depth": "depth", "denoising depth": "depth",
    "roughness": "roughness",
    "reference": "reference", "clean": "reference",
    "motion": "motion", "vector": "motion",
}  # fmt: skip


def _layer(group: str) -> str | None:
    """The buffer a layer (group) name stands for: the name or its last dotted part
    ("ViewLayer.Denoising Albedo" -> albedo), as rae-core's ``slot_of_group``."""
    return LAYERS.get(group.lower()) or LAYERS.get(group.rsplit(".", 1)[-1].lower())


def read_multilayer(path: Path) -> dict[str, np.ndarray]:
    """Buffer name -> HWC float32 of one multi-layer EXR frame, as rae-core reads it: RGB (or
    XYZ) for three-channel buffers, R, G (or X, Y) for motion (Blender's Vector pass converted to
    rae's convention, (X, -Y)), one channel (Y, Z, R, V or the first) for depth and roughness.
    Layers of other names are left out."""
    import OpenEXR

    groups: dict[str, dict[str, np.ndarray]] = {}
    with OpenEXR.File(str(path)) as f:
        for key, ch in f.channels().items():
            a = np.asarray(ch.pixels, dtype=np.float32)
            if a.ndim == 3:  # channels grouped by the library: RGB or RGBA
                groups.setdefault(key, {}).update({c: a[..., i] for i, c in enumerate("RGBA"[: a.shape[-1]])})
            else:
                group, _, name = key.rpartition(".")
                groups.setdefault(group, {})[name.upper()] = a
    out: dict[str, np.ndarray] = {}
    for group, chans in groups.items():
        buf = _layer(group) if group else "color"
        if buf is None:
            continue
        if buf == "motion":
            xy = [chans.get("R", chans.get("X")), chans.get("G", chans.get("Y"))]
            if any(c is None for c in xy):
                raise ValueError(f"{path}: `{group}` needs R, G (or X, Y) channels")
            m = np.stack(xy, -1)  # type: ignore[arg-type]
            if group.rsplit(".", 1)[-1].lower() == "vector":
                m[..., 1] = -m[..., 1]
            out[buf] = m
        elif buf in ("color", "albedo", "normal", "reference"):
            for names in ("RGB", "XYZ"):
                if all(c in chans for c in names):
                    out[buf] = np.stack([chans[c] for c in names], -1)
                    break
            else:
                raise ValueError(f"{path}: `{group}` needs R, G, B (or X, Y, Z) channels")
        else:
            c = next((chans[n] for n in ("Y", "Z", "R", "V") if n in chans), next(iter(chans.values())))
            out[buf] = c[..., None]
    return out


@dataclass
class Sequence:
    """One sequence: buffer name -> [frames, C, H, W] float32."""

    name: str
    buffers: dict[str, torch.Tensor]
    #: Where it was read from.
    folder: Path = Path()

    @property
    def frames(self) -> int:
        return self.buffers["color"].shape[0]


def load_multilayer_sequence(folder: Path, files: list[Path]) -> Sequence:
    """A sequence of one multi-layer EXR per frame (Blender's layout, ``read_multilayer``);
    every frame must hold every buffer and the reference."""
    frames = [read_multilayer(p) for p in files]
    buffers: dict[str, torch.Tensor] = {}
    for name in BUFFERS + OPTIONAL:
        if name in OPTIONAL and not all(name in f for f in frames):
            continue
        for p, f in zip(files, frames):
            if name not in f:
                raise ValueError(f"{p}: no `{name}` layer (training needs every buffer and the reference)")
        buffers[name] = torch.stack([torch.from_numpy(f[name]).permute(2, 0, 1) for f in frames])
    return Sequence(folder.name, buffers, folder)


def load_sequence(folder: Path) -> Sequence:
    """The sequence in `folder`: per-buffer files (color_NNNN.exr, albedo_NNNN.exr, ...) or one
    multi-layer EXR per frame."""
    frames = sorted(folder.glob("color_*.exr"))
    if not frames:
        layered = sorted(p for p in folder.glob("*.exr") if not p.name.startswith("."))
        if layered:
            return load_multilayer_sequence(folder, layered)
        raise ValueError(f"{folder}: no color_NNNN.exr frames and no multi-layer EXRs")
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
    return Sequence(folder.name, buffers, folder)


def load_sequences(root: Path, skip: set[Path] | frozenset[Path] = frozenset(), empty_ok: bool = False) -> list[Sequence]:
    """Every sequence folder under root: folders holding color_NNNN.exr, or multi-layer EXRs
    (and no sequence folder of their own); hidden ones (a renderer's ``.NAME.partial``) and those
    in ``skip`` are left out. A root with none (missing, or a renderer's not written to yet) is an
    error unless ``empty_ok``."""
    folders = sorted({p.parent for p in root.rglob("*.exr") if not p.name.startswith(".") and not any(q.name.startswith(".") for q in p.relative_to(root).parents if q.name)})
    if not folders and not empty_ok:
        raise ValueError(f"{root}: no sequences (folders with color_0000.exr or multi-layer EXRs); render some with rae-trace")
    return [load_sequence(f) for f in folders if f not in skip]


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


def random_orthogonal(rng: np.random.Generator) -> torch.Tensor:
    """A uniformly random 3x3 orthogonal matrix (a rotation, or a rotation and a mirror)."""
    q, r = np.linalg.qr(rng.standard_normal((3, 3)))
    return torch.from_numpy(q * np.sign(np.diag(r))).float()


def vary_conventions(clip: dict[str, torch.Tensor], rng: np.random.Generator) -> dict[str, torch.Tensor]:
    """The clip as another renderer might have written it, so that a model trained on it does
    not rely on one renderer's conventions: half the time its normals are turned (and perhaps
    mirrored) by one random orthogonal matrix, as world-space normals differ from camera-space
    ones and renderers differ in handedness and sign; half the time its depth is in other units
    (scaled by 10^U(-1, 1)). Misses stay misses (+inf scaled is +inf, 0 stays 0; prep maps
    both to the same value). The same change holds for every frame of the clip."""
    out = dict(clip)
    if "normal" in out and rng.random() < 0.5:
        m = random_orthogonal(rng).to(out["normal"].device)
        out["normal"] = torch.einsum("ij,tjhw->tihw", m, out["normal"])
    if "depth" in out and rng.random() < 0.5:
        out["depth"] = out["depth"] * float(10.0 ** rng.uniform(-1.0, 1.0))
    return out


def sample(seqs: list[Sequence], frames: int, crop: int, rng: np.random.Generator, vary: bool = False) -> dict[str, torch.Tensor]:
    """A random clip: `frames` consecutive frames, a random crop, flip and 90-degree rotation
    (motion turned with it, ``transform``), and with `vary` the conventions of another
    renderer (``vary_conventions``). Returns buffer -> [T, C, crop, crop]."""
    s = seqs[rng.integers(len(seqs))]
    t0 = rng.integers(s.frames - frames + 1)
    _, _, h, w = s.buffers["color"].shape
    c = min(crop, h, w)
    y, x = rng.integers(h - c + 1), rng.integers(w - c + 1)
    k, flip = int(rng.integers(4)), bool(rng.integers(2))
    out = {}
    for name, t in s.buffers.items():
        out[name] = transform(name, t[t0 : t0 + frames, :, y : y + c, x : x + c], k, flip)
    return vary_conventions(out, rng) if vary else out

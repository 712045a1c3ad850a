"""Golden fixtures: seeded weights, input frames, and PyTorch's output for each frame.

The Rust tests (tests/golden.rs) run the same frames through wgpu and hold every value to
``|wgpu - torch| <= 1e-4 * max(1, |torch|)``. Everything random comes from numpy's PCG64 with a
fixed seed, and PyTorch computes in float64, so the expected values are the network's exact
answer rounded once to f32, and regenerating reproduces them on any machine.

Regenerate with:  python -m rae_weights golden --out tests/fixtures
Check with:       python -m rae_weights golden --check tests/fixtures
"""

from __future__ import annotations

import json
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch
from safetensors.numpy import load_file, save_file

from . import accumulate, metrics
from .arch import INPUT_CHANNELS, Arch
from .export import _publish, read_weights, write_weights
from .model import RecurrentAE, finish_output, prepare_input

#: Bump when the generator changes what it writes; stored in every golden file.
GENERATOR_VERSION = 3
COMMAND = "python -m rae_weights golden --out tests/fixtures"
GOLDEN_KEY = "rae.golden"


@dataclass(frozen=True)
class WeightsSpec:
    """A seeded random network."""

    file: str
    arch: Arch
    seed: int


@dataclass(frozen=True)
class Case:
    """A golden sequence: a network, a size, a number of frames."""

    name: str
    weights: str
    width: int
    height: int
    frames: int
    seed: int
    #: Frames carry motion (``motion_field``), which reprojects the hidden state.
    motion: bool = False


WEIGHTS: list[WeightsSpec] = [
    WeightsSpec("weights_full.safetensors", Arch(), 1),
    WeightsSpec(
        "weights_paper_tiny.safetensors",
        Arch(inputs=["color", "albedo", "normal"], encoder=[8, 12, 16], bottleneck=20,
             skip="prepool", output_activation="linear"),
        2,
    ),
    WeightsSpec(
        "weights_color_tiny.safetensors",
        Arch(inputs=["color"], demodulate=False, encoder=[4, 6, 8, 10, 12], bottleneck=12),
        3,
    ),
]

CASES: list[Case] = [
    Case("golden_full_64x64.safetensors", "weights_full.safetensors", 64, 64, 4, 11),
    Case("golden_full_96x64.safetensors", "weights_full.safetensors", 96, 64, 4, 12),
    Case("golden_paper_tiny_40x24.safetensors", "weights_paper_tiny.safetensors", 40, 24, 4, 13),
    Case("golden_color_tiny_64x32.safetensors", "weights_color_tiny.safetensors", 64, 32, 4, 14),
    Case("golden_full_motion_64x64.safetensors", "weights_full.safetensors", 64, 64, 4, 15, motion=True),
    Case("golden_color_tiny_motion_96x32.safetensors", "weights_color_tiny.safetensors", 96, 32, 4, 16, motion=True),
]


def motion_field(width: int, height: int, t: int) -> np.ndarray:
    """HW x 2 float32 motion of frame t in rae's convention (previous minus current position, in
    pixels): a pan and a zoom about the centre; a disk that moves on its own (the background it
    leaves is uncovered, ``scene_depth``); a band at the left edge pointing off screen; and one NaN, one infinite
    and one absurd pixel, whose history is dropped."""
    yy, xx = np.meshgrid(np.arange(height, dtype=np.float64), np.arange(width, dtype=np.float64), indexing="ij")
    cx, cy = width / 2, height / 2
    zoom = 1.0 + 0.02 * (t + 1)
    pan = (1.25 + 0.5 * t, -0.75)
    px = cx + (xx - cx) / zoom + pan[0]
    py = cy + (yy - cy) / zoom + pan[1]
    m = np.stack([px - xx, py - yy], -1)
    disk = (xx - (cx + 3 * t)) ** 2 + (yy - cy) ** 2 < (height / 4) ** 2
    m[disk] = (-3.0, 0.4 * t)
    m[:, :3, 0] = -(3.0 + xx[:, :3]) - 5.5
    m[:, :3, 1] = 0.0
    m[2, 5] = (np.nan, 0.0)
    m[3, 7] = (0.0, np.inf)
    m[4, 9] = (1e6, 0.0)
    return m.astype(np.float32)


def scene_depth(width: int, height: int, t: int) -> np.ndarray:
    """HW float32 depth of frame t of a motion case: a slanted background at depth 4 and up, and
    ``motion_field``'s disk in front of it at depth 2, so the history test drops the background
    the disk uncovers."""
    yy, xx = np.meshgrid(np.arange(height, dtype=np.float64), np.arange(width, dtype=np.float64), indexing="ij")
    depth = 4.0 + 0.02 * xx + 0.01 * yy
    depth[(xx - (width / 2 + 3 * t)) ** 2 + (yy - height / 2) ** 2 < (height / 4) ** 2] = 2.0
    return depth.astype(np.float32)


def add_misses(frame: dict[str, np.ndarray], width: int, height: int, t: int) -> None:
    """Puts a background into a frame where the camera ray hits nothing (a miss, model.is_miss):
    a disk at the top right, moving left, written in several renderers' conventions at once:
    depth +inf (rae-trace) on even rows and 0 (Cycles' Denoising Depth) on odd ones; normal 0
    except on every fourth column, where only depth tells the miss; albedo 0 (rae-trace) on the
    left half and the sky's colour (Cycles) on the right; color a smooth sky."""
    yy, xx = np.meshgrid(np.arange(height), np.arange(width), indexing="ij")
    disk = (xx - (0.8 * width - 2 * t)) ** 2 + yy**2 < (0.45 * height) ** 2
    sky = np.stack([0.6 + 0.3 * np.sin(0.2 * xx), 0.8 + 0.1 * np.cos(0.3 * yy), 1.5 + 0.0 * xx], -1)
    frame["color"] = np.where(disk[..., None], sky, frame["color"]).astype(np.float32)
    if "albedo" in frame:
        a = np.where((xx < 0.8 * width)[..., None], 0.0, sky)
        frame["albedo"] = np.where(disk[..., None], a, frame["albedo"]).astype(np.float32)
    if "normal" in frame:
        zero = disk & (xx % 4 != 0)
        frame["normal"] = np.where(zero[..., None], 0.0, frame["normal"]).astype(np.float32)
    if "depth" in frame:
        d = np.where(yy % 2 == 0, np.inf, 0.0)
        frame["depth"] = np.where(disk, d, frame["depth"]).astype(np.float32)


def random_state(arch: Arch, seed: int) -> dict[str, torch.Tensor]:
    """He-style init for LeakyReLU(0.1) so activations stay O(1) through every layer; the last
    convolution gets a positive bias so the output is not clamped to zero everywhere."""
    rng = np.random.default_rng(seed)
    gain = float(np.sqrt(2.0 / (1.0 + arch.negative_slope**2)))
    state: dict[str, torch.Tensor] = {}
    for name, shape in arch.tensor_shapes().items():
        if name.endswith(".weight"):
            fan_in = shape[1] * 9
            a = rng.normal(0.0, gain / np.sqrt(fan_in), size=shape)
            if name == "u1.l1.3.weight":
                a *= 0.3
        else:
            a = rng.normal(0.0, 0.05, size=shape)
            if name == "u1.l1.3.bias":
                a += 1.0
        state[name] = torch.from_numpy(a.astype(np.float32))
    return state


def random_frames(arch: Arch, width: int, height: int, frames: int, seed: int) -> list[dict[str, np.ndarray]]:
    """A moving, noisy, HDR sequence with fireflies; buffers HWC float32 (depth, roughness HW)."""
    rng = np.random.default_rng(seed)
    yy, xx = np.meshgrid(np.arange(height), np.arange(width), indexing="ij")
    out = []
    for t in range(frames):
        s = 0.5 + 0.5 * np.sin(0.21 * xx + 0.4 * t) * np.cos(0.17 * yy - 0.3 * t)
        albedo = np.stack([0.1 + 0.8 * s, 0.3 + 0.4 * ((xx // 8 + yy // 8 + t) % 2), 0.5 + 0.3 * np.cos(0.1 * xx)], -1)
        light = s[..., None] * rng.exponential(1.0, size=(height, width, 3))
        firefly = rng.random((height, width, 1)) < 0.01
        color = albedo * light * np.where(firefly, 200.0, 2.0)
        n = np.stack([np.sin(0.05 * xx + 0.1 * t), np.cos(0.07 * yy), 0.5 + s], -1)
        normal = n / np.linalg.norm(n, axis=-1, keepdims=True)
        depth = 1.0 + 10.0 * s + 0.01 * xx
        rough = np.clip(0.5 + 0.5 * np.sin(0.13 * yy + 0.2 * t) + 0.05 * rng.standard_normal((height, width)), 0, 1)
        frame = {"color": color, "albedo": albedo, "normal": normal, "depth": depth, "roughness": rough}
        need = set(arch.required_buffers)
        out.append({k: v.astype(np.float32) for k, v in frame.items() if k in need})
    return out


def to_nchw(a: np.ndarray) -> torch.Tensor:
    t = torch.from_numpy(a).to(torch.float64)
    return (t.unsqueeze(-1) if t.dim() == 2 else t).permute(2, 0, 1).unsqueeze(0)


def run_sequence(arch: Arch, state: dict[str, torch.Tensor], frames: list[dict[str, np.ndarray]]) -> list[np.ndarray]:
    """PyTorch's output (HWC float32) for each frame, hidden state carried (reprojected with a
    frame's ``motion``, where it has one), computed in float64."""
    model = RecurrentAE(arch).double().eval()
    model.load_state_dict({k: v.double() for k, v in state.items()})
    outs = []
    with torch.no_grad():
        for frame in frames:
            buffers = {k: to_nchw(v) for k, v in frame.items() if k != "motion"}
            motion = to_nchw(frame["motion"]) if "motion" in frame else None
            y = model(prepare_input(arch, buffers), motion)
            r = finish_output(arch, y, buffers)
            outs.append(r[0].permute(1, 2, 0).numpy().astype(np.float32))
    return outs


def _atomic_save(tensors: dict[str, np.ndarray], path: Path, metadata: dict[str, str]) -> None:
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        save_file(tensors, tmp, metadata=metadata)
        _publish(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def generate(out_dir: Path) -> list[Path]:
    """Write every weights file and golden sequence into out_dir; returns the paths written."""
    out_dir.mkdir(parents=True, exist_ok=True)
    written = []
    specs = {w.file: w for w in WEIGHTS}
    for w in WEIGHTS:
        write_weights(out_dir / w.file, w.arch, random_state(w.arch, w.seed))
        written.append(out_dir / w.file)
    for case in CASES:
        spec = specs[case.weights]
        arch, state = read_weights(out_dir / case.weights)
        frames = random_frames(arch, case.width, case.height, case.frames, case.seed)
        if case.motion:
            for t, frame in enumerate(frames):
                frame["motion"] = motion_field(case.width, case.height, t)
                if "depth" in frame:
                    frame["depth"] = scene_depth(case.width, case.height, t)
        for t, frame in enumerate(frames):
            add_misses(frame, case.width, case.height, t)
        outs = run_sequence(arch, state, frames)
        tensors: dict[str, np.ndarray] = {}
        for i, (frame, out) in enumerate(zip(frames, outs)):
            for k, v in frame.items():
                tensors[f"frame{i}.{k}"] = np.ascontiguousarray(v)
            tensors[f"frame{i}.output"] = np.ascontiguousarray(out)
        meta = {
            "version": GENERATOR_VERSION, "weights": case.weights, "weights_seed": spec.seed,
            "width": case.width, "height": case.height, "frames": case.frames, "seed": case.seed,
            "buffers": arch.required_buffers + (["motion"] if case.motion else []), "torch": torch.__version__,
            "command": COMMAND,
        }
        _atomic_save(tensors, out_dir / case.name, {GOLDEN_KEY: json.dumps(meta, sort_keys=True)})
        written.append(out_dir / case.name)
    _atomic_save(metrics.shared_vectors(), out_dir / metrics.VECTORS_FILE, {"command": COMMAND})
    written.append(out_dir / metrics.VECTORS_FILE)
    _atomic_save(accumulate.shared_vectors(), out_dir / accumulate.VECTORS_FILE, {"command": COMMAND})
    written.append(out_dir / accumulate.VECTORS_FILE)
    return written


def compare(committed: Path, regenerated: Path, rtol: float = 1e-5) -> list[str]:
    """Differences between two fixture folders beyond |a-b| <= rtol * max(1, |a|); [] if none."""
    problems = []
    for name in [w.file for w in WEIGHTS] + [c.name for c in CASES] + [metrics.VECTORS_FILE, accumulate.VECTORS_FILE]:
        a_path, b_path = committed / name, regenerated / name
        if not a_path.exists():
            problems.append(f"{a_path}: missing (run `{COMMAND}`)")
            continue
        a, b = load_file(str(a_path)), load_file(str(b_path))
        if set(a) != set(b):
            problems.append(f"{name}: tensor names differ: {sorted(set(a) ^ set(b))[:5]}")
            continue
        for k in sorted(a):
            if a[k].shape != b[k].shape:
                problems.append(f"{name}:{k}: shape {a[k].shape} != {b[k].shape}")
                continue
            x, y = a[k].astype(np.float64), b[k].astype(np.float64)
            if not np.array_equal(np.isnan(x), np.isnan(y)):
                problems.append(f"{name}:{k}: NaNs differ")
                continue
            with np.errstate(invalid="ignore"):
                err = np.where(np.isnan(x) | (x == y), 0.0, np.abs(x - y) / np.maximum(1.0, np.abs(x)))
            if err.size and err.max() > rtol:
                problems.append(f"{name}:{k}: max relative difference {err.max():.3g} > {rtol}")
    return problems

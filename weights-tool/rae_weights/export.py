"""PyTorch checkpoint -> rae's flat weights file (safetensors with the architecture in metadata).

Why safetensors: a fixed, documented layout (8-byte length, JSON header, then raw little-endian
tensors, header padded to 8 bytes so every f32 tensor sits at an aligned offset), a string map for
metadata, and well-kept readers in Rust and Python, so neither side hand-writes a parser.
"""

from __future__ import annotations

import dataclasses
import os
import tempfile
from pathlib import Path
from typing import Any

import torch
from safetensors import safe_open
from safetensors.torch import save_file

from .arch import INPUT_CHANNELS, Arch

METADATA_KEY = "rae.arch"

#: Network inputs guessed from the first convolution's input channels (reference-code checkpoints
#: carry no architecture); anything else needs an explicit ``--inputs``.
INPUTS_BY_CHANNELS: dict[int, list[str]] = {
    8: ["color", "normal", "depth", "roughness"],
    3: ["color"],
    6: ["color", "normal"],
    9: ["color", "albedo", "normal"],
    11: ["color", "albedo", "normal", "depth", "roughness"],
}


def load_checkpoint(path: str | Path) -> tuple[dict[str, torch.Tensor], Arch | None]:
    """Read a checkpoint: rae's own {'arch', 'state_dict'}, the reference train.py's
    {'epoch', 'state_dict', 'optimizer'}, a bare state dict, or a rae weights file
    (``.safetensors``, ``read_weights``: a shipped model). Strips a DataParallel 'module.'."""
    if Path(path).suffix == ".safetensors":
        arch, state = read_weights(path)
        return state, arch
    ckpt: Any = torch.load(path, map_location="cpu", weights_only=True)
    arch = None
    if isinstance(ckpt, dict) and "state_dict" in ckpt:
        if isinstance(ckpt.get("arch"), str):
            arch = Arch.from_json(ckpt["arch"])
        state = ckpt["state_dict"]
    elif isinstance(ckpt, dict):
        state = ckpt
    else:
        raise ValueError(f"{path}: not a checkpoint dictionary (found {type(ckpt).__name__})")
    state = {k.removeprefix("module."): v for k, v in state.items() if isinstance(v, torch.Tensor)}
    return state, arch


def infer_arch(state: dict[str, torch.Tensor], **overrides: Any) -> Arch:
    """Architecture from tensor shapes, for checkpoints that do not declare one."""
    levels = 0
    while f"d{levels + 1}.l1.0.weight" in state:
        levels += 1
    if levels == 0 or "bottleneck.l1.0.weight" not in state or "u1.l1.3.weight" not in state:
        raise ValueError("state dict lacks d1.l1.0 / bottleneck.l1.0 / u1.l1.3: not a recurrent AE")
    encoder = [int(state[f"d{k}.l1.0.weight"].shape[0]) for k in range(1, levels + 1)]
    cin = int(state["d1.l1.0.weight"].shape[1])
    fields: dict[str, Any] = {
        "encoder": encoder,
        "bottleneck": int(state["bottleneck.l1.0.weight"].shape[0]),
        "out_channels": int(state["u1.l1.3.weight"].shape[0]),
    }
    if "inputs" not in overrides:
        if cin not in INPUTS_BY_CHANNELS:
            raise ValueError(f"d1.l1.0 takes {cin} channels: name the inputs explicitly (--inputs)")
        fields["inputs"] = INPUTS_BY_CHANNELS[cin]
    fields.update(overrides)
    return Arch(**fields)


def check_state(arch: Arch, state: dict[str, torch.Tensor]) -> None:
    """Every tensor the architecture needs, with its shape, and nothing else."""
    want = arch.tensor_shapes()
    for name, shape in want.items():
        if name not in state:
            raise ValueError(f"tensor {name} missing (expected shape {list(shape)})")
        if tuple(state[name].shape) != shape:
            raise ValueError(f"tensor {name}: expected shape {list(shape)}, found {list(state[name].shape)}")
    extra = sorted(set(state) - set(want))
    if extra:
        raise ValueError(f"tensors not in the declared architecture: {extra[:5]}")


def write_weights(path: str | Path, arch: Arch, state: dict[str, torch.Tensor]) -> None:
    """Write the flat weights file atomically (temporary file in the same folder, then rename)."""
    check_state(arch, state)
    tensors = {k: state[k].detach().to(torch.float32).contiguous() for k in arch.tensor_shapes()}
    for name, t in tensors.items():
        if not torch.isfinite(t).all():
            raise ValueError(f"tensor {name} holds non-finite values")
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent or ".")
    os.close(fd)
    try:
        save_file(tensors, tmp, metadata={METADATA_KEY: arch.to_json()})
        _publish(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _publish(tmp: str, path: Path) -> None:
    """Give the temporary file normal permissions (mkstemp makes it 0600), then rename it."""
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)
    os.replace(tmp, path)


def interpolate(
    a: dict[str, torch.Tensor], b: dict[str, torch.Tensor], t: float, at: dict[str, float] | None = None
) -> dict[str, torch.Tensor]:
    """Weights ``(1 - t) * a + t * b``, tensor by tensor, computed in f64 and stored in f32.
    ``at`` gives other fractions by module: a tensor whose name starts with ``MODULE.`` (``d5``,
    ``bottleneck``) takes ``at[MODULE]``. Two fine-tunes of one model average into a model
    that is often better than either, and the fraction per level trades one's gains against the
    other's behaviour (the deep levels set how far the network reaches, and so a tile's seams)."""
    if a.keys() != b.keys():
        raise ValueError(f"the weights differ in their tensors: {sorted(a.keys() ^ b.keys())[:5]}")
    at = at or {}
    out = {}
    for name, x in a.items():
        if x.shape != b[name].shape:
            raise ValueError(f"tensor {name}: shapes {list(x.shape)} and {list(b[name].shape)}")
        f = at.get(name.split(".", 1)[0], t)
        out[name] = ((1 - f) * x.double() + f * b[name].double()).to(torch.float32)
    return out


def drop_inputs(arch: Arch, state: dict[str, torch.Tensor], fill: dict[str, float]) -> tuple[Arch, dict[str, torch.Tensor]]:
    """A network for fewer buffers from one for more: each input in ``fill`` leaves the first
    conv, its columns folded into the bias as if that channel held the given value everywhere
    (a typical one: the training data's mean). Exact for a frame whose buffer holds that value,
    but for the frame's border pixels, where the original conv reads zero padding."""
    unknown = [n for n in fill if n not in arch.inputs]
    if unknown or "color" in fill:
        raise ValueError(f"cannot drop {unknown or ['color']}: the network reads {arch.inputs}")
    w, b = state["d1.l1.0.weight"], state["d1.l1.0.bias"]
    keep, bias, c = [], b.double(), 0
    for name in arch.inputs:
        n = INPUT_CHANNELS[name]
        if name in fill:
            bias = bias + w[:, c : c + n].double().sum(dim=(1, 2, 3)) * fill[name]
        else:
            keep.extend(range(c, c + n))
        c += n
    out = dict(state)
    out["d1.l1.0.weight"] = w[:, keep].clone()
    out["d1.l1.0.bias"] = bias.to(torch.float32)
    return dataclasses.replace(arch, inputs=[n for n in arch.inputs if n not in fill]), out


def read_weights(path: str | Path) -> tuple[Arch, dict[str, torch.Tensor]]:
    """Read a weights file back (architecture and tensors)."""
    with safe_open(str(path), framework="pt") as f:
        meta = f.metadata() or {}
        if METADATA_KEY not in meta:
            raise ValueError(f"{path}: no '{METADATA_KEY}' in the safetensors metadata")
        arch = Arch.from_json(meta[METADATA_KEY])
        state = {k: f.get_tensor(k) for k in f.keys()}
    check_state(arch, state)
    return arch, state

"""Held-out evaluation for the model card: the noisy input, each rae model, and Intel Open Image
Denoise (pyoidn, color+albedo+normal, HDR) on the same frames.

    python -m rae_weights evaluate ../models/*.safetensors --data 1spp=DATA/val 4spp=DATA/val4

rae runs here in PyTorch (float32) from the shipped weights file, with rae-core's exact input and
output stages (``prepare_input``/``finish_output``); the golden tests hold wgpu to the same
network within 1e-4. Metrics are those of rae-core (``metrics``): relMSE on radiance, PSNR and
SSIM on tonemapped images, temporal error on tonemapped frame differences; means over the
frames of each sequence, then over sequences. Prints a Markdown table.
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

import numpy as np
import torch

from . import accumulate as temporal
from .data import Sequence, load_sequences
from .export import read_weights
from .metrics import sequence_metrics
from .model import RecurrentAE, finish_output, prepare_input


def hwc(t: torch.Tensor) -> np.ndarray:
    """[1, C, H, W] or [C, H, W] tensor -> HxWxC float32 array."""
    return t.reshape(t.shape[-3:]).permute(1, 2, 0).contiguous().numpy().astype(np.float32)


def run_rae(
    path: Path, seq: Sequence, times: list[float] | None = None, motion: bool = True, accumulate: bool = True
) -> list[np.ndarray]:
    """Denoised frames of a sequence by a rae weights file (hidden state carried, and reprojected
    with the sequence's motion where it has one and `motion`, the output then accumulated along
    it where `accumulate` (``accumulate.accumulate``), as `rae-cli denoise` does; CPU, float32,
    channels_last). With `times`, appends the ms of every frame after the first (input stage,
    network, output stage, accumulation)."""
    arch, state = read_weights(path)
    model = RecurrentAE(arch).eval()
    model.load_state_dict(state)
    model = model.to(memory_format=torch.channels_last)
    model.reset()
    outs = []
    previous = None
    with torch.inference_mode():
        for i in range(seq.frames):
            t = time.perf_counter()
            frame = {k: v[i : i + 1] for k, v in seq.buffers.items()}
            x = prepare_input(arch, frame).contiguous(memory_format=torch.channels_last)
            m = frame.get("motion") if motion else None
            y = finish_output(arch, model(x, m), frame)
            if accumulate:
                y = previous = temporal.accumulate(y.contiguous(), previous, m)
            outs.append(hwc(y))
            if times is not None and i > 0:
                times.append((time.perf_counter() - t) * 1e3)
    return outs


def run_oidn(seq: Sequence, quality: str, times: list[float] | None = None) -> list[np.ndarray]:
    """OIDN's RT filter on each frame alone (it has no temporal mode): HDR color+albedo+normal.
    With `times`, one untimed call first (the filter is committed on a change of quality) and the
    ms of every frame after the first appended."""
    import pyoidn

    outs = []
    for i in range(seq.frames):
        b = {k: np.ascontiguousarray(np.nan_to_num(hwc(seq.buffers[k][i]))) for k in ("color", "albedo", "normal")}
        if times is not None and i == 0:
            pyoidn.denoise(b["color"], b["albedo"], b["normal"], hdr=True, quality=quality)
        t = time.perf_counter()
        outs.append(np.asarray(pyoidn.denoise(b["color"], b["albedo"], b["normal"], hdr=True, quality=quality), dtype=np.float32))
        if times is not None and i > 0:
            times.append((time.perf_counter() - t) * 1e3)
    return outs


#: The buffers ``with_aux_from`` takes from the other render.
AUX_BUFFERS = ("albedo", "normal", "depth", "roughness")


def with_aux_from(seqs: list[Sequence], other: list[Sequence]) -> list[Sequence]:
    """The sequences with the auxiliary buffers (``AUX_BUFFERS``) of the same-named sequences of
    another render of the same frames (e.g. the 4 spp render of a 1 spp set): how much the
    noise of a renderer's auxiliary buffers costs, color and reference unchanged."""
    by_name = {o.name: o for o in other}
    out = []
    for s in seqs:
        o = by_name.get(s.name)
        if o is None:
            raise ValueError(f"{s.folder}: no sequence {s.name!r} in the render to take auxiliary buffers from")
        buffers = dict(s.buffers)
        for k in AUX_BUFFERS:
            if k in buffers:
                if k not in o.buffers or o.buffers[k].shape != buffers[k].shape:
                    raise ValueError(f"{o.folder}: {k} missing or of another size than {s.folder}'s")
                buffers[k] = o.buffers[k]
        out.append(dataclasses.replace(s, buffers=buffers))
    return out


def evaluate(
    models: list[Path],
    sets: dict[str, Path],
    oidn: bool = True,
    motion: str = "both",
    accumulate: str = "on",
    per_sequence: bool = False,
    aux_from: dict[str, Path] | None = None,
) -> list[dict[str, object]]:
    """Rows of (set, sequence, method, metrics...): each set's means over its sequences (sequence
    ``"all"``), then with `per_sequence` each sequence's own rows. Where a sequence has motion,
    each model runs with it (its hidden state reprojected), without it, or both (`motion`: on,
    off, both), as separate rows; with motion, its output accumulated along it, not, or both
    (`accumulate`). `aux_from` maps a set's label to another render of the same frames whose
    auxiliary buffers every method reads instead of the set's own (``with_aux_from``)."""
    rows: list[dict[str, object]] = []
    for label, folder in sets.items():
        seqs = load_sequences(folder)
        if aux_from and label in aux_from:
            seqs = with_aux_from(seqs, load_sequences(aux_from[label]))
        # method -> sequence index -> metrics (a set may mix sequences with and without motion)
        methods: dict[str, dict[int, dict[str, float]]] = {}
        for j, s in enumerate(seqs):
            refs = [hwc(s.buffers["reference"][i]) for i in range(s.frames)]
            noisy = [hwc(s.buffers["color"][i]) for i in range(s.frames)]
            methods.setdefault("noisy input", {})[j] = sequence_metrics(noisy, refs)
            for m in models:
                if "motion" not in s.buffers:
                    methods.setdefault(f"rae {m.stem}", {})[j] = sequence_metrics(run_rae(m, s), refs)
                    continue
                for on in {"on": [True], "off": [False], "both": [True, False]}[motion]:
                    for acc in {"on": [True], "off": [False], "both": [True, False]}[accumulate] if on else [False]:
                        name = f"rae {m.stem} ({'motion' if on else 'no motion'}{'' if acc or not on else ', no accumulation'})"
                        methods.setdefault(name, {})[j] = sequence_metrics(run_rae(m, s, motion=on, accumulate=acc), refs)
            if oidn:
                methods.setdefault("OIDN 2.5 high (c+a+n)", {})[j] = sequence_metrics(run_oidn(s, "high"), refs)
        for name, per in methods.items():
            ms = list(per.values())
            row: dict[str, object] = {"set": label, "sequence": "all", "method": name, "sequences": len(ms)}
            row.update({k: float(np.mean([m[k] for m in ms])) for k in ms[0]})
            rows.append(row)
        if per_sequence:
            for j, s in enumerate(seqs):
                rows += [{"set": label, "sequence": s.name, "method": name, "sequences": 1, **per[j]} for name, per in methods.items() if j in per]
    return rows


def markdown(rows: list[dict[str, object]]) -> str:
    """The rows as a Markdown table; a sequence column where some row is one sequence's."""
    seq = any(r.get("sequence", "all") != "all" for r in rows)
    out = [f"| held-out set |{' sequence |' if seq else ''} method | relMSE | PSNR (dB) | SSIM | temporal error |"]
    out.append(f"|---|{'---|' if seq else ''}---|---:|---:|---:|---:|")
    for r in rows:
        s = f" {r.get('sequence', 'all')} |" if seq else ""
        out.append(f"| {r['set']} |{s} {r['method']} | {r['relmse']:.4f} | {r['psnr']:.2f} | {r['ssim']:.4f} | {r['temporal']:.4f} |")
    return "\n".join(out)


def labelled_folders(p: argparse.ArgumentParser, option: str, values: list[str]) -> dict[str, Path]:
    """``LABEL=FOLDER`` arguments of `option` as {label: folder}; a usage error otherwise."""
    out = {}
    for d in values:
        label, _, folder = d.partition("=")
        if not label or not folder:
            p.error(f"{option} {d}: expected LABEL=FOLDER")
        out[label] = Path(folder)
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="rae-weights evaluate", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("models", nargs="+", type=Path, help="rae weights files")
    p.add_argument("--data", nargs="+", required=True, metavar="LABEL=FOLDER", help="held-out sets, e.g. 1spp=data/val")
    p.add_argument("--no-oidn", action="store_true")
    p.add_argument("--motion", choices=["on", "off", "both"], default="both", help="run the models with the sequences' motion, without, or both")
    p.add_argument(
        "--accumulate", choices=["on", "off", "both"], default="on", help="with motion, accumulate the output along it, not, or both"
    )
    p.add_argument("--per-sequence", action="store_true", help="each sequence's rows too, after the sets' means")
    p.add_argument(
        "--aux-from", nargs="+", default=[], metavar="LABEL=FOLDER", help="every method reads set LABEL's auxiliary buffers from another render of the same frames"
    )
    p.add_argument("--threads", type=int, default=2)
    a = p.parse_args(argv)
    torch.set_num_threads(a.threads)
    sets = labelled_folders(p, "--data", a.data)
    aux_from = labelled_folders(p, "--aux-from", a.aux_from)
    for label in aux_from.keys() - sets.keys():
        p.error(f"--aux-from {label}=...: no --data set {label!r}")
    rows = evaluate(a.models, sets, oidn=not a.no_oidn, motion=a.motion, accumulate=a.accumulate, per_sequence=a.per_sequence, aux_from=aux_from)
    print(markdown(rows))
    return 0

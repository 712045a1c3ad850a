"""Activation ranges of a trained model on real sequences, and their headroom to f16.

    python -m rae_weights ranges models/rae-default.safetensors --data DATA/train

Runs every sequence through the network (hidden state carried, as rae-core does) and records,
for each convolution, the largest |value| it stores (after its activation). rae-core stores
exactly these values in its activation textures; in f16 the largest finite value is 65504, so the
headroom is 65504 / max. Prints a Markdown table.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import torch

from .data import load_sequences
from .export import read_weights
from .model import RecurrentAE, prepare_input

F16_MAX = 65504.0


def activation_ranges(model: RecurrentAE, seqs: list, inputs_max: dict[str, float]) -> dict[str, float]:
    """Largest |stored value| per conv (module name), over every frame of every sequence."""
    ranges: dict[str, float] = {}
    hooks = []
    mods = dict(model.named_modules())
    for name, m in mods.items():
        if isinstance(m, torch.nn.Conv2d):
            # The stored value is the conv's output after the activation that follows it.
            parent, idx = name.rsplit(".", 1)
            seq = mods[parent]
            nxt = seq[int(idx) + 1] if int(idx) + 1 < len(seq) else None
            target = nxt if isinstance(nxt, (torch.nn.LeakyReLU, torch.nn.Identity)) else m

            def hook(_m: torch.nn.Module, _i: tuple, out: torch.Tensor, name: str = name) -> None:
                ranges[name] = max(ranges.get(name, 0.0), out.abs().max().item())

            hooks.append(target.register_forward_hook(hook))
    with torch.inference_mode():
        for s in seqs:
            model.reset()
            for i in range(s.frames):
                frame = {k: v[i : i + 1] for k, v in s.buffers.items()}
                x = prepare_input(model.arch, frame)
                inputs_max["input"] = max(inputs_max.get("input", 0.0), x.abs().max().item())
                model(x)
    for h in hooks:
        h.remove()
    return ranges


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="rae-weights ranges", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("weights")
    p.add_argument("--data", required=True, type=Path, help="folder of rae-trace sequences")
    p.add_argument("--threads", type=int, default=2)
    a = p.parse_args(argv)
    torch.set_num_threads(a.threads)
    arch, state = read_weights(a.weights)
    model = RecurrentAE(arch).eval()
    model.load_state_dict(state)
    seqs = load_sequences(a.data)
    extra: dict[str, float] = {}
    ranges = activation_ranges(model, seqs, extra)
    frames = sum(s.frames for s in seqs)
    print(f"Activation ranges of {a.weights} over {len(seqs)} sequences ({frames} frames) in {a.data}\n")
    print("| stage | max abs value | f16 headroom (65504 / max) |")
    print("|---|---:|---:|")
    print(f"| network input (prep) | {extra['input']:.3g} | {F16_MAX / extra['input']:.0f}x |")
    for name, v in ranges.items():
        print(f"| {name} | {v:.3g} | {F16_MAX / max(v, 1e-30):.0f}x |")
    worst = max(ranges, key=lambda k: ranges[k])
    print(f"\nLeast headroom: {worst}, {F16_MAX / ranges[worst]:.0f}x.")
    return 0

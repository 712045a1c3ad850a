"""Training: the paper's loss on 7-frame clips, Adam with a cosine schedule, checkpoints,
resume, validation to CSV, export to rae's weights file.

    python -m rae_weights train --data DATA/train --val DATA/val --out runs/default --steps 4000

On a GPU (``--device cuda``) a step takes a batch of clips (``--batch``), and training can start
while a renderer still writes its data (``--reload-every``); ``scripts/gpu-train.sh`` does both on
a lent machine within a fixed time.

The network learns in its own space: inputs prepared exactly as rae-core prepares them
(sanitised, color demodulated by albedo and passed through the transfer function), and the
target is the reference prepared the same way, so rae-core's output stage inverts it.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import time
from pathlib import Path

import numpy as np
import torch
import torch.nn.functional as F

from . import accumulate as temporal
from . import transfer, warp
from .arch import INPUT_CHANNELS, Arch
from .data import Sequence, load_sequences, sample
from .export import load_checkpoint, write_weights
from .metrics import sequence_metrics
from .model import RecurrentAE, demodulation_albedo, finish_output, pass_misses, prepare_input, sanitize_buffers

#: The paper's per-frame loss weights for 7-frame clips (later frames count more).
PAPER_FRAME_WEIGHTS = (0.011, 0.044, 0.135, 0.325, 0.607, 0.882, 1.0)


def target_space(arch: Arch, clip: dict[str, torch.Tensor]) -> torch.Tensor:
    """The reference in the network's output space: log1p(reference / (albedo + eps)), the
    albedo canonical as the input's (``model.demodulation_albedo``)."""
    r = sanitize_buffers({"color": clip["reference"]})["color"]
    if arch.demodulate:
        r = r / demodulation_albedo(arch, clip)
    return transfer.encode(arch.transfer, r)


def log_kernel(size: int = 5, sigma: float = 1.0) -> torch.Tensor:
    """Laplacian of Gaussian, zero-sum, for the HFEN gradient term."""
    ax = torch.arange(size, dtype=torch.float32) - size // 2
    yy, xx = torch.meshgrid(ax, ax, indexing="ij")
    r2 = (xx**2 + yy**2) / (2 * sigma**2)
    k = (r2 - 1) * torch.exp(-r2)
    return (k - k.mean()).view(1, 1, size, size)


PAPER_LOSS_WEIGHTS = (0.8, 0.1, 0.1)


def loss_fn(
    ys: list[torch.Tensor],
    ts: list[torch.Tensor],
    weights: tuple[float, ...],
    log: torch.Tensor,
    terms: tuple[float, float, float] = PAPER_LOSS_WEIGHTS,
    motions: list[torch.Tensor] | None = None,
) -> torch.Tensor:
    """ws spatial L1 + wg HFEN L1 + wt temporal L1 (the paper's 0.8/0.1/0.1), each frame weighted.
    With each frame's ``motions``, the temporal term compares ``y_t - warp(y_t-1)`` with
    ``t_t - warp(t_t-1)``: change along the motion, not at a fixed pixel."""
    ws, wg, wt = terms
    total = ys[0].new_zeros(())
    c = ys[0].shape[1]
    k = log.to(ys[0]).repeat(c, 1, 1, 1)
    for i, (y, t) in enumerate(zip(ys, ts)):
        ls = F.l1_loss(y, t)
        lg = F.l1_loss(F.conv2d(y, k, padding=2, groups=c), F.conv2d(t, k, padding=2, groups=c))
        if i == 0:
            lt = y.new_zeros(())
        elif motions is None:
            lt = F.l1_loss(y - ys[i - 1], t - ts[i - 1])
        else:
            m, v = warp.pyramid(motions[i], 0)[0]
            lt = F.l1_loss(y - warp.warp(ys[i - 1], m, v), t - warp.warp(ts[i - 1], m, v))
        total = total + weights[i] * (ws * ls + wg * lg + wt * lt)
    return total / sum(weights)


def clip_frame(clip: dict[str, torch.Tensor], i: int) -> dict[str, torch.Tensor]:
    """Frame ``i``'s renderer buffers of a batch of clips (``batch``): what the input and output
    stages read, without the reference and the motion."""
    return {k: v[i] for k, v in clip.items() if k not in ("reference", "motion")}


def run_clip(model: RecurrentAE, arch: Arch, clip: dict[str, torch.Tensor]) -> list[torch.Tensor]:
    """Network outputs (N x C x H x W) for each frame of a batch of clips ([T, N, C, H, W]
    buffers, ``batch``), hidden state carried and reprojected with the clips' motion where they
    have it, misses passed through (``pass_misses``) as the output stage does."""
    model.reset()
    outs = []
    for i in range(clip["color"].shape[0]):
        frame = clip_frame(clip, i)
        x = prepare_input(arch, frame).contiguous(memory_format=torch.channels_last)
        motion = clip["motion"][i] if "motion" in clip else None
        outs.append(pass_misses(arch, model(x, motion), frame))
    return outs


def accumulated(arch: Arch, ys: list[torch.Tensor], clip: dict[str, torch.Tensor]) -> list[torch.Tensor]:
    """The outputs ``ys`` (``run_clip``) as rae-core delivers them for a sequence with motion:
    in radiance (``finish_output``), accumulated along the clip's motion
    (``accumulate.accumulate``), then back in the network's output space with misses passed
    through, so the loss can be measured on what the user sees. Without motion, ``ys``."""
    if "motion" not in clip:
        return ys
    out: list[torch.Tensor] = []
    previous = None
    for i, y in enumerate(ys):
        frame = clip_frame(clip, i)
        previous = temporal.accumulate(finish_output(arch, y, frame), previous, clip["motion"][i])
        r = previous / demodulation_albedo(arch, frame) if arch.demodulate else previous
        out.append(pass_misses(arch, transfer.encode(arch.transfer, r), frame))
    return out


def batch(clips: list[dict[str, torch.Tensor]], device: torch.device) -> dict[str, torch.Tensor]:
    """Clips of [T, C, H, W] buffers (``data.sample``) stacked into one batch [T, N, C, H, W] on
    ``device``; a buffer only some clips have (motion) is left out."""
    names = [k for k in clips[0] if all(k in c for c in clips)]
    return {k: torch.stack([c[k] for c in clips], 1).to(device, non_blocking=True) for k in names}


@torch.no_grad()
def validate(model: RecurrentAE, arch: Arch, seqs: list[Sequence]) -> dict[str, float]:
    """Held-out metrics over whole sequences (``metrics.sequence_metrics``), input and rae,
    averaged over sequences."""
    model.eval()
    device = next(model.parameters()).device
    rows: dict[str, list[float]] = {}
    for s in seqs:
        clip = batch([s.buffers], device)
        ys = run_clip(model, arch, clip)
        outs, noisy, refs = [], [], []
        for i, y in enumerate(ys):
            frame = {k: v[i] for k, v in clip.items()}
            outs.append(finish_output(arch, y, frame)[0].permute(1, 2, 0).cpu().numpy())
            noisy.append(frame["color"][0].permute(1, 2, 0).cpu().numpy())
            refs.append(frame["reference"][0].permute(1, 2, 0).cpu().numpy())
        for who, imgs in (("input", noisy), ("rae", outs)):
            for k, v in sequence_metrics(imgs, refs).items():
                rows.setdefault(f"{k}_{who}", []).append(v)
    model.train()
    return {k: float(np.mean(v)) for k, v in rows.items()}


#: Validation columns of the training log, in order.
VAL_COLUMNS = ["relmse_input", "relmse_rae", "ssim_input", "ssim_rae", "temporal_input", "temporal_rae"]


def warm_start(model: RecurrentAE, arch: Arch, state: dict[str, torch.Tensor], src: Arch) -> int:
    """Initialise ``model`` from another architecture's weights: every tensor of equal shape is
    copied; the first convolution's input columns are copied by buffer name (a color+normal net
    starts from the default net's color and normal columns), and the columns of a buffer the
    source does not read start at zero, so the network computes what the source computes (for the
    buffers they share) and learns to use the new buffer from there. Returns the tensors copied."""
    own = model.state_dict()
    copied = 0
    for name, t in own.items():
        w = state.get(name)
        if w is None:
            continue
        if w.shape == t.shape:
            own[name] = w.clone()
            copied += 1
        elif name == "d1.l1.0.weight" and w.shape[0] == t.shape[0]:
            new = torch.zeros_like(t)
            offsets = {}
            c = 0
            for b in src.inputs:
                offsets[b] = c
                c += INPUT_CHANNELS[b]
            c = 0
            for b in arch.inputs:
                n = INPUT_CHANNELS[b]
                if b in offsets:
                    new[:, c : c + n] = w[:, offsets[b] : offsets[b] + n]
                c += n
            own[name] = new
            copied += 1
    model.load_state_dict(own)
    return copied


def on_device(seqs: list[Sequence], device: torch.device) -> list[Sequence]:
    """``seqs`` with their buffers moved to ``device``, where clips are then cut (``data.sample``)."""
    for s in seqs:
        s.buffers = {k: v.to(device) for k, v in s.buffers.items()}
    return seqs


def reload(roots: list[Path], have: list[Sequence], device: torch.device) -> list[Sequence]:
    """``have`` and the sequences under ``roots`` not yet in it, on ``device`` (a renderer writes
    each under a hidden name and renames it when done, so a folder seen here is complete)."""
    known = {s.folder for s in have}
    new = on_device([s for r in roots for s in load_sequences(r, skip=known, empty_ok=True)], device)
    if new:
        print(f"{len(new)} more training sequences ({len(have) + len(new)} in all)", flush=True)
    return have + new


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="rae-weights train", description=__doc__)
    p.add_argument("--data", required=True, type=Path, nargs="+", help="folders of training sequences (searched recursively)")
    p.add_argument("--val", type=Path)
    p.add_argument("--out", required=True, type=Path)
    p.add_argument("--steps", type=int, default=4000)
    p.add_argument("--lr", type=float, default=5e-4)
    p.add_argument("--crop", type=int, default=128)
    p.add_argument("--frames", type=int, default=7)
    p.add_argument(
        "--inputs",
        help="network inputs, comma-separated (default: those of the --init weights, so a round continues the model it starts from; without --init color,normal,depth,roughness)",
    )
    p.add_argument("--no-demodulate", action="store_true", help="feed color as is (no albedo needed)")
    p.add_argument(
        "--skip",
        choices=["pooled", "prepool"],
        default="pooled",
        help="the decoder's skips: pooled encoder features (the reference code) or full-resolution ones before pooling (the paper)",
    )
    p.add_argument("--transfer", choices=transfer.TRANSFERS, default="log1p", help="HDR transfer on color (rae-core runs log1p and none; the others are for comparison)")
    p.add_argument("--init", type=Path, help="warm start from a checkpoint of another architecture (see warm_start)")
    p.add_argument("--frame-weights", choices=["paper", "equal"], default="paper")
    p.add_argument(
        "--loss-weights",
        default="0.8,0.1,0.1",
        help="spatial,gradient,temporal weights of the loss (the paper's 0.8,0.1,0.1); a fine-tune may weigh temporal more",
    )
    p.add_argument(
        "--accumulated-loss",
        type=float,
        default=0.0,
        help="share of the loss measured on the output accumulated along the motion, as rae-core delivers a sequence with motion (accumulated); the rest on the network's own output",
    )
    p.add_argument("--val-every", type=int, default=500)
    p.add_argument("--ckpt-every", type=int, default=250)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument(
        "--conventions",
        choices=["varied", "as-rendered"],
        default="varied",
        help="varied: clips as other renderers might write them (normals turned, depth in other units; data.vary_conventions)",
    )
    p.add_argument("--threads", type=int, default=max(1, (os.cpu_count() or 2)))
    p.add_argument(
        "--max-minutes",
        type=float,
        default=0.0,
        help="stop (checkpoint and export) after this long; the learning rate's cosine runs over whichever ends first, the steps or the minutes",
    )
    p.add_argument("--device", default="cpu", help="torch device to train on (cpu, cuda)")
    p.add_argument("--batch", type=int, default=1, help="clips per step")
    p.add_argument(
        "--reload-every",
        type=float,
        default=0.0,
        help="rescan the --data folders every this many seconds for sequences a renderer has finished since (0: load once)",
    )
    a = p.parse_args(argv)
    if a.batch < 1:
        p.error(f"--batch {a.batch}: at least 1")
    terms = tuple(float(v) for v in a.loss_weights.split(","))
    if len(terms) != 3 or min(terms) < 0 or sum(terms) <= 0:
        p.error(f"--loss-weights {a.loss_weights}: expected three non-negative numbers, not all zero")
    if not 0.0 <= a.accumulated_loss <= 1.0:
        p.error(f"--accumulated-loss {a.accumulated_loss}: a share between 0 and 1")
    torch.set_num_threads(a.threads)
    device = torch.device(a.device)
    if device.type == "cuda":
        torch.backends.cudnn.benchmark = True  # every step has the same shapes
    torch.manual_seed(a.seed)
    rng = np.random.default_rng(a.seed)
    a.out.mkdir(parents=True, exist_ok=True)
    state, src = load_checkpoint(a.init) if a.init else (None, None)
    inputs = a.inputs.split(",") if a.inputs else list(src.inputs if src else Arch().inputs)
    arch = Arch(inputs=inputs, demodulate=not a.no_demodulate, transfer=a.transfer, skip=a.skip)
    model = RecurrentAE(arch)
    ckpt = a.out / "checkpoint.pt"
    if state is not None and not ckpt.exists():
        n = warm_start(model, arch, state, src or Arch())
        print(f"warm start from {a.init}: {n} of {len(model.state_dict())} tensors")
    model = model.to(device, memory_format=torch.channels_last)
    opt = torch.optim.Adam(model.parameters(), lr=a.lr, betas=(0.9, 0.99))
    start = time.time()

    def progress(s: int) -> float:
        """How far through the schedule step ``s`` is: by steps, or by time under --max-minutes."""
        by_time = (time.time() - start) / (60 * a.max_minutes) if a.max_minutes > 0 else 0.0
        return min(1.0, max(s / a.steps, by_time))

    sched = torch.optim.lr_scheduler.LambdaLR(opt, lambda s: 0.5 * (1 + math.cos(math.pi * progress(s))) * min(1.0, (s + 1) / 100))
    step = 0
    if ckpt.exists():
        state = torch.load(ckpt, map_location=device, weights_only=True)
        model.load_state_dict(state["state_dict"])
        opt.load_state_dict(state["optimizer"])
        sched.load_state_dict(state["scheduler"])
        step = int(state["step"])
        print(f"resumed at step {step}")
    # Under --reload-every a folder a renderer has not written to yet is taken up later.
    train = on_device([s for d in a.data for s in load_sequences(d, empty_ok=a.reload_every > 0)], device)
    if not train:
        p.error(f"--data {' '.join(map(str, a.data))}: no sequences yet")
    val = load_sequences(a.val) if a.val else []
    print(f"{len(train)} training sequences, {len(val)} held out; arch {arch.to_json()}")
    loaded = time.time()
    weights = PAPER_FRAME_WEIGHTS if a.frame_weights == "paper" and a.frames == 7 else (1.0,) * a.frames
    log = log_kernel().to(device)
    log_path = a.out / "log.csv"
    new_log = not log_path.exists()
    logf = log_path.open("a", newline="")
    writer = csv.writer(logf)
    if new_log:
        writer.writerow(["step", "seconds", "loss", "lr", *VAL_COLUMNS])
    start, running = time.time(), []  # the clock --max-minutes and the schedule run on

    def save() -> None:
        tmp = ckpt.with_suffix(".tmp")
        torch.save({"arch": arch.to_json(), "state_dict": model.state_dict(), "optimizer": opt.state_dict(), "scheduler": sched.state_dict(), "step": step}, tmp)
        os.replace(tmp, ckpt)

    while step < a.steps:
        if a.reload_every > 0 and time.time() - loaded > a.reload_every:
            train = reload(a.data, train, device)
            loaded = time.time()
        clip = batch([sample(train, a.frames, a.crop, rng, vary=a.conventions == "varied") for _ in range(a.batch)], device)
        ys = run_clip(model, arch, clip)
        ts = [target_space(arch, {k: v[i] for k, v in clip.items()}) for i in range(a.frames)]
        motions = [clip["motion"][i] for i in range(a.frames)] if "motion" in clip else None
        share = a.accumulated_loss
        parts = [(1.0 - share, ys)] + ([(share, accumulated(arch, ys, clip))] if share > 0.0 else [])
        loss = sum(w * loss_fn(out, ts, weights, log, terms, motions) for w, out in parts if w > 0.0)  # type: ignore[arg-type]
        opt.zero_grad(set_to_none=True)
        loss.backward()
        # A step whose gradient is not finite (one extreme pixel) is skipped, not taken.
        if torch.isfinite(torch.nn.utils.clip_grad_norm_(model.parameters(), 1.0)):
            opt.step()
        sched.step()
        step += 1
        running.append(loss.item())
        out_of_time = a.max_minutes > 0 and time.time() - start > 60 * a.max_minutes
        if step % a.ckpt_every == 0 or step == a.steps or out_of_time:
            save()
        if step % a.val_every == 0 or step == a.steps or out_of_time:
            v = validate(model, arch, val) if val else {}
            writer.writerow([step, round(time.time() - start, 1), float(np.mean(running)), sched.get_last_lr()[0], *(v.get(c, math.nan) for c in VAL_COLUMNS)])
            logf.flush()
            print(f"step {step}: loss {np.mean(running):.4f} {json.dumps(v)} ({time.time() - start:.0f} s)", flush=True)
            running = []
        if out_of_time:
            break
    write_weights(a.out / "model.safetensors", arch, {k: v.cpu() for k, v in model.state_dict().items()})
    print(f"wrote {a.out / 'model.safetensors'} after {step} steps, {time.time() - start:.0f} s")
    return 0

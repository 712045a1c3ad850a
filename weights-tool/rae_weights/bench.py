"""PyTorch CPU inference time per frame of a rae weights file: the peer rae's speed is held to.

    python -m rae_weights bench models/rae-default.safetensors --sizes 256x256 --threads 2

Same network and weights as rae-core (read from the safetensors file), recurrent state carried
frame to frame, ``channels_last``, ``torch.inference_mode``; median over timed frames after two
warm-up frames. Prints a table in the shape of ``rae-cli bench``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import torch

from .export import read_weights
from .model import RecurrentAE


def macs_per_pixel(model: RecurrentAE) -> float:
    """Multiply-adds per full-resolution pixel, counted as rae-core's ``Graph::macs_per_pixel``."""
    total = 0.0
    n = model.arch.levels
    for name, m in model.named_modules():
        if isinstance(m, torch.nn.Conv2d):
            top = name.split(".")[0]
            level = n if top == "bottleneck" else int(top[1:]) - 1
            total += 9 * m.in_channels * m.out_channels / 4**level
    return total


def time_frames(model: RecurrentAE, width: int, height: int, frames: int) -> list[float]:
    """Seconds per frame for `frames` timed frames after 2 warm-up frames, on the model's device
    and dtype (a CUDA frame is timed to its completion)."""
    p = next(model.parameters())
    x = torch.rand(1, model.arch.in_channels, height, width, device=p.device, dtype=p.dtype).contiguous(memory_format=torch.channels_last)
    cuda = p.device.type == "cuda"
    model.reset()
    times = []
    with torch.inference_mode():
        for i in range(frames + 2):
            if cuda:
                torch.cuda.synchronize()
            t = time.perf_counter()
            model(x)
            if cuda:
                torch.cuda.synchronize()
            if i >= 2:
                times.append(time.perf_counter() - t)
    return times


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="rae-weights bench", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("weights")
    p.add_argument("--sizes", default="256x256", help="comma-separated WxH (multiples of 2^levels)")
    p.add_argument("--frames", type=int, default=10)
    p.add_argument("--threads", type=int, default=min(2, os.cpu_count() or 1))
    p.add_argument("--device", default="cpu", help="cpu or cuda (cuDNN; TF32 off so float32 is IEEE float32)")
    p.add_argument("--dtypes", default="float32", help="comma-separated: float32, float16 (float16 on cuda only)")
    p.add_argument("--tf32", action="store_true", help="let cuDNN run float32 convs in TF32 (PyTorch's own default for convs on Ampere and later)")
    a = p.parse_args(argv)
    torch.set_num_threads(a.threads)
    torch.backends.cudnn.allow_tf32 = a.tf32
    torch.backends.cuda.matmul.allow_tf32 = a.tf32
    torch.backends.cudnn.benchmark = True
    arch, state = read_weights(a.weights)
    model = RecurrentAE(arch)
    model.load_state_dict(state)
    model = model.eval().to(memory_format=torch.channels_last)
    flop_px = 2 * macs_per_pixel(model)
    where = f"CPU, {a.threads} threads" if a.device == "cpu" else f"{torch.cuda.get_device_name()} (cuDNN {torch.backends.cudnn.version()}, TF32 {'on' if a.tf32 else 'off'})"
    print(f"PyTorch {torch.__version__} {where}, channels_last; weights: {a.weights}; {a.frames} timed frames after 2 warm-up")
    print(f"{'size':>10} {'dtype':>8} {'ms':>10} {'GFLOP/s':>10}")
    for dtype in a.dtypes.split(","):
        m = model.to(device=a.device, dtype=getattr(torch, dtype))
        for s in a.sizes.split(","):
            w, h = (int(v) for v in s.lower().split("x"))
            ms = statistics.median(time_frames(m, w, h, a.frames)) * 1e3
            print(f"{s:>10} {dtype:>8} {ms:>10.2f} {flop_px * w * h / (ms * 1e-3) / 1e9:>10.2f}")
    return 0

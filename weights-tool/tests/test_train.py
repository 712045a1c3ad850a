"""Training pieces: the loss, the target space the runtime inverts, data loading, two steps."""

from pathlib import Path

import numpy as np
import pytest
import torch

from rae_weights import Arch, finish_output
from rae_weights.train import PAPER_FRAME_WEIGHTS, log_kernel, loss_fn, main, target_space


def test_loss_is_zero_for_a_perfect_result_and_sees_temporal_error() -> None:
    torch.manual_seed(0)
    ts = [torch.rand(1, 3, 16, 16) for _ in range(7)]
    log = log_kernel()
    assert loss_fn(ts, ts, PAPER_FRAME_WEIGHTS, log).item() == 0.0
    # Same per-frame error, but flickering vs constant: the temporal term tells them apart.
    steady = [t + 0.1 for t in ts]
    flicker = [t + (0.1 if i % 2 else -0.1) for i, t in enumerate(ts)]
    assert loss_fn(flicker, ts, PAPER_FRAME_WEIGHTS, log) > loss_fn(steady, ts, PAPER_FRAME_WEIGHTS, log)
    assert log_kernel().sum().abs().item() < 1e-6, "LoG is zero-sum: flat images have no gradient loss"


def test_target_space_is_inverted_by_the_output_stage() -> None:
    arch = Arch()
    ref = torch.rand(1, 3, 8, 8) * 20
    albedo = torch.rand(1, 3, 8, 8)
    y = target_space(arch, {"reference": ref, "albedo": albedo})
    back = finish_output(arch, y, {"albedo": albedo})
    assert torch.allclose(back, ref, rtol=1e-4, atol=1e-5)


def _write_sequence(folder: Path, frames: int, size: int) -> None:
    OpenEXR = pytest.importorskip("OpenEXR")
    folder.mkdir(parents=True)
    rng = np.random.default_rng(1)
    for f in range(frames):
        for name, c in [("color", 3), ("reference", 3), ("albedo", 3), ("normal", 3), ("depth", 1), ("roughness", 1)]:
            a = rng.random((size, size, c), dtype=np.float32)
            channels = {"RGB": a} if c == 3 else {"Y": a[..., 0]}
            header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
            OpenEXR.File(header, channels).write(str(folder / f"{name}_{f:04}.exr"))


def test_two_training_steps_write_checkpoint_log_and_weights(tmp_path: Path) -> None:
    _write_sequence(tmp_path / "data" / "a", 8, 32)
    out = tmp_path / "run"
    args = ["--data", str(tmp_path / "data"), "--val", str(tmp_path / "data"), "--out", str(out), "--steps", "2", "--crop", "32", "--val-every", "2", "--threads", "1"]
    assert main(args) == 0
    assert (out / "model.safetensors").exists() and (out / "checkpoint.pt").exists()
    rows = (out / "log.csv").read_text().strip().splitlines()
    assert rows[0].startswith("step,") and rows[-1].startswith("2,")
    # Resuming at the last step runs nothing more and exports again.
    assert main(args) == 0

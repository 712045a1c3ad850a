"""A small random rae-trace-like sequence on disk, for the tests that read EXR folders."""

from pathlib import Path

import numpy as np
import pytest

BUFFERS = [("color", 3), ("reference", 3), ("albedo", 3), ("normal", 3), ("depth", 1), ("roughness", 1)]


def write_sequence(folder: Path, frames: int, size: int, seed: int = 1, motion: bool = False) -> None:
    """Every buffer of `frames` frames at `size` x `size`, random values, ZIP EXR; with `motion`,
    motion_NNNN.exr (R, G) of a few pixels too."""
    OpenEXR = pytest.importorskip("OpenEXR")
    folder.mkdir(parents=True)
    rng = np.random.default_rng(seed)
    for f in range(frames):
        for name, c in BUFFERS:
            a = rng.random((size, size, c), dtype=np.float32)
            channels = {"RGB": a} if c == 3 else {"Y": a[..., 0]}
            header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
            OpenEXR.File(header, channels).write(str(folder / f"{name}_{f:04}.exr"))
        if motion:
            m = (rng.random((size, size, 2), dtype=np.float32) - 0.5) * 6
            header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
            OpenEXR.File(header, {"R": m[..., 0], "G": m[..., 1]}).write(str(folder / f"motion_{f:04}.exr"))

"""docs/sample.png: one frame of the shipped sample as noisy input | rae | reference, each tone
mapped as rae's previews are (x / (1 + x), then sRGB) and scaled 2x (nearest).

Run `bash scripts/demo.sh` first (it writes out/random2026/denoised_NNNN.exr), then
`python3 scripts/sample_picture.py [FRAME]` from the repository root.
"""

import sys
from pathlib import Path

import matplotlib.image
import numpy as np
import OpenEXR


def read_rgb(path: Path) -> np.ndarray:
    with OpenEXR.File(str(path)) as f:
        return np.asarray(f.channels()["RGB"].pixels, dtype=np.float32)


def tonemap(x: np.ndarray) -> np.ndarray:
    x = np.where(np.isfinite(x), np.maximum(x, 0.0), 0.0)
    t = x / (1.0 + x)
    return np.where(t <= 0.0031308, 12.92 * t, 1.055 * np.power(t, 1.0 / 2.4) - 0.055)


def main() -> None:
    frame = int(sys.argv[1]) if len(sys.argv) > 1 else 7
    seq, out = Path("samples/random2026"), Path("out/random2026")
    paths = [seq / f"color_{frame:04d}.exr", out / f"denoised_{frame:04d}.exr", seq / f"reference_{frame:04d}.exr"]
    for p in paths:
        if not p.exists():
            sys.exit(f"{p}: missing (run `bash scripts/demo.sh` first)")
    panels = [tonemap(read_rgb(p)) for p in paths]
    gap = np.ones((panels[0].shape[0], 4, 3), dtype=np.float32)
    row = np.concatenate([panels[0], gap, panels[1], gap, panels[2]], axis=1)
    row = np.repeat(np.repeat(row, 2, axis=0), 2, axis=1)
    target = Path("docs/sample.png")
    tmp = target.with_name(".sample.png.partial")
    matplotlib.image.imsave(tmp, np.clip(row, 0.0, 1.0), format="png")
    tmp.replace(target)
    print(f"{target}: frame {frame}, noisy | rae | reference")


if __name__ == "__main__":
    main()

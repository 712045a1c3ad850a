"""Copies multi-layer EXR sequences (Blender's, scripts/render-blender.py) keeping only the layers
rae reads (color, albedo, normal, depth, roughness, reference, motion in rae's convention), in
half precision where that is exact enough for training (albedo, normal, depth, roughness,
motion), so that a set travels small (a lent GPU machine takes 64 MiB): about 3.4 MB for an
8-frame 128x128 sequence instead of 6. `rae_weights.data` loads the copies as it loads the
originals.

    python3 scripts/compact-exr.py SRC DST      # every *.exr under SRC, same layout under DST
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import OpenEXR

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "weights-tool"))
from rae_weights.data import read_multilayer  # noqa: E402

HALF = {"albedo", "normal", "depth", "roughness", "motion"}


def compact(src: Path, dst: Path) -> None:
    """One frame: the buffers ``read_multilayer`` finds, as layers of their own names."""
    channels = {}
    for name, a in read_multilayer(src).items():
        dtype = np.float16 if name in HALF else np.float32
        letters = "RGB"[: a.shape[-1]] if a.shape[-1] > 1 else "Y"
        for i, c in enumerate(letters):
            channels[f"{name}.{c}"] = np.ascontiguousarray(a[..., i].astype(dtype))
    tmp = dst.with_name(f".{dst.name}.tmp")
    OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}, channels).write(str(tmp))
    tmp.replace(dst)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("src", type=Path)
    p.add_argument("dst", type=Path)
    a = p.parse_args()
    files = sorted(f for f in a.src.rglob("*.exr") if not f.name.startswith("."))
    if not files:
        sys.exit(f"{a.src}: no EXR files")
    for f in files:
        out = a.dst / f.relative_to(a.src)
        out.parent.mkdir(parents=True, exist_ok=True)
        compact(f, out)
    print(f"{len(files)} frames from {a.src} in {a.dst}")


if __name__ == "__main__":
    main()

"""Sequence loading: Blender's multi-layer EXRs read as rae-core reads them."""

from pathlib import Path

import numpy as np
import pytest

from rae_weights.data import load_sequences


def test_multilayer_frames_are_read_like_rae_core_reads_them(tmp_path: Path) -> None:
    OpenEXR = pytest.importorskip("OpenEXR")
    folder = tmp_path / "set" / "shot"
    folder.mkdir(parents=True)
    h, w = 4, 6
    full = lambda v: np.full((h, w), v, dtype=np.float32)  # noqa: E731
    for f in (1, 2):
        channels = {
            "ViewLayer.Combined": np.stack([full(1.0), full(2.0), full(3.0), full(1.0)], -1),
            "ViewLayer.Denoising Albedo": np.stack([full(0.5)] * 3, -1),
            "ViewLayer.Denoising Normal.X": full(0.0),
            "ViewLayer.Denoising Normal.Y": full(0.0),
            "ViewLayer.Denoising Normal.Z": full(-1.0),
            "ViewLayer.Denoising Depth.Z": full(4.0 + f),
            "ViewLayer.roughness.X": full(0.25),
            "ViewLayer.Vector.X": full(1.5),
            "ViewLayer.Vector.Y": full(0.75),
            "ViewLayer.Vector.Z": full(-1.5),
            "ViewLayer.Vector.W": full(-0.75),
            "ViewLayer.Mist.Z": full(0.3),
            "reference": np.stack([full(1.0)] * 3, -1),
        }
        header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
        OpenEXR.File(header, channels).write(str(folder / f"frame_{f:04}.exr"))
    (seq,) = load_sequences(tmp_path / "set")
    assert seq.name == "shot" and seq.folder == folder and seq.frames == 2
    b = seq.buffers
    assert b["color"].shape == (2, 3, h, w) and b["color"][0, :, 0, 0].tolist() == [1.0, 2.0, 3.0], "RGB of RGBA"
    assert b["normal"][0, :, 0, 0].tolist() == [0.0, 0.0, -1.0]
    assert b["depth"][1, 0, 0, 0] == 6.0 and b["roughness"][0, 0, 0, 0] == 0.25
    assert b["motion"][0, :, 0, 0].tolist() == [1.5, -0.75], "Blender's Vector is (X, -Y) in rae's convention"
    assert "Mist" not in str(sorted(b)), "layers rae does not use are left out"

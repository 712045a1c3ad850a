"""Sequence loading: Blender's multi-layer EXRs read as rae-core reads them."""

from pathlib import Path

import numpy as np
import pytest
import torch

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


def test_varied_conventions_keep_geometry_and_misses() -> None:
    import math

    import numpy as np

    from rae_weights.data import vary_conventions

    g = torch.Generator().manual_seed(0)
    normal = torch.nn.functional.normalize(torch.randn(3, 3, 4, 5, generator=g), dim=1)
    depth = torch.rand(3, 1, 4, 5, generator=g) * 9 + 1
    depth[:, :, 0, 0], depth[:, :, 0, 1] = math.inf, 0.0
    clip = {"color": torch.rand(3, 3, 4, 5, generator=g), "normal": normal, "depth": depth}
    changed_normals = changed_depth = 0
    for seed in range(20):
        out = vary_conventions(clip, np.random.default_rng(seed))
        assert torch.equal(out["color"], clip["color"])
        n = out["normal"]
        # One orthogonal map for the whole clip: lengths and angles between any two normals,
        # of any frames, are kept.
        flat, flat0 = n.permute(1, 0, 2, 3).reshape(3, -1), normal.permute(1, 0, 2, 3).reshape(3, -1)
        assert torch.allclose(flat.T @ flat, flat0.T @ flat0, atol=1e-5)
        changed_normals += not torch.allclose(n, normal)
        d = out["depth"]
        assert d[0, 0, 0, 0] == math.inf and d[0, 0, 0, 1] == 0.0, "misses stay misses"
        ratio = d[:, :, 1:] / depth[:, :, 1:]
        assert torch.allclose(ratio, ratio.flatten()[0].expand_as(ratio)), "one scale for every frame"
        changed_depth += not torch.equal(d, depth)
    assert 4 <= changed_normals <= 16 and 4 <= changed_depth <= 16, (changed_normals, changed_depth)

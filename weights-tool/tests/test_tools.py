"""The report-side commands: PyTorch bench cost model, activation ranges, evaluation table."""

from pathlib import Path

import numpy as np
import torch

from rae_weights import Arch, RecurrentAE
from rae_weights.bench import macs_per_pixel, time_frames
from rae_weights.data import load_sequences
from rae_weights.evaluate import AUX_BUFFERS, evaluate, markdown, with_aux_from
from rae_weights.export import write_weights
from rae_weights.ranges import activation_ranges
from sequences import write_sequence


def test_cost_model_matches_rae_core() -> None:
    # rae-core's Graph::macs_per_pixel for the default architecture (rae-cli info prints it).
    assert round(macs_per_pixel(RecurrentAE(Arch()))) == 73661
    small = RecurrentAE(Arch(encoder=[8, 8], bottleneck=8, inputs=["color"], demodulate=False))
    assert len(time_frames(small, 16, 16, 2)) == 2


def test_activation_ranges_cover_every_conv_and_see_the_input(tmp_path: Path) -> None:
    write_sequence(tmp_path / "s", 3, 16, seed=2)
    arch = Arch(encoder=[8, 8], bottleneck=8)
    model = RecurrentAE(arch).eval()
    extra: dict[str, float] = {}
    ranges = activation_ranges(model, load_sequences(tmp_path), extra)
    convs = [n for n, m in model.named_modules() if isinstance(m, torch.nn.Conv2d)]
    assert sorted(ranges) == sorted(convs)
    assert all(v >= 0 for v in ranges.values()) and extra["input"] > 0


def test_evaluation_rows_for_input_and_each_model(tmp_path: Path) -> None:
    write_sequence(tmp_path / "data" / "s", 3, 16, seed=2)
    arch = Arch(encoder=[8, 8], bottleneck=8)
    weights = tmp_path / "m.safetensors"
    write_weights(weights, arch, RecurrentAE(arch).state_dict())
    rows = evaluate([weights], {"1spp": tmp_path / "data"}, oidn=False)
    assert [r["method"] for r in rows] == ["noisy input", "rae m"]
    assert all(np.isfinite(r["relmse"]) and -1 <= r["ssim"] <= 1 and np.isfinite(r["temporal"]) for r in rows)
    assert markdown(rows).count("\n") == 3
    write_sequence(tmp_path / "data" / "t", 3, 16, seed=3)
    rows = evaluate([weights], {"1spp": tmp_path / "data"}, oidn=False, per_sequence=True)
    assert [(r["sequence"], r["method"]) for r in rows] == [
        ("all", "noisy input"), ("all", "rae m"), ("s", "noisy input"), ("s", "rae m"), ("t", "noisy input"), ("t", "rae m")
    ]
    # The sets' means are the means of their sequences' rows.
    for k in ("relmse", "psnr", "ssim", "temporal"):
        assert np.isclose(rows[1][k], (rows[3][k] + rows[5][k]) / 2)
    assert markdown(rows).splitlines()[0].startswith("| held-out set | sequence | method |")


def test_auxiliary_buffers_from_another_render(tmp_path: Path) -> None:
    """with_aux_from swaps albedo, normal, depth and roughness for another render's (same
    sequence names), keeps color and reference, and names the file when they do not match."""
    import pytest

    write_sequence(tmp_path / "a" / "s", 2, 16, seed=2)
    write_sequence(tmp_path / "b" / "s", 2, 16, seed=3)
    write_sequence(tmp_path / "c" / "other", 2, 16, seed=4)
    write_sequence(tmp_path / "d" / "s", 2, 8, seed=5)
    (a,), (b,) = load_sequences(tmp_path / "a"), load_sequences(tmp_path / "b")
    (swapped,) = with_aux_from([a], [b])
    for k in a.buffers:
        expected = b.buffers[k] if k in AUX_BUFFERS else a.buffers[k]
        assert torch.equal(swapped.buffers[k], expected), k
    assert not torch.equal(a.buffers["albedo"], b.buffers["albedo"])
    with pytest.raises(ValueError, match="no sequence 's'"):
        with_aux_from([a], load_sequences(tmp_path / "c"))
    with pytest.raises(ValueError, match="another size"):
        with_aux_from([a], load_sequences(tmp_path / "d"))
    arch = Arch(encoder=[8, 8], bottleneck=8)
    weights = tmp_path / "m.safetensors"
    write_weights(weights, arch, RecurrentAE(arch).state_dict())
    own = evaluate([weights], {"x": tmp_path / "a"}, oidn=False)
    other = evaluate([weights], {"x": tmp_path / "a"}, oidn=False, aux_from={"x": tmp_path / "b"})
    assert own[0]["psnr"] == other[0]["psnr"]  # the noisy input: color is the set's own
    assert own[1]["psnr"] != other[1]["psnr"]  # the model reads the other render's buffers
    from rae_weights.evaluate import main

    for bad in (["--aux-from", f"y={tmp_path / 'b'}"], ["--aux-from", "x"]):
        with pytest.raises(SystemExit):
            main([str(weights), "--data", f"x={tmp_path / 'a'}", "--no-oidn", *bad])


def test_per_sequence_rows_of_a_set_mixing_sequences_with_and_without_motion(tmp_path: Path) -> None:
    write_sequence(tmp_path / "data" / "still", 3, 16, seed=2)
    write_sequence(tmp_path / "data" / "moving", 3, 16, seed=3, motion=True)
    arch = Arch(encoder=[8, 8], bottleneck=8)
    weights = tmp_path / "m.safetensors"
    write_weights(weights, arch, RecurrentAE(arch).state_dict())
    rows = evaluate([weights], {"x": tmp_path / "data"}, oidn=False, motion="on", per_sequence=True)
    per = [(r["sequence"], r["method"]) for r in rows if r["sequence"] != "all"]
    assert sorted(per) == sorted([("still", "noisy input"), ("still", "rae m"), ("moving", "noisy input"), ("moving", "rae m (motion)")])
    means = {r["method"]: r["sequences"] for r in rows if r["sequence"] == "all"}
    assert means == {"noisy input": 2, "rae m": 1, "rae m (motion)": 1}

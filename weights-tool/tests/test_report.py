"""The report command end to end on a tiny sequence: every method's row, rae against PyTorch, figures."""

from pathlib import Path

import numpy as np
import pytest

from rae_weights import Arch, RecurrentAE
from rae_weights.export import write_weights
from rae_weights.report import find_rae_cli, main
from sequences import write_sequence


def test_report_puts_every_method_side_by_side(tmp_path: Path) -> None:
    pytest.importorskip("pyoidn")
    pytest.importorskip("flip_evaluator")
    pytest.importorskip("matplotlib")
    cli = find_rae_cli()
    if cli is None:
        pytest.fail("build rae-cli first (cargo build -p rae-cli); scripts/test.sh runs cargo test before pytest")
    write_sequence(tmp_path / "data" / "s", 3, 32, seed=3, motion=True)
    arch = Arch(encoder=[8, 8, 8, 8, 8], bottleneck=8)
    torch_model = RecurrentAE(arch)
    weights = tmp_path / "tiny.safetensors"
    write_weights(weights, arch, torch_model.state_dict())
    out = tmp_path / "docs" / "REPORT.md"
    args = [str(weights), "--data", f"1spp={tmp_path / 'data'}", "--out", str(out), "--rae-cli", str(cli), "--bench-sizes", "32x32", "--bench-frames", "1"]
    assert main(args) == 0
    text = out.read_text()
    assert "python -m rae_weights report" in text and "logical cores" in text, "names the command and the machine"
    for row in ["| noisy input |", "| rae tiny f32 |", "| rae tiny f16 |", "| rae tiny f32 no motion |", "| PyTorch CPU tiny |", "| OIDN high |", "| OIDN fast |"]:
        assert row in text, row
    # The sequence has motion: rae with and without it, per sequence, beside OIDN.
    per_seq = [l.split("|") for l in text.splitlines() if l.startswith("| s | yes |")]
    assert len(per_seq) == 1 and all(np.isfinite(float(v)) for v in per_seq[0][3:10]), per_seq
    assert "Crops at a disocclusion" in text
    # rae against PyTorch: same weights, so the f32 difference is float noise and f16 stays small.
    rows = {l.split("|")[2].strip(): l for l in text.splitlines() if l.startswith("| tiny |")}
    rel = {p: float(r.split("|")[5]) for p, r in rows.items()}
    assert rel["f32"] < 1e-4 and rel["f16"] < 1e-2, rows
    # Each method row has finite errors; rae's time is a positive number.
    table = [l for l in text.splitlines() if l.startswith("| rae tiny f32 |")][0].split("|")
    assert float(table[2]) > 0 and all(np.isfinite(float(v)) for v in table[3:8])
    for png in ("error-vs-time.png", "crops.png", "crops-disocclusion.png"):
        data = (out.parent / "report" / png).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 5000
    assert "rae-cli bench" in text
    speed = [l for l in text.splitlines() if l.startswith("| 32x32 |")]
    assert len(speed) == 1 and float(speed[0].split("|")[5]) > 0, "rae and PyTorch side by side at the bench size"
    assert not list(out.parent.rglob("*.partial*")), "no partial files left"

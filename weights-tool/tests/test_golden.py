"""The golden generator reproduces the committed fixtures (tests/fixtures) within tolerance."""

from pathlib import Path

from rae_weights import golden

FIXTURES = Path(__file__).resolve().parents[2] / "tests" / "fixtures"


def test_regenerating_reproduces_committed_fixtures(tmp_path: Path) -> None:
    golden.generate(tmp_path)
    problems = golden.compare(FIXTURES, tmp_path)
    assert problems == [], "\n".join(problems)


def test_compare_detects_a_changed_value(tmp_path: Path) -> None:
    import numpy as np
    from safetensors.numpy import load_file, save_file

    golden.generate(tmp_path)
    case = tmp_path / golden.CASES[0].name
    tensors = load_file(str(case))
    tensors["frame2.output"] = tensors["frame2.output"] + np.float32(1e-3)
    save_file(tensors, str(case))
    assert any("frame2.output" in p for p in golden.compare(FIXTURES, tmp_path))

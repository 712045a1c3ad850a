"""Checkpoint export: rae's own and the reference train.py's checkpoints round-trip; a wrong
checkpoint is a clear error naming the tensor."""

from pathlib import Path

import pytest
import torch

from rae_weights import Arch, RecurrentAE
from rae_weights.cli import main
from rae_weights.export import read_weights, write_weights


def _reference_checkpoint(path: Path, prefix: str = "") -> dict[str, torch.Tensor]:
    torch.manual_seed(1)
    model = RecurrentAE(Arch())
    state = {prefix + k: v for k, v in model.state_dict().items()}
    opt = torch.optim.Adam(model.parameters(), lr=1e-4)
    torch.save({"epoch": 3, "state_dict": state, "optimizer": opt.state_dict()}, path)
    return model.state_dict()


@pytest.mark.parametrize("prefix", ["", "module."])
def test_reference_train_py_checkpoint_exports(tmp_path: Path, prefix: str) -> None:
    want = _reference_checkpoint(tmp_path / "ckpt.pt", prefix)
    out = tmp_path / "model.safetensors"
    assert main(["export", str(tmp_path / "ckpt.pt"), str(out)]) == 0
    arch, state = read_weights(out)
    assert arch == Arch(), "8 input channels infer the reference inputs"
    for k, v in want.items():
        assert torch.equal(state[k], v), k


def test_own_checkpoint_keeps_its_architecture(tmp_path: Path) -> None:
    arch = Arch(inputs=["color"], demodulate=False, encoder=[4, 6], bottleneck=6, skip="prepool")
    model = RecurrentAE(arch)
    torch.save({"arch": arch.to_json(), "state_dict": model.state_dict()}, tmp_path / "c.pt")
    out = tmp_path / "w.safetensors"
    assert main(["export", str(tmp_path / "c.pt"), str(out)]) == 0
    assert read_weights(out)[0] == arch


def test_wrong_shape_names_the_tensor(tmp_path: Path) -> None:
    state = RecurrentAE(Arch()).state_dict()
    state["u3.l1.3.weight"] = torch.zeros(43, 43, 5, 5)
    with pytest.raises(ValueError, match="u3.l1.3.weight"):
        write_weights(tmp_path / "x.safetensors", Arch(), state)
    assert not (tmp_path / "x.safetensors").exists(), "no partial output"
    assert list(tmp_path.iterdir()) == [], "no temporary left behind"


def test_cli_reports_bad_checkpoint(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    torch.save({"state_dict": {"foo.weight": torch.zeros(1)}}, tmp_path / "bad.pt")
    assert main(["export", str(tmp_path / "bad.pt"), str(tmp_path / "o.safetensors")]) == 1
    assert "not a recurrent AE" in capsys.readouterr().err

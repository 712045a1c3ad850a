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


def test_interpolate_mixes_two_weights_files_per_module(tmp_path: Path) -> None:
    arch = Arch(encoder=[4, 6], bottleneck=6, skip="prepool")
    files = []
    for seed in (1, 2):
        torch.manual_seed(seed)
        files.append(tmp_path / f"w{seed}.safetensors")
        write_weights(files[-1], arch, RecurrentAE(arch).state_dict())
    out = tmp_path / "mix.safetensors"
    assert main(["interpolate", str(files[0]), str(files[1]), str(out), "--t", "0.25", "--at", "d2,bottleneck=1"]) == 0
    got_arch, got = read_weights(out)
    assert got_arch == arch
    a, b = read_weights(files[0])[1], read_weights(files[1])[1]
    for name, v in got.items():
        want = b[name] if name.split(".")[0] in ("d2", "bottleneck") else 0.75 * a[name].double() + 0.25 * b[name].double()
        assert torch.allclose(v.double(), want.double(), atol=1e-7), name
    assert not torch.equal(got["d1.l1.0.weight"], a["d1.l1.0.weight"])
    # A module the weights do not have, or another architecture, is an error naming it.
    assert main(["interpolate", str(files[0]), str(files[1]), str(out), "--t", "0.5", "--at", "d9=0"]) == 1
    other = tmp_path / "other.safetensors"
    write_weights(other, Arch(encoder=[4, 8], bottleneck=8, skip="prepool"), RecurrentAE(Arch(encoder=[4, 8], bottleneck=8, skip="prepool")).state_dict())
    assert main(["interpolate", str(files[0]), str(other), str(out), "--t", "0.5"]) == 1


def test_drop_inputs_folds_a_constant_buffer_into_the_first_bias(tmp_path: Path) -> None:
    from rae_weights.model import prepare_input

    torch.manual_seed(3)
    arch = Arch(encoder=[4, 6], bottleneck=6, skip="prepool")
    full = RecurrentAE(arch).eval()
    src = tmp_path / "full.safetensors"
    write_weights(src, arch, full.state_dict())
    out = tmp_path / "can.safetensors"
    assert main(["drop-inputs", str(src), str(out), "--fill", "depth=1.5,roughness=0.25"]) == 0
    small_arch, state = read_weights(out)
    assert small_arch.inputs == ["color", "normal"]
    small = RecurrentAE(small_arch).eval()
    small.load_state_dict(state)
    frame = {
        "color": torch.rand(1, 3, 16, 16) * 4,
        "albedo": torch.rand(1, 3, 16, 16),
        "normal": torch.nn.functional.normalize(torch.randn(1, 3, 16, 16), dim=1),
        "depth": torch.full((1, 1, 16, 16), float(torch.expm1(torch.tensor(1.5)))),
        "roughness": torch.full((1, 1, 16, 16), 0.25),
    }
    with torch.no_grad():
        a = full.d1.l1[0](prepare_input(arch, frame))
        b = small.d1.l1[0](prepare_input(small_arch, {k: v for k, v in frame.items() if k not in ("depth", "roughness")}))
    # The first conv is equal but at the border, where the full one read zero padding for depth;
    # the rest of the network is the same tensors.
    assert torch.allclose(a[..., 1:-1, 1:-1], b[..., 1:-1, 1:-1], atol=1e-5)
    assert not torch.allclose(a[..., 0, :], b[..., 0, :], atol=1e-5)
    assert all(torch.equal(state[k], v) for k, v in full.state_dict().items() if not k.startswith("d1.l1.0"))
    color_only = tmp_path / "color.safetensors"
    assert main(["drop-inputs", str(src), str(color_only), "--fill", "normal=0,depth=1.5,roughness=0.25", "--no-demodulate"]) == 0
    color_arch, color_state = read_weights(color_only)
    assert (color_arch.inputs, color_arch.demodulate) == (["color"], False)
    assert color_state["d1.l1.0.weight"].shape[1] == 3
    assert main(["drop-inputs", str(src), str(out), "--fill", "albedo=1"]) == 1

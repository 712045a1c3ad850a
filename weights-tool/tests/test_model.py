"""The PyTorch network: shapes and names of the reference code, recurrence, the input policy."""

import math

import torch

from rae_weights import Arch, RecurrentAE, finish_output, prepare_input


def test_reference_network_has_papers_parameter_count_and_names() -> None:
    model = RecurrentAE(Arch())
    assert sum(p.numel() for p in model.parameters()) == 1_504_301
    names = {n for n, _ in model.named_parameters()}
    assert names == set(Arch().tensor_shapes())
    for n in ["d1.l1.0.weight", "d5.l2.2.bias", "bottleneck.l2.0.weight", "u5.l1.1.weight", "u1.l1.3.bias"]:
        assert n in names
    assert tuple(model.state_dict()["u5.l1.1.weight"].shape) == (76, 202, 3, 3)


def test_forward_shape_and_hidden_state_carries() -> None:
    torch.manual_seed(0)
    model = RecurrentAE(Arch(encoder=[4, 5, 6], bottleneck=7)).eval()
    x = torch.rand(1, 8, 16, 24)
    with torch.no_grad():
        y0 = model(x)
        y1 = model(x)
        model.reset()
        y0_again = model(x)
    assert y0.shape == (1, 3, 16, 24)
    assert not torch.allclose(y0, y1), "the second frame sees the first frame's hidden state"
    assert torch.equal(y0, y0_again), "reset() restores the first frame exactly"


def test_paper_variant_runs_and_is_linear_at_the_output() -> None:
    arch = Arch(inputs=["color", "albedo", "normal"], encoder=[4, 6], bottleneck=8, skip="prepool", output_activation="linear")
    model = RecurrentAE(arch)
    assert isinstance(model.u1.l1[4], torch.nn.Identity)
    y = model(torch.rand(1, 9, 8, 12))
    assert y.shape == (1, 3, 8, 12)


def test_input_policy_makes_everything_finite() -> None:
    arch = Arch(inputs=["color", "albedo", "normal", "depth", "roughness"])
    bad = torch.tensor([math.nan, math.inf, -math.inf, -5.0, 1e30])
    frame = {
        "color": bad.view(1, 1, 1, 5).expand(1, 3, 1, 5),
        "albedo": bad.view(1, 1, 1, 5).expand(1, 3, 1, 5),
        "normal": bad.view(1, 1, 1, 5).expand(1, 3, 1, 5),
        "depth": bad.view(1, 1, 1, 5),
        "roughness": bad.view(1, 1, 1, 5),
    }
    x = prepare_input(arch, frame)
    assert x.shape == (1, 11, 1, 5)
    assert torch.isfinite(x).all()
    out = finish_output(arch, torch.full((1, 3, 1, 5), 1e6), frame)
    assert torch.isfinite(out).all() and (out >= 0).all()


def test_transfer_functions_invert_and_bound() -> None:
    from rae_weights import transfer

    x = torch.tensor([0.0, 1e-4, 0.01, 0.5, 1.0, 7.0, 300.0, 1e5], dtype=torch.float64)
    for name in transfer.TRANSFERS:
        y = transfer.encode(name, x)
        assert torch.all(y[1:] > y[:-1]), f"{name} is increasing"
        assert y[0].abs() < 1e-9, f"{name} maps black to 0"
        back = transfer.decode(name, y)
        assert torch.allclose(back, x, rtol=1e-6, atol=1e-9), (name, back)
        lim = transfer.limit(name, y, 2.0, 1e8, 80.0)
        assert torch.allclose(transfer.decode(name, lim), 2 * x, rtol=1e-6, atol=1e-9), name
    assert abs(float(transfer.encode("pu21", torch.tensor(1.0, dtype=torch.float64))) - 1.0) < 1e-12


def test_a_depth_miss_is_the_same_whatever_the_renderer_writes() -> None:
    # rae-trace writes +inf at a miss, Blender's Denoising Depth 0; NaN and negative values
    # are misses too. Prep maps every one to DEPTH_MAX, and hits keep their depth.
    from rae_weights.model import DEPTH_MAX

    arch = Arch(inputs=["color", "albedo", "depth"])
    depth = torch.tensor([math.inf, 0.0, math.nan, -1.0, 1e9, 3.0, 1e-3]).view(1, 1, 1, 7)
    x = prepare_input(arch, {"color": torch.ones(1, 3, 1, 7), "albedo": torch.ones(1, 3, 1, 7), "depth": depth})
    d = x[0, 6, 0]
    miss = math.log1p(DEPTH_MAX)
    assert torch.allclose(d[:5], torch.full((5,), miss)), d
    assert torch.allclose(d[5:], torch.log1p(torch.tensor([3.0, 1e-3]))), d


def test_a_miss_is_demodulated_by_one_and_passed_through() -> None:
    # Pixels 0-2 are misses told by depth (+inf, 0) or by a zero normal, each with another
    # renderer's albedo there (0, the sky's colour, 0); pixel 3 is a hit with albedo 0.5.
    from rae_weights.model import is_miss, sanitize_buffers

    arch = Arch(inputs=["color", "albedo", "normal", "depth"])
    color = torch.tensor([2.0, 0.7, 5.0, 1.0]).view(1, 1, 1, 4).expand(1, 3, 1, 4)
    albedo = torch.tensor([0.0, 0.7, 0.0, 0.5]).view(1, 1, 1, 4).expand(1, 3, 1, 4)
    normal = torch.tensor([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 1.0], [0.0, 0.0, 0.0, 0.0]]).view(1, 3, 1, 4)
    depth = torch.tensor([math.inf, 0.0, 4.0, 3.0]).view(1, 1, 1, 4)
    frame = {"color": color, "albedo": albedo, "normal": normal, "depth": depth}
    miss = is_miss(arch, sanitize_buffers(frame))
    assert miss is not None and miss[0, 0, 0].tolist() == [True, True, True, False]
    x = prepare_input(arch, frame)
    eps = arch.albedo_eps
    want_color = torch.log1p(torch.tensor([2.0 / (1 + eps), 0.7 / (1 + eps), 5.0 / (1 + eps), 1.0 / (0.5 + eps)]))
    assert torch.allclose(x[0, 0, 0], want_color), x[0, 0, 0]
    assert torch.equal(x[0, 3, 0], torch.tensor([1.0, 1.0, 1.0, 0.5])), "the albedo channel is 1 at misses"
    out = finish_output(arch, torch.full((1, 3, 1, 4), 0.3), frame)
    assert torch.equal(out[0, :, 0, :3], color[0, :, 0, :3]), "misses keep the input color"
    assert torch.allclose(out[0, :, 0, 3], torch.full((3,), math.expm1(0.3) * (0.5 + eps))), "hits are remodulated"
    # A model that reads neither depth nor normal has no misses: albedo 0 stays 0.
    plain = Arch(inputs=["color", "albedo"])
    assert is_miss(plain, sanitize_buffers(frame)) is None
    assert prepare_input(plain, frame)[0, 3, 0, 0] == 0.0

"""Training pieces: the loss, the target space the runtime inverts, data loading, two steps."""

from pathlib import Path

import numpy as np
import pytest
import torch

from rae_weights import Arch, finish_output
from sequences import write_sequence
from rae_weights.train import PAPER_FRAME_WEIGHTS, log_kernel, loss_fn, main, target_space


def test_loss_is_zero_for_a_perfect_result_and_sees_temporal_error() -> None:
    torch.manual_seed(0)
    ts = [torch.rand(1, 3, 16, 16) for _ in range(7)]
    log = log_kernel()
    assert loss_fn(ts, ts, PAPER_FRAME_WEIGHTS, log).item() == 0.0
    # Same per-frame error, but flickering vs constant: the temporal term tells them apart.
    steady = [t + 0.1 for t in ts]
    flicker = [t + (0.1 if i % 2 else -0.1) for i, t in enumerate(ts)]
    assert loss_fn(flicker, ts, PAPER_FRAME_WEIGHTS, log) > loss_fn(steady, ts, PAPER_FRAME_WEIGHTS, log)
    assert log_kernel().sum().abs().item() < 1e-6, "LoG is zero-sum: flat images have no gradient loss"
    # The term weights: temporal-only sees no error in the steady result, and weighing temporal
    # more widens the gap between flicker and steady.
    assert loss_fn(steady, ts, PAPER_FRAME_WEIGHTS, log, (0.0, 0.0, 1.0)).item() < 1e-6
    gap = lambda terms: (loss_fn(flicker, ts, PAPER_FRAME_WEIGHTS, log, terms) - loss_fn(steady, ts, PAPER_FRAME_WEIGHTS, log, terms)).item()  # noqa: E731
    assert gap((0.8, 0.1, 0.4)) > gap((0.8, 0.1, 0.1)) > 0


def test_target_space_is_inverted_by_the_output_stage() -> None:
    arch = Arch()
    ref = torch.rand(1, 3, 8, 8) * 20
    albedo = torch.rand(1, 3, 8, 8)
    y = target_space(arch, {"reference": ref, "albedo": albedo})
    # The input frame bounds the output (2x its brightest demodulated value): use the reference.
    back = finish_output(arch, y, {"albedo": albedo, "color": ref})
    assert torch.allclose(back, ref, rtol=1e-4, atol=1e-5)
    # A black input frame bounds everything to black, whatever the network says.
    black = finish_output(arch, y, {"albedo": albedo, "color": torch.zeros_like(ref)})
    assert black.abs().max().item() == 0.0


def test_two_training_steps_write_checkpoint_log_and_weights(tmp_path: Path) -> None:
    write_sequence(tmp_path / "data" / "a", 8, 32)
    out = tmp_path / "run"
    args = ["--data", str(tmp_path / "data"), "--val", str(tmp_path / "data"), "--out", str(out), "--steps", "2", "--crop", "32", "--val-every", "2", "--threads", "1"]
    assert main(args) == 0
    assert (out / "model.safetensors").exists() and (out / "checkpoint.pt").exists()
    rows = (out / "log.csv").read_text().strip().splitlines()
    assert rows[0].startswith("step,") and rows[-1].startswith("2,")
    # Resuming at the last step runs nothing more and exports again.
    assert main(args) == 0


def test_a_pooled_checkpoint_warm_starts_a_prepool_network_whole(tmp_path: Path) -> None:
    # The two skip variants have the same tensors: a run with --skip prepool starts from every
    # weight of a pooled one and exports a file whose architecture says prepool.
    from rae_weights.export import read_weights

    write_sequence(tmp_path / "data" / "a", 8, 32)
    common = ["--data", str(tmp_path / "data"), "--steps", "1", "--crop", "32", "--threads", "1", "--lr", "0"]
    assert main([*common, "--out", str(tmp_path / "pooled")]) == 0
    assert main([*common, "--out", str(tmp_path / "prepool"), "--skip", "prepool", "--init", str(tmp_path / "pooled" / "checkpoint.pt")]) == 0
    (a, pooled), (b, prepool) = (read_weights(tmp_path / run / "model.safetensors") for run in ("pooled", "prepool"))
    assert (a.skip, b.skip) == ("pooled", "prepool")
    assert pooled.keys() == prepool.keys() and all(torch.equal(pooled[k], prepool[k]) for k in pooled), "lr 0: the warm start is the whole network"


def test_a_round_from_weights_keeps_their_inputs_unless_told_otherwise(tmp_path: Path) -> None:
    # gpu-train.sh continues whatever model ships: without --inputs, a run takes the --init
    # weights' inputs (albedo included) instead of dropping the buffers the default lacks.
    from rae_weights.export import read_weights

    write_sequence(tmp_path / "data" / "a", 8, 32)
    common = ["--data", str(tmp_path / "data"), "--steps", "1", "--crop", "32", "--threads", "1", "--lr", "0"]
    five = "color,albedo,normal,depth,roughness"
    assert main([*common, "--out", str(tmp_path / "a"), "--inputs", five]) == 0
    init = str(tmp_path / "a" / "model.safetensors")
    assert main([*common, "--out", str(tmp_path / "b"), "--init", init]) == 0
    assert main([*common, "--out", str(tmp_path / "c"), "--init", init, "--inputs", "color,normal"]) == 0
    assert main([*common, "--out", str(tmp_path / "d")]) == 0
    (a, wa), (b, wb), (c, _), (d, _) = (read_weights(tmp_path / r / "model.safetensors") for r in "abcd")
    assert a.inputs == b.inputs == five.split(",")
    assert all(torch.equal(wa[k], wb[k]) for k in wa), "lr 0: the same network"
    assert c.inputs == ["color", "normal"]
    assert d.inputs == Arch().inputs


def test_warm_start_copies_shared_tensors_and_input_columns_by_buffer() -> None:
    from rae_weights import RecurrentAE
    from rae_weights.train import warm_start

    torch.manual_seed(0)
    src_arch = Arch()  # color, normal, depth, roughness
    src = RecurrentAE(src_arch).state_dict()
    arch = Arch(inputs=["color", "albedo", "normal"])
    model = RecurrentAE(arch)
    n = warm_start(model, arch, src, src_arch)
    got = model.state_dict()
    assert n == len(got), "every tensor has a source: equal shapes, or the first conv by columns"
    w, s = got["d1.l1.0.weight"], src["d1.l1.0.weight"]
    assert torch.equal(w[:, 0:3], s[:, 0:3]), "color columns"
    assert torch.equal(w[:, 6:9], s[:, 3:6]), "normal columns"
    assert torch.equal(w[:, 3:6], torch.zeros_like(w[:, 3:6])), "albedo has no source column: zero"
    assert torch.equal(got["u1.l1.3.weight"], src["u1.l1.3.weight"])


def test_a_buffer_added_by_warm_start_leaves_the_networks_output_as_the_sources() -> None:
    # rae-default with albedo as an input as well starts as rae-default: the new columns are zero,
    # so the first frames' outputs are the source network's whatever the albedo holds.
    from rae_weights import RecurrentAE
    from rae_weights.train import warm_start

    torch.manual_seed(1)
    src_arch = Arch(encoder=[8, 12, 16], bottleneck=20)
    src = RecurrentAE(src_arch)
    arch = Arch(inputs=["color", "albedo", "normal", "depth", "roughness"], encoder=[8, 12, 16], bottleneck=20)
    model = RecurrentAE(arch)
    warm_start(model, arch, src.state_dict(), src_arch)
    x = torch.rand(2, 8, 32, 32)
    albedo = torch.rand(2, 3, 32, 32)
    with torch.no_grad():
        a = src(x[:, :8])
        b = model(torch.cat([x[:, :3], albedo, x[:, 3:]], dim=1))
    assert torch.allclose(a, b, atol=1e-6)


def test_metrics_match_their_definitions() -> None:
    from rae_weights import metrics

    rng = np.random.default_rng(0)
    r = rng.random((24, 17, 3)).astype(np.float32)
    assert metrics.relmse(r, r) == 0 and metrics.psnr(r, r) == float("inf")
    assert abs(metrics.ssim(r, r) - 1) < 1e-12
    noisy = r + (rng.random(r.shape) < 0.1) * 0.5
    assert metrics.ssim(noisy, r) < 0.99 and metrics.psnr(noisy, r) < 40
    x = np.full((1, 1, 3), 3.0, dtype=np.float32)
    assert abs(metrics.relmse(x, np.zeros_like(x)) - 900.0) < 1e-9, "(3-0)^2 / (0 + 0.01)"
    assert metrics.temporal_error(r, noisy, r, noisy) == 0, "the same change as the reference"


def test_flips_and_turns_turn_the_motion_with_the_image() -> None:
    # Warping a transformed previous frame with the transformed motion is the transformed warp,
    # for motion along x and along y, every flip and quarter turn.
    from rae_weights import warp
    from rae_weights.data import transform

    img = (torch.arange(6).view(6, 1) * 10 + torch.arange(6).view(1, 6)).double().view(1, 1, 6, 6)
    for vec in ((1.0, 0.0), (0.0, -2.0), (1.0, 1.0)):
        m = torch.zeros(1, 2, 6, 6, dtype=torch.float64)
        m[:, 0], m[:, 1] = vec
        warped = warp.warp(img, *warp.pyramid(m, 0)[0])
        for k in range(4):
            for flip in (False, True):
                got = warp.warp(transform("color", img, k, flip), *warp.pyramid(transform("motion", m, k, flip), 0)[0])
                assert torch.equal(got, transform("color", warped, k, flip)), (vec, k, flip)


def test_training_with_motion_reprojects_and_warps_the_temporal_term(tmp_path: Path) -> None:
    # A sequence with motion_NNNN.exr: the clip carries it, the temporal term warps the previous
    # frame with it (a result that follows the motion has no temporal loss), and two steps run.
    from rae_weights import warp
    from rae_weights.data import load_sequences

    write_sequence(tmp_path / "data" / "m", 8, 32, motion=True)
    (seq,) = load_sequences(tmp_path / "data")
    assert seq.buffers["motion"].shape == (8, 2, 32, 32)
    # Result and reference both move with the motion (each frame the previous one warped):
    # along the motion neither changes, so the warped temporal term is zero; at fixed pixels
    # both change, differently.
    torch.manual_seed(0)
    m = torch.zeros(1, 2, 16, 16)
    m[:, 0] = 1.0
    ys, ts = [torch.rand(1, 3, 16, 16)], [torch.rand(1, 3, 16, 16)]
    for _ in range(6):
        ys.append(warp.warp(ys[-1], *warp.pyramid(m, 0)[0]))
        ts.append(warp.warp(ts[-1], *warp.pyramid(m, 0)[0]))
    log = log_kernel()
    temporal = (0.0, 0.0, 1.0)
    assert loss_fn(ys, ts, PAPER_FRAME_WEIGHTS, log, temporal, [m] * 7).item() < 1e-6
    assert loss_fn(ys, ts, PAPER_FRAME_WEIGHTS, log, temporal).item() > 0.01
    out = tmp_path / "run"
    args = ["--data", str(tmp_path / "data"), "--val", str(tmp_path / "data"), "--out", str(out), "--steps", "2", "--crop", "32", "--val-every", "2", "--threads", "1"]
    assert main(args) == 0


def test_a_batch_of_clips_runs_each_clip_as_it_runs_alone(tmp_path: Path) -> None:
    # run_clip on a batch [T, N, ...] gives each clip the outputs it gets alone (hidden state,
    # warp and misses per clip), and a batched training run warm-starts from a shipped weights
    # file (.safetensors) and exports.
    from rae_weights.data import load_sequences, sample
    from rae_weights.model import RecurrentAE
    from rae_weights.train import batch, run_clip

    write_sequence(tmp_path / "data" / "a", 8, 32, motion=True)
    write_sequence(tmp_path / "data" / "b", 8, 32, motion=True)
    seqs = load_sequences(tmp_path / "data")
    rng = np.random.default_rng(3)
    clips = [sample(seqs, 4, 32, rng, vary=True) for _ in range(3)]
    arch = Arch(skip="prepool")
    torch.manual_seed(0)
    model = RecurrentAE(arch).eval()
    with torch.no_grad():
        together = run_clip(model, arch, batch(clips, torch.device("cpu")))
        for n, clip in enumerate(clips):
            alone = run_clip(model, arch, batch([clip], torch.device("cpu")))
            for y, ys in zip(alone, together):
                assert torch.allclose(y[0], ys[n], atol=1e-5), "a clip's output depends on the others in its batch"
    out = tmp_path / "run"
    assert main(["--data", str(tmp_path / "data"), "--out", str(out), "--steps", "2", "--crop", "32", "--threads", "1", "--batch", "3", "--skip", "prepool"]) == 0
    init = out / "model.safetensors"
    assert main(["--data", str(tmp_path / "data"), "--out", str(tmp_path / "again"), "--steps", "1", "--crop", "32", "--threads", "1", "--batch", "2", "--skip", "prepool", "--init", str(init), "--lr", "0"]) == 0
    from rae_weights.export import read_weights

    (_, a), (_, b) = read_weights(init), read_weights(tmp_path / "again" / "model.safetensors")
    assert all(torch.equal(a[k], b[k]) for k in a), "lr 0: the warm start from a weights file is the whole network"


def test_reload_adds_the_sequences_a_renderer_finished_since(tmp_path: Path) -> None:
    # Training can start while a renderer writes: reload adds folders that appeared (not hidden
    # ones still being written, not those already loaded).
    from rae_weights.data import load_sequences
    from rae_weights.train import reload

    root = tmp_path / "data"
    write_sequence(root / "a", 8, 16)
    have = load_sequences(root)
    write_sequence(root / "b", 8, 16)
    write_sequence(root / ".c.partial", 8, 16)
    now = reload([root], have, torch.device("cpu"))
    assert [s.name for s in now] == ["a", "b"]
    assert now[0] is have[0], "a loaded sequence is kept, not read again"
    assert [s.name for s in reload([root], now, torch.device("cpu"))] == ["a", "b"]


def test_reload_takes_up_a_folder_a_renderer_has_not_written_to_yet(tmp_path: Path) -> None:
    # Training starts on the folders that have sequences; one still empty (or not yet made) is
    # read at a later reload instead of stopping the run.
    from rae_weights.data import load_sequences
    from rae_weights.train import reload

    first, later = tmp_path / "first", tmp_path / "later"
    write_sequence(first / "a", 8, 32)
    write_sequence(later / ".b.partial", 8, 16)
    have = reload([first, later, tmp_path / "missing"], load_sequences(first), torch.device("cpu"))
    assert [s.name for s in have] == ["a"]
    write_sequence(later / "b", 8, 16)
    assert [s.name for s in reload([first, later], have, torch.device("cpu"))] == ["a", "b"]
    out = tmp_path / "run"
    base = ["--val", str(first), "--out", str(out), "--steps", "1", "--crop", "32", "--frames", "4", "--threads", "1"]
    assert main(["--data", str(first), str(tmp_path / "missing"), "--reload-every", "60", *base]) == 0
    with pytest.raises(ValueError, match="no sequences"):
        main(["--data", str(first), str(tmp_path / "empty-too"), *base, "--out", str(tmp_path / "run2")])


def test_the_accumulated_loss_sees_the_output_rae_core_delivers(tmp_path: Path) -> None:
    # accumulated() is the engine's path for a sequence with motion (finish_output, then
    # accumulate.accumulate along the motion) back in the network's output space: decoded, it
    # equals that path; its first frame is the network's own; it differs where history blends in;
    # gradients reach the network through it; a run with --accumulated-loss trains and exports.
    from rae_weights import accumulate
    from rae_weights.data import load_sequences, sample
    from rae_weights.model import RecurrentAE
    from rae_weights.train import accumulated, batch, clip_frame, run_clip

    write_sequence(tmp_path / "data" / "m", 8, 32, motion=True)
    (seq,) = load_sequences(tmp_path / "data")
    clip = batch([sample([seq], 4, 32, np.random.default_rng(1), vary=True)], torch.device("cpu"))
    arch = Arch(skip="prepool")
    torch.manual_seed(0)
    model = RecurrentAE(arch)
    ys = run_clip(model, arch, clip)
    acc = accumulated(arch, ys, clip)
    frames = [clip_frame(clip, i) for i in range(4)]
    previous = None
    for i, (y, a) in enumerate(zip(ys, acc)):
        previous = accumulate.accumulate(finish_output(arch, y, frames[i]), previous, clip["motion"][i])
        assert torch.allclose(finish_output(arch, a, frames[i]), previous, rtol=1e-4, atol=1e-5), i
    assert torch.allclose(acc[0], ys[0].clamp(min=0.0), atol=1e-5)
    assert (acc[3] - ys[3]).abs().max().item() > 1e-3, "history blended into later frames"
    acc[3].sum().backward()
    assert any(p.grad is not None and p.grad.abs().sum() > 0 for p in model.parameters())
    assert accumulated(arch, ys, {k: v for k, v in clip.items() if k != "motion"}) is ys
    common = ["--data", str(tmp_path / "data"), "--steps", "2", "--crop", "32", "--threads", "1", "--skip", "prepool"]
    assert main([*common, "--out", str(tmp_path / "run"), "--accumulated-loss", "0.5"]) == 0
    assert (tmp_path / "run" / "model.safetensors").exists()
    with pytest.raises(SystemExit):
        main([*common, "--out", str(tmp_path / "bad"), "--accumulated-loss", "1.5"])

"""Error against run time: rae beside its peers on the same held-out frames, written to docs/REPORT.md.

    python -m rae_weights report ../models/*.safetensors --data 1spp=DATA/val 4spp=DATA/val4 \\
        --out ../docs/REPORT.md --peak-gflops 156

One run, side by side on the same frames: the noisy input; rae (``rae-cli denoise`` on the adapter
wgpu picks) in each precision and with each model; PyTorch on the CPU with the same weights; Intel
Open Image Denoise (pyoidn, color+albedo+normal, HDR) at quality high and fast. For each: median
time per frame (host to host: upload, GPU and download for rae; the whole call for PyTorch and
OIDN; first frame of each sequence left out, it holds shader compilation and warm-up), relMSE,
PSNR, SSIM, FLIP (HDR-FLIP of flip-evaluator) and temporal error (rae-core's metrics, mirrored
in ``metrics``). Also rae's error against PyTorch per model and precision, ``rae-cli bench``
(sizes, precisions, per-stage GPU times), a PNG plot of error against time and a sheet of crops.
Figures go beside the report (``report/`` next to it); every file is written atomically.
"""

from __future__ import annotations

import argparse
import csv
import importlib.metadata
import os
import platform
import shlex
import statistics
import subprocess
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch
import torch.nn.functional as F

from . import warp
from .data import Sequence, load_sequences, read_exr
from .evaluate import hwc, labelled_folders, run_oidn, run_rae
from .export import read_weights
from .metrics import sequence_metrics, tonemap
from .model import RecurrentAE, sanitize_buffers

REPO = Path(__file__).resolve().parents[2]


@dataclass
class Method:
    """One row of the report: a way of getting a clean frame, its outputs and its times."""

    name: str
    kind: str  # "input", "rae", "pytorch", "oidn"
    outputs: dict[str, dict[str, list[np.ndarray]]] = field(default_factory=dict)  # set -> seq -> frames
    times_ms: list[float] = field(default_factory=list)
    metrics: dict[str, dict[str, float]] = field(default_factory=dict)  # set -> metric -> mean
    per_seq: dict[str, dict[str, dict[str, float]]] = field(default_factory=dict)  # set -> seq -> metric

    def add(self, label: str, seq: str, frames: list[np.ndarray]) -> None:
        self.outputs.setdefault(label, {})[seq] = frames

    @property
    def ms(self) -> float:
        return statistics.median(self.times_ms) if self.times_ms else float("nan")


def find_rae_cli() -> Path | None:
    """The workspace's rae-cli binary, if built: the newer of release and debug."""
    built = [p for p in (REPO / "target" / prof / "rae-cli" for prof in ("release", "debug")) if p.exists()]
    return max(built, key=lambda p: p.stat().st_mtime) if built else None


def machine() -> str:
    """CPU model, cores and memory of this machine, one line."""
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
        mem = next(int(l.split()[1]) for l in Path("/proc/meminfo").read_text().splitlines() if l.startswith("MemTotal"))
        memory = f", {mem / 2**20:.0f} GiB"
    except (OSError, StopIteration):
        memory = ""
    return f"{cpu}, {os.cpu_count()} logical cores{memory}, {platform.system()} {platform.release()}"


def run_rae_cli(
    cli: Path,
    weights: Path,
    precision: str,
    folder: Path,
    frames: int,
    times: list[float],
    log: list[str],
    motion: bool = True,
    accumulate: bool = True,
) -> list[np.ndarray]:
    """rae-cli denoise of one sequence folder (``--no-motion`` unless `motion`,
    ``--no-accumulate`` unless `accumulate`); the denoised frames and per-frame times (all but
    the first, which compiles the shaders)."""
    with tempfile.TemporaryDirectory() as tmp:
        out, table = Path(tmp) / "out", Path(tmp) / "times.csv"
        cmd = [str(cli), "denoise", str(folder), "-o", str(out), "--weights", str(weights), "--precision", precision, "--csv", str(table)]
        if not motion:
            cmd.append("--no-motion")
        if not accumulate:
            cmd.append("--no-accumulate")
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0:
            raise RuntimeError(f"{shlex.join(cmd)} failed ({r.returncode}):\n{r.stdout}\n{r.stderr}")
        device = next((l.split(":", 1)[1].strip() for l in r.stdout.splitlines() if l.startswith("device:")), "?")
        if device not in log:
            log.append(device)
        with table.open() as f:
            rows = list(csv.DictReader(f))
        times.extend(float(x["upload_ms"]) + float(x["gpu_ms"]) + float(x["download_ms"]) for x in rows[1:])
        files = sorted(out.glob("denoised_*.exr"))
        if len(files) != frames:
            raise RuntimeError(f"{folder}: rae-cli wrote {len(files)} frames, expected {frames}")
        return [read_exr(p) for p in files]


def flip_mean(outs: list[np.ndarray], refs: list[np.ndarray]) -> float:
    """Mean HDR-FLIP over frames (flip-evaluator, default 67 pixels per degree)."""
    import flip_evaluator

    vals = []
    for o, r in zip(outs, refs):
        clean = lambda a: np.ascontiguousarray(np.maximum(np.nan_to_num(a, posinf=0.0), 0.0), dtype=np.float32)  # noqa: E731
        vals.append(float(flip_evaluator.evaluate(clean(r), clean(o), "HDR", applyMagma=False)[1]))
    return float(np.mean(vals))


def score(methods: list[Method], refs: dict[str, dict[str, list[np.ndarray]]]) -> None:
    """Fill each method's metrics: per sequence, then the mean over each set's sequences."""
    for m in methods:
        for label, seqs in m.outputs.items():
            per_seq = []
            for name, outs in seqs.items():
                s = sequence_metrics(outs, refs[label][name])
                s["flip"] = flip_mean(outs, refs[label][name])
                per_seq.append(s)
                m.per_seq.setdefault(label, {})[name] = s
            m.metrics[label] = {k: float(np.mean([s[k] for s in per_seq])) for k in per_seq[0]}


def abs_error(a: Method, b: Method) -> tuple[float, float, float]:
    """(max |a - b|, mean |a - b|, max |a - b| over the frame's max |b|) over all frames of all sets."""
    mx, total, n, rel = 0.0, 0.0, 0, 0.0
    for label, seqs in a.outputs.items():
        for name, outs in seqs.items():
            for x, y in zip(outs, b.outputs[label][name]):
                d = np.abs(x.astype(np.float64) - y)
                mx, total, n = max(mx, float(d.max())), total + float(d.sum()), n + d.size
                rel = max(rel, float(d.max()) / max(float(np.abs(y).max()), 1e-12))
    return mx, total / max(n, 1), rel


def atomic_save(path: Path, write) -> None:  # type: ignore[no-untyped-def]
    """Call write(tmp) and rename tmp onto path; no partial file on failure."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.partial{path.suffix}")
    try:
        write(tmp)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def plot(methods: list[Method], labels: list[str], path: Path, caption: str) -> None:
    """Error (relMSE and FLIP) against time per frame, one column per held-out set."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    import textwrap

    fig, axes = plt.subplots(2, len(labels), figsize=(6.5 * len(labels), 9), squeeze=False)
    markers = {"input": "x", "rae": "o", "pytorch": "s", "oidn": "^"}
    colors = plt.get_cmap("tab20")
    for col, label in enumerate(labels):
        for row, key in enumerate(("relmse", "flip")):
            ax = axes[row][col]
            for i, m in enumerate(methods):
                t = m.ms if m.kind != "input" else 0.1
                ax.scatter(t, m.metrics[label][key], marker=markers[m.kind], s=45, color=colors(i % 20), label=m.name if (row, col) == (0, 0) else None)
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel("time per frame, ms (the noisy input placed at 0.1)")
            ax.set_ylabel("relMSE" if key == "relmse" else "mean HDR-FLIP")
            ax.set_title(f"held-out {label}: {'relMSE' if key == 'relmse' else 'FLIP'} against time")
            ax.grid(True, which="both", alpha=0.3)
    fig.legend(loc="lower center", ncol=3, fontsize=8, frameon=False)
    fig.suptitle(textwrap.fill(caption, int(20 * 6.5 * len(labels))), fontsize=6)
    fig.tight_layout(rect=(0, 0.12, 1, 0.93))
    atomic_save(path, lambda p: fig.savefig(p, dpi=110, format="png"))
    plt.close(fig)


def disocclusion(seq: Sequence, frame: int) -> np.ndarray:
    """HW: 1 - the history test of `frame` of a sequence with motion (``warp.history`` on its
    normal and log1p depth, as a model that reads both prepares them): 1 where the previous frame
    did not see the surface. Pixels whose history lies off screen count 0 (the warp zeroes them
    whatever the test says; they are not a disocclusion). Each pixel keeps the smallest value of
    its 3x3 neighbourhood: a disocclusion is a region, while a renderer's speckled buffers (at
    1 spp over glass) fail the test pixel by pixel."""
    def guide(i: int) -> torch.Tensor:
        b = sanitize_buffers({k: seq.buffers[k][i : i + 1] for k in ("normal", "depth")})
        return torch.cat([b["normal"], torch.log1p(b["depth"])], 1)

    m, ok = warp.sanitize_motion(seq.buffers["motion"][frame : frame + 1])
    h, w = m.shape[-2:]
    sx = torch.arange(w, dtype=m.dtype).view(1, 1, w) + m[:, 0]
    sy = torch.arange(h, dtype=m.dtype).view(1, h, 1) + m[:, 1]
    on_screen = ((sx >= 0) & (sx <= w - 1) & (sy >= 0) & (sy <= h - 1)).to(m.dtype).unsqueeze(1)
    failed = on_screen * (1.0 - ok * warp.history(guide(frame), guide(frame - 1), m))
    return (-F.max_pool2d(-failed, 3, 1, 1))[0, 0].numpy()


def window(v: np.ndarray, c: int, avoid: list[tuple[int, int]] = []) -> tuple[int, int]:  # noqa: B006
    """(y, x) of the c x c window of `v` with the largest sum, not overlapping the windows at
    `avoid` where the frame leaves room (window sums from an integral image)."""
    s = np.pad(v.cumsum(0).cumsum(1), ((1, 0), (1, 0)))
    win = s[c:, c:] - s[:-c, c:] - s[c:, :-c] + s[:-c, :-c]
    for ay, ax in avoid:
        masked = win.copy()
        masked[max(0, ay - c + 1) : ay + c, max(0, ax - c + 1) : ax + c] = -np.inf
        if np.isfinite(masked).any():
            win = masked
    y, x = np.unravel_index(int(np.argmax(win)), win.shape)
    return int(y), int(x)


def crop_sheet(
    columns: list[tuple[str, np.ndarray]],
    ref: np.ndarray,
    path: Path,
    caption: str,
    size: int = 48,
    spots: list[tuple[str, np.ndarray]] | None = None,
) -> None:
    """Crops of one frame: where the first method after the input (column 1) errs most and where
    the reference has most detail, or at the maxima of the given `spots` maps (name, HW map);
    columns are the given methods and the reference, tonemapped as the metrics are."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    h, w, _ = ref.shape
    c = min(size, h, w)
    t_ref = tonemap(ref)

    if spots is None:
        err = np.abs(tonemap(columns[1][1]) - t_ref).mean(-1)
        detail = np.abs(np.diff(t_ref, axis=0, prepend=t_ref[:1])).mean(-1) + np.abs(np.diff(t_ref, axis=1, prepend=t_ref[:, :1])).mean(-1)
        spots = [("largest rae error", err), ("most detail elsewhere", detail)]
    at: list[tuple[str, tuple[int, int]]] = []
    for why, v in spots:
        at.append((why, window(v, c, [p for _, p in at])))
    cols = columns + [("reference", ref)]
    fig, axes = plt.subplots(len(at), len(cols), figsize=(2.2 * len(cols), 2.4 * len(at) + 0.5), squeeze=False)
    for r, (why, (y, x)) in enumerate(at):
        for k, (name, img) in enumerate(cols):
            ax = axes[r][k]
            ax.imshow(tonemap(img[y : y + c, x : x + c]), interpolation="nearest")
            ax.set_xticks([])
            ax.set_yticks([])
            if r == 0:
                ax.set_title(name, fontsize=8)
            if k == 0:
                ax.set_ylabel(f"{why}\n({x},{y}) {c}x{c}", fontsize=7)
    import textwrap

    fig.suptitle(textwrap.fill(caption, 110), fontsize=6)
    fig.tight_layout(rect=(0, 0, 1, 0.88))
    atomic_save(path, lambda p: fig.savefig(p, dpi=110, format="png"))
    plt.close(fig)


def bench_text(cli: Path, weights: Path, sizes: str, frames: int, peak: float | None) -> tuple[str, str]:
    """(command, output) of rae-cli bench with per-stage times."""
    cmd = [str(cli), "bench", str(weights), "--sizes", sizes, "--frames", str(frames), "--precision", "f32,f16", "--layers"]
    if peak:
        cmd += ["--peak-gflops", str(peak)]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"{shlex.join(cmd)} failed ({r.returncode}):\n{r.stdout}\n{r.stderr}")
    return shlex.join(cmd), r.stdout


def bench_rows(text: str) -> dict[tuple[str, str], tuple[float, float]]:
    """(size, precision) -> (total ms, GFLOP/s) from rae-cli bench's summary rows (by header)."""
    rows = {}
    col: dict[str, int] = {}
    for line in text.splitlines():
        f = line.split()
        if f[:2] == ["size", "precision"]:
            # Header names, "total ms" as one column.
            col = {name: i for i, name in enumerate(line.replace("total ms", "total").replace("peak MiB", "peak_mib").replace("alloc MiB", "alloc_mib").replace("of peak", "of_peak").split())}
        elif col and len(f) == len(col) and "x" in f[0] and f[1] in ("f32", "f16"):
            rows[(f[0], f[1])] = (float(f[col["total"]]), float(f[col["GFLOP/s"]]))
    return rows


def pytorch_at_sizes(weights: Path, sizes: list[str], frames: int) -> dict[str, float]:
    """Median ms per frame of the PyTorch peer at each bench size (``bench.time_frames``)."""
    from .bench import time_frames

    arch, state = read_weights(weights)
    model = RecurrentAE(arch)
    model.load_state_dict(state)
    model = model.eval().to(memory_format=torch.channels_last)
    out = {}
    for s in sizes:
        w, h = (int(v) for v in s.lower().split("x"))
        m = 1 << arch.levels
        out[s] = statistics.median(time_frames(model, -(-w // m) * m, -(-h // m) * m, frames)) * 1e3
    return out


def rel(p: Path, to: Path) -> str:
    """p relative to `to` where it lies below it (for links and commands), else as is."""
    try:
        return os.path.relpath(p, to)
    except ValueError:
        return str(p)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="rae-weights report", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("models", nargs="+", type=Path, help="rae weights files; the first is the one the crops, PyTorch row and bench show first")
    p.add_argument("--data", nargs="+", required=True, metavar="LABEL=FOLDER", help="held-out sets, e.g. 1spp=data/val")
    p.add_argument("--out", type=Path, default=REPO / "docs" / "REPORT.md")
    p.add_argument("--rae-cli", type=Path, default=None, help="rae-cli binary (default: target/release or target/debug of this workspace)")
    p.add_argument("--precisions", default="f32,f16")
    p.add_argument("--bench-sizes", default="256x256,512x512,1280x720", help="rae-cli bench sizes; empty to skip the bench")
    p.add_argument("--bench-frames", type=int, default=10)
    p.add_argument("--peak-gflops", type=float, help="the adapter's fp32 peak, for the bench's share of peak")
    p.add_argument("--threads", type=int, default=min(2, os.cpu_count() or 1), help="CPU threads of PyTorch")
    a = p.parse_args(argv)
    command = "python -m rae_weights report " + shlex.join(sys.argv[2:] if argv is None else argv)
    cli = a.rae_cli or find_rae_cli()
    if cli is None or not cli.exists():
        p.error("no rae-cli binary: build it (cargo build --release -p rae-cli) or pass --rae-cli")
    for m in a.models:
        if not m.exists():
            p.error(f"{m}: no such weights file")
    sets = labelled_folders(p, "--data", a.data)
    torch.set_num_threads(a.threads)
    precisions = [x for x in a.precisions.split(",") if x]

    # Every method on every sequence of every set; where sequences carry motion, rae also
    # without it (`--no-motion`, first precision) for comparison.
    loaded = {label: load_sequences(folder) for label, folder in sets.items()}
    moving = any("motion" in seq.buffers for seqs in loaded.values() for seq in seqs)
    noisy = Method("noisy input", "input")
    raes = {(m, pr): Method(f"rae {m.stem} {pr}", "rae") for m in a.models for pr in precisions}
    stills = {m: Method(f"rae {m.stem} {precisions[0]} no motion", "rae") for m in a.models} if moving else {}
    unblended = {m: Method(f"rae {m.stem} {precisions[0]} no accumulation", "rae") for m in a.models} if moving else {}
    torches = {m: Method(f"PyTorch CPU {m.stem}", "pytorch") for m in a.models}
    oidns = {q: Method(f"OIDN {q}", "oidn") for q in ("high", "fast")}
    refs: dict[str, dict[str, list[np.ndarray]]] = {}
    devices: list[str] = []
    first: tuple[str, str, int] | None = None
    for label, folder in sets.items():
        for seq in loaded[label]:
            seq_folder = seq.folder
            print(f"[{label}] {seq.name}: {seq.frames} frames", flush=True)
            refs.setdefault(label, {})[seq.name] = [hwc(seq.buffers["reference"][i]) for i in range(seq.frames)]
            noisy.add(label, seq.name, [hwc(seq.buffers["color"][i]) for i in range(seq.frames)])
            for (m, pr), meth in raes.items():
                meth.add(label, seq.name, run_rae_cli(cli, m, pr, seq_folder, seq.frames, meth.times_ms, devices))
            for m, meth in stills.items():
                meth.add(label, seq.name, run_rae_cli(cli, m, precisions[0], seq_folder, seq.frames, meth.times_ms, devices, motion=False))
            for m, meth in unblended.items():
                out = run_rae_cli(cli, m, precisions[0], seq_folder, seq.frames, meth.times_ms, devices, accumulate=False)
                meth.add(label, seq.name, out)
            for m, meth in torches.items():
                meth.add(label, seq.name, run_rae(m, seq, meth.times_ms))
            for q, meth in oidns.items():
                meth.add(label, seq.name, run_oidn(seq, q, meth.times_ms))
            first = first or (label, seq.name, seq.frames - 1)
    methods = [noisy, *raes.values(), *unblended.values(), *stills.values(), *torches.values(), *oidns.values()]
    score(methods, refs)
    assert first is not None

    host = machine()
    device = "; ".join(devices)
    try:
        oidn_version = importlib.metadata.version("pyoidn")
    except importlib.metadata.PackageNotFoundError:
        oidn_version = "?"
    figures = a.out.parent / "report"
    stamp = f"`{command}` on {host}; rae on {device}"
    plot(methods, list(sets), figures / "error-vs-time.png", f"{command}\n{host}; rae: {device}")
    crop_set, crop_seq, k = first
    shown = raes[(a.models[0], precisions[0])]
    crop_cols = [("noisy input", noisy.outputs[crop_set][crop_seq][k]), (shown.name, shown.outputs[crop_set][crop_seq][k]), ("OIDN high", oidns["high"].outputs[crop_set][crop_seq][k])]
    crop_sheet(crop_cols, refs[crop_set][crop_seq][k], figures / "crops.png", f"{crop_set}/{crop_seq} frame {k}: {command}\n{host}")
    # At a disocclusion: the frame of a sequence with motion where the most pixels fail the
    # history test, rae with motion (accumulated and not) and without beside OIDN.
    uncovered = None
    if moving:
        uncovered = max(
            ((float(disocclusion(seq, i).sum()), label, seq, i) for label, seqs in loaded.items() for seq in seqs if "motion" in seq.buffers for i in range(1, seq.frames)),
            key=lambda t: t[0],
        )
        _, d_set, d_seq, d_k = uncovered
        still, raw = stills[a.models[0]], unblended[a.models[0]]
        d_ref = refs[d_set][d_seq.name][d_k]
        shown_cols = (("noisy input", noisy), (shown.name, shown), (raw.name, raw), (still.name, still), ("OIDN high", oidns["high"]))
        d_cols = [(n, meth.outputs[d_set][d_seq.name][d_k]) for n, meth in shown_cols]
        d_err = np.abs(tonemap(shown.outputs[d_set][d_seq.name][d_k]) - tonemap(d_ref)).mean(-1)
        spots = [("most disoccluded", disocclusion(d_seq, d_k)), ("largest rae error", d_err)]
        crop_sheet(d_cols, d_ref, figures / "crops-disocclusion.png", f"{d_set}/{d_seq.name} frame {d_k}: {command}\n{host}", spots=spots)

    bench = None
    if a.bench_sizes:
        print("rae-cli bench ...", flush=True)
        bench = bench_text(cli, a.models[0], a.bench_sizes, a.bench_frames, a.peak_gflops)
        print("PyTorch at the bench sizes ...", flush=True)
        peer = pytorch_at_sizes(a.models[0], a.bench_sizes.split(","), a.bench_frames)

    # The report.
    L = ["# rae: error against run time", ""]
    L += [f"Written by `{command}` (weights-tool/rae_weights/report.py); every table and figure below comes from this one run.", ""]
    L += [f"- Machine: {host}.", f"- rae: `rae-cli denoise` on {device}.", f"- PyTorch {torch.__version__} on the CPU, {a.threads} threads, float32, channels_last, same weights files.", f"- OIDN: pyoidn {oidn_version}, RT filter, HDR, color+albedo+normal, on the CPU, frame by frame (it has no temporal state).", ""]
    L += ["Time per frame: median over all frames but each sequence's first (shader compilation, warm-up), host memory to host memory (rae: upload + GPU + download as `rae-cli denoise --csv` records them). Errors: means over each sequence's frames, then over sequences; relMSE on radiance, PSNR/SSIM on tonemapped images (x/(1+x), sRGB), FLIP = mean HDR-FLIP (flip-evaluator), temporal = mean |d out - d ref| of tonemapped consecutive frames. Lower is better except PSNR and SSIM.", ""]
    for label, folder in sets.items():
        seqs = refs[label]
        shape = next(iter(seqs.values()))[0].shape
        L += [f"## Held-out set `{label}` ({folder}: {len(seqs)} sequences, {sum(len(v) for v in seqs.values())} frames, {shape[1]}x{shape[0]})", ""]
        L += ["| method | ms / frame | relMSE | PSNR (dB) | SSIM | FLIP | temporal |", "|---|---:|---:|---:|---:|---:|---:|"]
        for m in methods:
            r = m.metrics[label]
            t = "-" if m.kind == "input" else f"{m.ms:.1f}"
            L.append(f"| {m.name} | {t} | {r['relmse']:.4f} | {r['psnr']:.2f} | {r['ssim']:.4f} | {r['flip']:.4f} | {r['temporal']:.4f} |")
        L.append("")
        if stills:
            shown_still, shown_raw = stills[a.models[0]], unblended[a.models[0]]
            L += [f"Per sequence, `{shown.name}` with the sequence's motion (the hidden state reprojected, the output accumulated along it), with it but the output not accumulated (`--no-accumulate`) and without motion, beside OIDN high (temporal: lower is better; the last column is rae's with motion over OIDN's):", ""]
            L += ["| sequence | motion | PSNR with | PSNR not accumulated | PSNR without | PSNR OIDN | temporal with | temporal not accumulated | temporal without | temporal OIDN | with / OIDN |", "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
            for name in seqs:
                w, raw, wo, o = (x.per_seq[label][name] for x in (shown, shown_raw, shown_still, oidns["high"]))
                has = "yes" if any(q.name == name and "motion" in q.buffers for q in loaded[label]) else "no"
                L.append(
                    f"| {name} | {has} | {w['psnr']:.2f} | {raw['psnr']:.2f} | {wo['psnr']:.2f} | {o['psnr']:.2f} | {w['temporal']:.4f} | {raw['temporal']:.4f} | {wo['temporal']:.4f} | {o['temporal']:.4f} | {w['temporal'] / o['temporal']:.2f} |"
                )
            L.append("")
    L += ["## rae (wgpu) against PyTorch, same weights and frames", "", "Absolute difference of the output radiance over all frames of all sets; the last column divides each frame's largest difference by the frame's largest PyTorch value.", ""]
    L += ["| model | precision | max abs | mean abs | max / frame max |", "|---|---|---:|---:|---:|"]
    for (m, pr), meth in raes.items():
        mx, mean, relmax = abs_error(meth, torches[m])
        L.append(f"| {m.stem} | {pr} | {mx:.3e} | {mean:.3e} | {relmax:.3e} |")
    L.append("")
    L += ["## Error against time", "", f"![error against time]({rel(figures / 'error-vs-time.png', a.out.parent)})", "", f"Made by {stamp}.", ""]
    L += ["## Crops", "", f"Set `{crop_set}`, sequence `{crop_seq}`, frame {k}: where rae's error is largest and where the reference has the most detail.", "", f"![crops]({rel(figures / 'crops.png', a.out.parent)})", "", f"Made by {stamp}.", ""]
    if uncovered is not None:
        _, d_set, d_seq, d_k = uncovered
        L += ["## Crops at a disocclusion", "", f"Set `{d_set}`, sequence `{d_seq.name}`, frame {d_k}, the frame of the sequences with motion where the most pixels fail the history test (normal and depth against the previous frame's at x + motion, `rae_weights.warp.history`) with their whole 3x3 neighbourhood (a region the previous frame did not see, not speckled buffers): where the most do, and where rae's error is largest. rae with the sequence's motion (reprojected, history dropped where the test fails, the output accumulated along the motion), with it but not accumulated, and without it, beside OIDN high.", "", f"![crops at a disocclusion]({rel(figures / 'crops-disocclusion.png', a.out.parent)})", "", f"Made by {stamp}.", ""]
    if bench:
        bcmd, btext = bench
        rows = bench_rows(btext)
        L += ["## Speed at larger frames: rae against PyTorch", ""]
        L += [f"`{bcmd}` and, right after it, PyTorch (same weights, CPU, {a.threads} threads, channels_last, frames padded as rae pads them, median of {a.bench_frames} after 2 warm-up; `rae_weights.bench.time_frames`), on {host}:", ""]
        L += ["| size | rae f32 ms | rae f32 GFLOP/s | rae f16 ms | PyTorch ms | rae f32 / PyTorch |", "|---|---:|---:|---:|---:|---:|"]
        for size, torch_ms in peer.items():
            f32 = rows.get((size, "f32"), (float("nan"), float("nan")))
            f16 = rows.get((size, "f16"), (float("nan"), float("nan")))
            L.append(f"| {size} | {f32[0]:.1f} | {f32[1]:.2f} | {f16[0]:.1f} | {torch_ms:.1f} | {f32[0] / torch_ms:.2f} |")
        L += ["", "The full `rae-cli bench` output (per-stage GPU times from timestamp queries, GFLOP/s, share of the stated peak, GPU memory):", "", "```", btext.rstrip(), "```", ""]
    atomic_save(a.out, lambda path: path.write_text("\n".join(L)))
    print(f"wrote {a.out} and the figures in {figures}")
    return 0

"""Command line: ``rae-weights export``, ``interpolate``, ``drop-inputs`` and ``golden`` (also ``python -m rae_weights``)."""

from __future__ import annotations

import argparse
import dataclasses
import sys
import tempfile
from pathlib import Path

from . import golden
from .export import drop_inputs, infer_arch, interpolate, load_checkpoint, read_weights, write_weights


def _export(args: argparse.Namespace) -> int:
    state, arch = load_checkpoint(args.checkpoint)
    overrides = {}
    if args.inputs:
        overrides["inputs"] = args.inputs.split(",")
    for key in ("skip", "output_activation", "transfer"):
        if getattr(args, key) is not None:
            overrides[key] = getattr(args, key)
    if args.no_demodulate:
        overrides["demodulate"] = False
    if arch is None or overrides:
        arch = infer_arch(state, **overrides)
    write_weights(args.output, arch, state)
    n = sum(t.numel() for t in state.values())
    print(f"wrote {args.output}: {arch.to_json()} ({n} parameters)")
    return 0


def _interpolate(args: argparse.Namespace) -> int:
    arch, a = read_weights(args.a)
    arch_b, b = read_weights(args.b)
    if arch_b != arch:
        raise ValueError(f"{args.b}: another architecture than {args.a} ({arch_b.to_json()})")
    known = {name.split(".", 1)[0] for name in a}
    at: dict[str, float] = {}
    for spec in args.at:
        modules, sep, value = spec.partition("=")
        if not sep:
            raise ValueError(f"--at {spec}: expected MODULE[,MODULE...]=FRACTION")
        for m in modules.split(","):
            if m not in known:
                raise ValueError(f"--at {spec}: no module {m!r} (the weights have {', '.join(sorted(known))})")
            at[m] = float(value)
    write_weights(args.output, arch, interpolate(a, b, args.t, at))
    print(f"wrote {args.output}: {1 - args.t:g} x {args.a} + {args.t:g} x {args.b}" + "".join(f"; {m} at {f:g}" for m, f in at.items()))
    return 0


def _drop_inputs(args: argparse.Namespace) -> int:
    arch, state = read_weights(args.source)
    fill: dict[str, float] = {}
    for spec in args.fill.split(","):
        name, sep, value = spec.partition("=")
        if not sep:
            raise ValueError(f"--fill {args.fill}: expected INPUT=VALUE[,INPUT=VALUE...]")
        fill[name] = float(value)
    arch, state = drop_inputs(arch, state, fill)
    if args.no_demodulate:
        # Not a fold: the same weights then see the color itself rather than color / albedo, a
        # starting point for training a color-only network (no albedo needed).
        arch = dataclasses.replace(arch, demodulate=False)
    write_weights(args.output, arch, state)
    demod = "" if arch.demodulate else "; color not demodulated"
    print(f"wrote {args.output}: inputs {','.join(arch.inputs)} ({', '.join(f'{n} = {v:g}' for n, v in fill.items())} folded into d1.l1.0{demod})")
    return 0


def _golden(args: argparse.Namespace) -> int:
    if args.check:
        with tempfile.TemporaryDirectory() as tmp:
            golden.generate(Path(tmp))
            problems = golden.compare(Path(args.check), Path(tmp))
        for p in problems:
            print(p, file=sys.stderr)
        print("golden fixtures reproduce" if not problems else f"{len(problems)} differences")
        return 1 if problems else 0
    for path in golden.generate(Path(args.out)):
        print(f"wrote {path}")
    return 0


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="rae-weights", description=__doc__)
    sub = p.add_subparsers(dest="cmd", required=True)
    e = sub.add_parser("export", help="PyTorch checkpoint -> rae weights file (.safetensors)")
    e.add_argument("checkpoint")
    e.add_argument("output")
    e.add_argument("--inputs", help="comma-separated network inputs, e.g. color,normal,depth,roughness")
    e.add_argument("--skip", choices=["pooled", "prepool"])
    e.add_argument("--output-activation", choices=["lrelu", "linear"])
    e.add_argument("--transfer", choices=["log1p", "none"])
    e.add_argument("--no-demodulate", action="store_true")
    e.set_defaults(func=_export)
    i = sub.add_parser("interpolate", help="weights (1 - t) * A + t * B, the fraction chosen per module")
    i.add_argument("a")
    i.add_argument("b")
    i.add_argument("output")
    i.add_argument("--t", type=float, required=True, help="fraction of B (0: A, 1: B)")
    i.add_argument("--at", action="append", default=[], metavar="MODULE[,MODULE...]=FRACTION", help="another fraction for these modules (d1..d5, bottleneck, u1..u5)")
    i.set_defaults(func=_interpolate)
    d = sub.add_parser("drop-inputs", help="a network for fewer buffers: dropped inputs folded into the first conv's bias")
    d.add_argument("source")
    d.add_argument("output")
    d.add_argument("--fill", required=True, metavar="INPUT=VALUE[,INPUT=VALUE...]", help="the inputs to drop and the value each stands at (prepared: log1p for depth)")
    d.add_argument("--no-demodulate", action="store_true", help="the result reads color as is, without albedo (a warm start for training, not an exact fold)")
    d.set_defaults(func=_drop_inputs)
    g = sub.add_parser("golden", help="write (or --check) the golden fixtures of the Rust tests")
    g.add_argument("--out", default="tests/fixtures")
    g.add_argument("--check", metavar="DIR", help="regenerate into a temporary folder and compare with DIR")
    g.set_defaults(func=_golden)
    sub.add_parser("train", help="train on rae-trace sequences (see `train --help`)", add_help=False)
    sub.add_parser("bench", help="PyTorch CPU time per frame of a weights file (see `bench --help`)", add_help=False)
    sub.add_parser("evaluate", help="held-out metrics of models, noisy input and OIDN (see `evaluate --help`)", add_help=False)
    sub.add_parser("report", help="error against run time of rae, PyTorch and OIDN -> docs/REPORT.md (see `report --help`)", add_help=False)
    sub.add_parser("ranges", help="activation ranges and f16 headroom on real sequences (see `ranges --help`)", add_help=False)
    if argv is None:
        import sys as _sys
        argv = _sys.argv[1:]
    if argv and argv[0] == "train":
        from .train import main as train_main

        return train_main(argv[1:])
    if argv and argv[0] == "bench":
        from .bench import main as bench_main

        return bench_main(argv[1:])
    if argv and argv[0] == "evaluate":
        from .evaluate import main as evaluate_main

        return evaluate_main(argv[1:])
    if argv and argv[0] == "report":
        from .report import main as report_main

        return report_main(argv[1:])
    if argv and argv[0] == "ranges":
        from .ranges import main as ranges_main

        return ranges_main(argv[1:])
    args = p.parse_args(argv)
    try:
        return args.func(args)
    except (ValueError, OSError) as err:
        print(f"rae-weights: {err}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())

"""The learning curve of Bayesian intention recognition (issue 4; docs/INTENTION.md).

    .venv/bin/python tools/intention_curve.py [--seeds 10] [--iterations 5000] [--window 250]
                                              [--set KEY=VALUE ...] [--out out/intention]

Runs ``--intention bayes`` and the oracle with the same seeds, prints the recognition accuracy per
window (mean over seeds and a 95% interval), the first/last-500 accuracy, HSR of both modes, and
writes ``intention_curve.png`` and ``intention_curve.json`` into ``--out``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from homeo_sim.metrics import accuracy_curve
from homeo_sim.runner import RunConfig, build_scenario, run_seeds
from homeo_sim.stats import aggregate, describe


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--iterations", type=int, default=5000)
    ap.add_argument("--window", type=int, default=250)
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="override an open choice")
    ap.add_argument("--out", default="out/intention")
    ap.add_argument("--workers", type=int, default=None)
    args = ap.parse_args(argv)
    overrides = []
    for s in args.set:
        k, v = s.split("=", 1)
        try:
            v = json.loads(v)
        except json.JSONDecodeError:
            pass
        overrides.append((k, v))
    seeds = range(args.seeds)
    base = RunConfig(iterations=args.iterations, overrides=tuple(overrides))
    bayes = run_seeds(RunConfig(**{**base.__dict__, "intention": "bayes"}), seeds, args.workers)
    oracle = run_seeds(base, seeds, args.workers)
    curves = [accuracy_curve(r.intention_hits, args.window) for r in bayes]
    windows = [describe([c[i] for c in curves]) for i in range(len(curves[0]))]
    names = build_scenario(base).drive_names
    mb, mo = aggregate([r.metrics for r in bayes], names), aggregate([r.metrics for r in oracle], names)
    acc = {k: describe([r.metrics["intention_accuracy"][k] for r in bayes]) for k in ("first_500", "last_500")}
    print(f"accuracy per {args.window}-tick window (mean [95% interval] over {args.seeds} seeds):")
    for i, w in enumerate(windows):
        print(f"  {i * args.window:5d}-{(i + 1) * args.window - 1:5d}  {w['mean']:.3f} [{w['ci95'][0]:.3f}, {w['ci95'][1]:.3f}]")
    print(f"first 500: {acc['first_500']['mean']:.3f}   last 500: {acc['last_500']['mean']:.3f}   "
          f"gain: {acc['last_500']['mean'] - acc['first_500']['mean']:.3f}")
    for key in ("HSR", "RSR"):
        print(f"{key}: bayes {mb[key]['mean']:.3f} [{mb[key]['ci95'][0]:.3f}, {mb[key]['ci95'][1]:.3f}]   "
              f"oracle {mo[key]['mean']:.3f} [{mo[key]['ci95'][0]:.3f}, {mo[key]['ci95'][1]:.3f}]   "
              f"difference {mo[key]['mean'] - mb[key]['mean']:+.3f}")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "intention_curve.json").write_text(json.dumps({
        "seeds": list(seeds), "iterations": args.iterations, "window": args.window, "overrides": overrides,
        "accuracy_windows": windows, "intention_accuracy": acc, "bayes": mb, "oracle": mo}))
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    x = [(i + 0.5) * args.window for i in range(len(windows))]
    fig, ax = plt.subplots(figsize=(7, 3.6))
    ax.plot(x, [w["mean"] for w in windows], marker="o", ms=3, label="recognition accuracy (bayes)")
    ax.fill_between(x, [w["ci95"][0] for w in windows], [w["ci95"][1] for w in windows], alpha=0.25)
    ax.axhline(0.90, ls=":", c="grey", lw=1)
    ax.set_xlabel("iteration")
    ax.set_ylabel(f"accuracy per {args.window} iterations")
    ax.set_ylim(0.4, 1.0)
    ax.set_title(f"Bayesian intention recognition learning this user ({args.seeds} seeds)")
    ax.legend(loc="lower right")
    fig.tight_layout()
    fig.savefig(out / "intention_curve.png", dpi=120)
    print(f"wrote {out / 'intention_curve.png'} and {out / 'intention_curve.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

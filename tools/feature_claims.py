"""The two features' claims, one change at a time (issue 31, docs/FIDELITY.md): for the current default and each
change of it, over the seeds given, Table 4.5's mean absolute error, HSR with the pseudo update against HSR
without it (Sec 4.2.4, Chapter 5: "about 10%") and RSR at xi 0, 0.5 and 1 (Sec 4.2.3: "greatly improved with xi
larger than 0.5").

    .venv/bin/python tools/feature_claims.py --seeds 20000-20019 [--change KEY=JSON[,KEY=JSON] ...]
"""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

TOOLS = Path(__file__).resolve().parent
sys.path.insert(0, str(TOOLS))
sys.path.insert(0, str(TOOLS.parent / "src"))

import error_search as es  # noqa: E402
from homeo_msgs_py.cli_args import Parser, run_command  # noqa: E402
from homeo_sim.report.fidelity import error_summary, relative_errors  # noqa: E402
from homeo_sim.runner import run_seeds  # noqa: E402
from homeo_sim.stats import aggregate  # noqa: E402

PROG = "feature_claims.py"


def measure(o: dict, seeds: list[int], workers: int = 1) -> dict:
    """Table 4.5's errors, the pseudo update's HSR ratio and RSR at xi 0, 0.5, 1 for the open block ``o``."""
    base = es.j._configs(o, ())["base"]
    agg = {k: aggregate([r.metrics for r in run_seeds(cfg, seeds, workers)], es.DRIVES) for k, cfg in
           (("base", base), ("off", replace(base, pseudo_update=False)), ("xi0", replace(base, xi=0.0)),
            ("xi.5", replace(base, xi=0.5)))}
    e = error_summary(relative_errors(agg["base"], es.SC.reference.metrics))
    m = lambda k, p: agg[k][p]["mean"]  # noqa: E731
    return {"mae": e["mean_abs_error"], "largest": e["largest"], "largest_error": e["largest_error"],
            "HSR": m("base", "HSR"), "RSR": m("base", "RSR"), "pseudo_ratio": m("base", "HSR") / m("off", "HSR"),
            "RSR_xi": [m("xi0", "RSR"), m("xi.5", "RSR"), m("base", "RSR")]}


def row(label: str, x: dict) -> str:
    r0, r5, r1 = x["RSR_xi"]
    return (f"| {label} | {100 * x['mae']:.1f}% | {x['largest'].replace('.', ' ')} {100 * x['largest_error']:+.0f}% | "
            f"{x['HSR']:.3f} | {x['RSR']:.3f} | {100 * (x['pseudo_ratio'] - 1):+.1f}% | {r0:.2f} / {r5:.2f} / {r1:.2f} | "
            f"{r1 - r5:+.2f} |")


def build_parser() -> Parser:
    return es.points_parser(PROG, __doc__, "20000-20019")


def main(argv=None) -> int:
    def command() -> int:
        a = build_parser().parse_args(argv)
        seeds, points = es.points_of(a)
        print("| point | MAE | largest | HSR | RSR | HSR with / without pseudo update | RSR at xi 0 / 0.5 / 1 | "
              "RSR(1) - RSR(0.5) |\n|---|---|---|---|---|---|---|---|")
        for label, o in points:
            print(row(label, measure(o, seeds, a.workers)), flush=True)
        return 0

    return run_command(PROG, command, (), os_errors=True)


if __name__ == "__main__":
    raise SystemExit(main())

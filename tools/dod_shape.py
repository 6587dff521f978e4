"""The shape of RSR over the Degree of Dedication (Fig 4.5; issue 25, docs/FIDELITY.md "The DoD line").

    .venv/bin/python tools/dod_shape.py --seeds 5000-5099 [--change KEY=JSON[,KEY=JSON] ...]

For the current default (and each change of it): mean RSR and HSR at every DoD of the sweep over all the
seeds, then per disjoint set of 20 seeds the criterion of "RSR is almost negatively linearly related to
[DoD]" (RSR(0.5) against the straight line from RSR(0) to RSR(1), tolerance 0.1) and where the curve
leaves that line the most over the whole grid.
"""

from __future__ import annotations

import sys
from pathlib import Path

TOOLS = Path(__file__).resolve().parent
sys.path.insert(0, str(TOOLS))
sys.path.insert(0, str(TOOLS.parent / "src"))

import error_search as es  # noqa: E402
from homeo_msgs_py.cli_args import Parser, run_command  # noqa: E402
from homeo_sim.report.fidelity import seed_sets  # noqa: E402
from homeo_sim.runner import run_seeds  # noqa: E402
from homeo_sim.sweep import SWEEPS  # noqa: E402

PROG = "dod_shape.py"
# issue 25's criterion of dod_linear_rsr: RSR(0.5) within 0.1 of the straight line from RSR(0) to RSR(1) (issue 31
# reads "linearly related" as Pearson's r, docs/FIDELITY.md); the ends are DoD 0 and 1, so shape() walks the line
# by the DoD itself
LINEAR_TOL = 0.1
LINE_LOW, LINE_MID, LINE_HIGH = 0.0, 0.5, 1.0


def curve(o: dict, seeds: list[int], workers: int = 1) -> dict:
    """RSR and HSR per seed at every DoD of the sweep: ``{dod: {"RSR": [...], "HSR": [...]}}``."""
    cfgs = es.j._configs(o, SWEEPS["dod"])
    out = {}
    for d in SWEEPS["dod"]:
        ms = [r.metrics for r in run_seeds(cfgs[f"dod={d}"], seeds, workers)]
        out[d] = {"RSR": [m["RSR"] for m in ms], "HSR": [m["HSR"] for m in ms]}
    return out


def shape(c: dict, idx: list[int]) -> dict:
    """Over the seeds at positions ``idx``: mean RSR per DoD, RSR(0.5) minus the line from RSR(0) to RSR(1),
    and the largest departure from that line over the grid (with its DoD)."""
    rsr = {d: sum(v["RSR"][i] for i in idx) / len(idx) for d, v in c.items()}
    lo, hi = rsr[LINE_LOW], rsr[LINE_HIGH]
    dev = {d: r - (lo + (hi - lo) * d) for d, r in rsr.items()}
    far = max(dev, key=lambda d: abs(dev[d]))
    return {"rsr": rsr, "at_half": dev[LINE_MID], "largest": (far, dev[far])}


def report(label: str, c: dict, seeds: list[int]) -> list[str]:
    everything = shape(c, list(range(len(seeds))))
    hsr = {d: sum(v["HSR"]) / len(v["HSR"]) for d, v in c.items()}
    sets = [shape(c, pos) for pos in seed_sets(range(len(seeds)))]  # the seeds are distinct: by position
    held = sum(abs(s["at_half"]) <= LINEAR_TOL for s in sets)
    far, dev = everything["largest"]
    per_set = ", ".join(f"{s['at_half']:+.2f}" for s in sets)
    return [f"| {label} | RSR | " + " | ".join(f"{everything['rsr'][d]:.2f}" for d in SWEEPS["dod"])
            + f" | {everything['at_half']:+.3f} ({per_set}; holds on {held}/{len(sets)}) | {dev:+.2f} at {far:g} |",
            f"| | HSR | " + " | ".join(f"{hsr[d]:.2f}" for d in SWEEPS["dod"]) + " | | |"]


def build_parser() -> Parser:
    return es.points_parser(PROG, __doc__, "5000-5099")


def main(argv=None) -> int:
    def command() -> int:
        a = build_parser().parse_args(argv)
        seeds, points = es.points_of(a)
        print("| point | | " + " | ".join(f"DoD {d:g}" for d in SWEEPS["dod"])
              + " | RSR(0.5) - line (per set of 20) | largest departure |")
        print("|---|---|" + "---|" * (len(SWEEPS["dod"]) + 2))
        for label, o in points:
            print("\n".join(report(label, curve(o, seeds, a.workers), seeds)), flush=True)
        return 0

    return run_command(PROG, command, (), os_errors=True)


if __name__ == "__main__":
    raise SystemExit(main())

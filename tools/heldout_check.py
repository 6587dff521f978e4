"""Fidelity of a few open blocks on further sets of 20 seeds (issue 15, third stage; docs/FIDELITY.md).

    .venv/bin/python tools/heldout_check.py 400-419 500-519

For each seed set: the current default and each change (KEY=JSON of the searched open choices, the
default ones below) scored as the confirmation scores (``joint_search.evaluate`` with the full DoD grid),
one Markdown row each. The count of Table 4.5 numbers inside our 95% interval moves by one or two
from one set of 20 seeds to the next; this shows by how much around the adopted block.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import joint_search as j  # noqa: E402
from homeo_sim.sweep import SWEEPS  # noqa: E402

# the adopted block's rivals (docs/FIDELITY.md, "Third stage"); a change that is the default already is scored once
CHANGES = ({}, {"human_proposal_prob": 0.8}, {"human_proposal_prob": 0.9}, {"human_proposal_prob": 1.0},
           {"tie_break": "last"})


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="heldout_check.py", description=__doc__.splitlines()[0])
    ap.add_argument("seed_sets", nargs="+", metavar="A-B")
    ap.add_argument("--change", action="append", default=[], metavar="KEY=JSON",
                    help="a point to score: the default with this change (repeat for several keys of one point "
                         "as KEY=JSON,KEY=JSON); default: the points of docs/FIDELITY.md")
    ap.add_argument("--workers", type=int, default=2)
    a = ap.parse_args(argv)
    try:
        sets = [j._seeds(s) for s in a.seed_sets]
        changes = [dict((kv.split("=", 1)[0], json.loads(kv.split("=", 1)[1])) for kv in c.split(","))
                   for c in a.change] or list(CHANGES)
    except (ValueError, IndexError) as exc:  # SeedSetError, a change without "=" or with bad JSON
        ap.error(f"bad seed set or change: {str(exc)[:120]}".replace("\n", " "))
    start = j.current_open()
    bad = [k for c in changes for k in c if k not in start]
    if bad:
        ap.error(f"not a searched open choice: {', '.join(bad)}")
    points = []  # each distinct point once: a change equal to the default is the default
    for c in changes:
        if {**start, **c} not in points:
            points.append({**start, **c})
    print("| point | seeds | Table 4.5 inside | statements | trends | HSR | RSR | inside | unmet |")
    print("|---|---|---|---|---|---|---|---|---|")
    for spec, seeds in zip(a.seed_sets, sets):
        for point in points:
            e = j.evaluate(point, seeds, dods=SWEEPS["dod"], workers=a.workers)
            print(f"| {j.diff(point, start)} | {spec} | {e['inside']}/12 | {e['met']}/10 | {e['trends']}/6 | "
                  f"{e['HSR']:.3f} | {e['RSR']:.3f} | {', '.join(e['inside_names'])} | {', '.join(e['unmet'])} |",
                  flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""A long graph run against fresh ones over the same minutes: does its cost per tick grow with its length?

    python tools/soak_compare.py LONG.json [EARLY.json LATE.json] [--skip 0.2] [--segments 20]

Each file is the ``--samples`` output of a ``homeo-launch soak`` run (its graph part). The fresh runs
are short graphs started beside the long one by hand (on another ROS domain), one near its start,
one near its end; ``homeo-launch soak --fresh TICKS`` does the same in one command. On a shared
machine the CPU time of a tick moves with the load by more than the target allows (+-30% within an
hour here), and both graphs feel the same load; so the long run's CPU time per
tick over a fresh run's steady part (``--skip``: its first fifth left out, start-up), in the same
wall-clock window, is free of the machine's drift. If that ratio is the same near the long run's end
as near its start, the run's length costs nothing.

Without fresh runs (and before their comparison) it fits, for each process of the long run, its CPU
time per tick over ``--segments`` stretches of the run against the reference's CPU time per piece in
the same stretches and the tick: log(cost) = a + b log(reference) + c tick. ``c`` (in % per 100,000
ticks) is the growth with the run's length once the load is taken out; ``b`` how much the process
feels what the reference feels.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

from homeo_ops.soak import format_fresh, side_by_side  # noqa: E402


def drift(g: dict, segments: int) -> dict:
    """name -> (b, c in % per 100k ticks, its standard error, R^2) of the fit described above, from
    a graph part's samples."""
    import numpy as np

    ref = {k: (n, c) for k, n, c in g["reference"]}
    out = {}
    for name, pts in g["cpu"].items():
        pts = [(k, c) for k, c in pts if k in ref]
        if len(pts) < 2 * segments:
            continue
        idx = np.linspace(0, len(pts) - 1, segments + 1).round().astype(int)
        rows = []
        for i, j in zip(idx[:-1], idx[1:]):
            (k0, c0), (k1, c1) = pts[i], pts[j]
            (n0, r0), (n1, r1) = ref[k0], ref[k1]
            if k1 > k0 and n1 > n0:
                rows.append(((k0 + k1) / 2, np.log((c1 - c0) / (k1 - k0)), np.log((r1 - r0) / (n1 - n0))))
        t, y, r = map(np.array, zip(*rows))
        X = np.column_stack([np.ones_like(t), r, t / 1e5])
        beta, *_ = np.linalg.lstsq(X, y, rcond=None)
        res = y - X @ beta
        dof = max(1, len(y) - 3)
        cov = np.linalg.inv(X.T @ X) * (res @ res) / dof
        r2 = 1 - (res @ res) / (((y - y.mean()) ** 2).sum() or 1)
        out[name] = (beta[1], (np.exp(beta[2]) - 1) * 100, np.sqrt(cov[2, 2]) * 100, r2)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("long")
    ap.add_argument("fresh", nargs="*")
    ap.add_argument("--segments", type=int, default=20, help="stretches of the long run in the fit")
    ap.add_argument("--skip", type=float, default=0.2, help="the fresh run's first fraction left out (start-up)")
    a = ap.parse_args(argv)
    long = json.loads(Path(a.long).read_text())["graph"]
    print(f"{a.long}: log(CPU per tick) = a + b log(reference per piece) + c tick, over {a.segments} stretches")
    print(f"  {'process':16} {'b':>6} {'c: % per 100k ticks':>20} {'R^2':>6}")
    for name, (b, c, se, r2) in drift(long, a.segments).items():
        print(f"  {name:16} {b:6.2f} {c:+10.1f} +- {se:4.1f}   {r2:6.2f}")
    if a.fresh:
        fresh = [json.loads(Path(p).read_text())["graph"] for p in a.fresh]
        runs = [side_by_side(long, f, a.skip) for f in fresh]
        print("\n".join(format_fresh({"ticks": fresh[0]["time"][-1][0], "early": runs[0], "late": runs[-1]})))
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Does a robot that stops and resumes from its checkpoint do as well as one that never stopped?

Issue 12's check, in-process (the graph's nodes run the same objects): per seed, (a) one
uninterrupted run of FIRST + SECOND ticks; (b) FIRST ticks, a checkpoint through JSON
(``homeo_decision.checkpoint``: Q-table, random stream, learned ticks), then a new world and a
new robot restored from it, with the schedule offset by the learned ticks, for SECOND ticks (as
``homeo-launch sim --resume``: the world starts again with the same seed); (c) as (b) but the
schedule starts again at tick 0 (what a plain --load-q did before). HSR over ticks
FIRST+1 .. FIRST+WINDOW of each, mean and 95% interval over seeds; (b) passes when its mean is not
lower than (a)'s by more than (a)'s interval half-width.

    PYTHONPATH=src .venv/bin/python tools/resume_check.py [--seeds 20] [--first 2500] [--second 2500] [--window 200]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

from homeo_decision import checkpoint  # noqa: E402
from homeo_sim.parallel import parallel_map  # noqa: E402
from homeo_sim.runner import RunConfig, Simulation, build_scenario  # noqa: E402
from homeo_sim.stats import describe  # noqa: E402


def window_hsr(series: dict, lo: int, hi: int) -> float:
    e, s = series["expressed"][lo:hi], series["satisfied"][lo:hi]
    return float(s.sum() / e.sum()) if e.sum() else float("nan")


def one_seed(args: tuple) -> tuple[float, float, float, dict]:
    seed, first, second, window = args
    sc = build_scenario(RunConfig())
    cfg = RunConfig(iterations=first + second, seed=seed, series=True)
    whole = Simulation(sc, cfg).run(first + second).series
    a = window_hsr(whole, first, first + window)
    stop = Simulation(sc, cfg)
    stop.run(first)
    ck = json.loads(json.dumps(checkpoint.decision_checkpoint(stop.policy, first, 0)))
    out = []
    for offset in (True, False):
        sim = Simulation(sc, cfg)
        checkpoint.restore_decision(sim.policy, ck)
        if offset:
            sim.policy.set_tick_offset(ck["ticks"])
        ph = sim.policy.phase(0)
        out.append((window_hsr(sim.run(second).series, 0, window), {"alpha": ph.alpha, "tau": ph.tau}))
    return a, out[0][0], out[1][0], out[0][1]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--first", type=int, default=2500)
    ap.add_argument("--second", type=int, default=2500)
    ap.add_argument("--window", type=int, default=200)
    ap.add_argument("--workers", type=int, default=None)
    a = ap.parse_args(argv)
    res = parallel_map(one_seed, [(s, a.first, a.second, a.window) for s in range(a.seeds)], a.workers)
    whole, resumed, restarted = (describe([r[i] for r in res]) for i in range(3))
    ph = res[0][3]
    print(f"HSR over ticks {a.first + 1}-{a.first + a.window}, mean [95% interval] over {a.seeds} seeds:")
    print(f"  uninterrupted {a.first + a.second} ticks:        {whole['mean']:.4f} [{whole['ci95'][0]:.4f}, {whole['ci95'][1]:.4f}]")
    print(f"  resumed, schedule goes on (alpha {ph['alpha']}, tau {ph['tau']}): "
          f"{resumed['mean']:.4f} [{resumed['ci95'][0]:.4f}, {resumed['ci95'][1]:.4f}]")
    print(f"  resumed, schedule from 0 (old --load-q): {restarted['mean']:.4f} "
          f"[{restarted['ci95'][0]:.4f}, {restarted['ci95'][1]:.4f}]")
    half = (whole["ci95"][1] - whole["ci95"][0]) / 2
    ok = resumed["mean"] >= whole["mean"] - half
    print(f"resumed - uninterrupted = {resumed['mean'] - whole['mean']:+.4f} (allowed down to -{half:.4f}): "
          f"{'PASS' if ok else 'FAIL'}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())

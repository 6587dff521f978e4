"""Ray's overhead on one machine (issue 30): the same ``homeo-sim report`` on the local process pool and as Ray
tasks on a one-machine cluster started here on loopback (tools/loopback_cluster.py; a node with all cores),
in one run, alternating; prints each round's wall time of the runs, the overhead ratio (cluster / local, the
issue's bar: <= 1.15) and the runs a second per core, and checks that both wrote the same results.json.

    .venv/bin/python tools/cluster_bench.py                     # the 100-seed report (2400 runs of 5000 iterations)
    .venv/bin/python tools/cluster_bench.py --seeds 10 --rounds 2
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

TOOLS = Path(__file__).resolve().parent
sys.path.insert(0, str(TOOLS))
sys.path.insert(0, str(TOOLS.parent / "src"))

from loopback_cluster import LoopbackCluster  # noqa: E402
from homeo_sim.parallel import Pool  # noqa: E402
from homeo_sim.report import build_report  # noqa: E402


def one(out: Path, seeds: int, iterations: int, pool: Pool) -> tuple[float, dict]:
    data = build_report(out, seeds=seeds, iterations=iterations, workers=pool, quiet=True)
    res = json.loads((out / "results.json").read_text())
    res.pop("timing")
    return data["timing"]["runs_s"], res


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=100)
    ap.add_argument("--iterations", type=int, default=5000)
    ap.add_argument("--rounds", type=int, default=1, help="local then cluster, this many times")
    a = ap.parse_args(argv)
    cores = os.cpu_count() or 1
    with LoopbackCluster(head_cpus=cores, nodes=()) as c, tempfile.TemporaryDirectory() as tmp:
        cluster = Pool(cluster=c.address)
        print(f"one-machine Ray cluster at {c.address}: {cores} CPUs; report of {a.seeds} seeds x {a.iterations} "
              f"iterations, {a.rounds} round(s), load {os.getloadavg()[0]:.1f}", flush=True)
        ratios, rates, same = [], [], True
        for r in range(a.rounds):
            t_local, res_local = one(Path(tmp) / f"local{r}", a.seeds, a.iterations, Pool())
            t_ray, res_ray = one(Path(tmp) / f"ray{r}", a.seeds, a.iterations, cluster)
            runs = json.loads((Path(tmp) / f"ray{r}" / "results.json").read_text())["timing"]["jobs"]
            same &= res_local == res_ray
            ratios.append(t_ray / t_local)
            rates.append((runs / t_local / cores, runs / t_ray / cores))
            print(f"round {r}: {runs} runs: local pool {t_local:.1f} s, Ray {t_ray:.1f} s: overhead x{ratios[-1]:.3f}; "
                  f"runs/s per core {rates[-1][0]:.2f} local, {rates[-1][1]:.2f} Ray; load "
                  f"{os.getloadavg()[0]:.1f}", flush=True)
        print(f"Ray / local pool: x{statistics.median(ratios):.3f} (median of {len(ratios)}; the bar: 1.15); "
              f"runs/s per core: {statistics.median(x for x, _ in rates):.2f} local, "
              f"{statistics.median(y for _, y in rates):.2f} Ray; results.json {'identical' if same else 'DIFFERENT'}")
    return 0 if same else 1


if __name__ == "__main__":
    t0 = time.time()
    code = main()
    print(f"({time.time() - t0:.0f} s)", file=sys.stderr)
    raise SystemExit(code)

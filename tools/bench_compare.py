"""Core loop speed of this checkout against another git revision, measured in one run.

    python tools/bench_compare.py REV [--rounds 9] [--iterations 20000] [--instructions]

Checks REV out into a temporary worktree and alternates fresh processes of the two (this machine
is shared and noisy: single runs vary by +-30%), in ABBA order, each the best of 5 episodes of
``homeo-sim run``'s default setting in CPU time; prints every round's iterations/s and the ratio of
the medians. ``--instructions`` counts instructions per iteration instead, with valgrind's
callgrind (repeatable whatever else the machine does: the difference of a 11000- and a
1000-iteration episode, PYTHONHASHSEED fixed).
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CODE = ("import time\nfrom homeo_sim.runner import RunConfig, run_episode\nfrom homeo_decision.scenario import load_scenario\n"
        "sc = load_scenario(); cfg = RunConfig(iterations={n}, seed=0); run_episode(cfg, sc); best = 9e9\n"
        "for _ in range(5):\n    t = time.process_time(); run_episode(cfg, sc); best = min(best, time.process_time() - t)\n"
        "print({n} / best)")


def rate(src: Path, n: int) -> float:
    out = subprocess.run([sys.executable, "-c", CODE.format(n=n)], env={"PYTHONPATH": str(src), "PATH": "/usr/bin:/bin"},
                         capture_output=True, text=True, check=True)
    return float(out.stdout)


def instructions(src: Path, n: int) -> int:
    code = ("from homeo_sim.runner import RunConfig, run_episode\nfrom homeo_decision.scenario import load_scenario\n"
            f"run_episode(RunConfig(iterations={n}, seed=0), load_scenario())")
    with tempfile.NamedTemporaryFile() as out:
        r = subprocess.run(["valgrind", "--tool=callgrind", "--trace-children=yes", f"--callgrind-out-file={out.name}",
                            sys.executable, "-c", code], capture_output=True, text=True,
                           env={"PYTHONPATH": str(src), "PATH": "/usr/bin:/bin", "PYTHONHASHSEED": "0",
                                "PYTHONDONTWRITEBYTECODE": "1"})  # the same start-up in both runs
    counts = [int(x.split(":")[1]) for x in r.stderr.splitlines() if "Collected :" in x for x in [x.split("==")[-1]]]
    if not counts:
        raise SystemExit(f"valgrind gave no count: {r.stderr[-300:]}")
    return counts[-1]


def per_iteration(src: Path) -> float:
    return (instructions(src, 11000) - instructions(src, 1000)) / 10000


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("rev")
    ap.add_argument("--rounds", type=int, default=9)
    ap.add_argument("--iterations", type=int, default=20000)
    ap.add_argument("--instructions", action="store_true", help="count instructions (callgrind) instead of timing")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="homeo-bench-") as tmp:
        wt = Path(tmp) / "rev"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(wt), a.rev], check=True,
                       capture_output=True)
        try:
            if a.instructions:
                b, h = per_iteration(wt / "src"), per_iteration(ROOT / "src")
                print(f"instructions per iteration: {a.rev} {b:,.0f}, this checkout {h:,.0f}; this/rev = {h / b:.3f}")
                return 0
            runs = {"rev": [], "here": []}
            for r in range(a.rounds):
                order = (("rev", wt / "src"), ("here", ROOT / "src"))
                for name, src in order if r % 2 == 0 else order[::-1]:
                    runs[name].append(rate(src, a.iterations))
                print(f"round {r + 1}: {a.rev} {runs['rev'][-1]:,.0f} it/s, this checkout {runs['here'][-1]:,.0f} it/s",
                      file=sys.stderr)
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(wt)], capture_output=True)
    b, h = statistics.median(runs["rev"]), statistics.median(runs["here"])
    bb, hb = max(runs["rev"]), max(runs["here"])  # noise only ever slows a run down: the best is the least disturbed
    print(f"median iterations/s: {a.rev} {b:,.0f}, this checkout {h:,.0f}; this/rev = {h / b:.3f}")
    print(f"best iterations/s  : {a.rev} {bb:,.0f}, this checkout {hb:,.0f}; this/rev = {hb / bb:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

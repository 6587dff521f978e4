"""A long graph run profiled early and late: does a tick cost more after 50,000 ticks, and where?

Runs ``homeo-launch sim --iterations N --rate 0`` (signed, checkpoints every 100 ticks, as by default)
and samples every node with py-spy (``homeo_ops.profile``) for ``--window`` seconds twice:
from tick ``--early`` on and from tick ``--late`` on. Prints, per window, each node's CPU
milliseconds a tick (from /proc) and the budget's categories as shares of the wall clock, the two
side by side; the run's wall time and each node's memory at both ends. The tick is read from the
decision's checkpoint (every 100 ticks). A measurement, not a test: on a shared machine compare the
shares (what the time is spent on), not the absolute figures.

    .venv/bin/python tools/profile_long_run.py [--iterations 60000] [--early 3000] [--late 50000] [--window 20]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from homeo_ops import profile
from homeo_ops.soak import cpu_s, rss_mb
from homeo_record.procfs import stat_fields
from homeo_msgs_py.graph import NODES


def node_pids(launcher: int) -> dict:
    out = {}
    for d in Path("/proc").iterdir():
        stat = stat_fields(d.name) if d.name.isdigit() else None  # None: not a process (or gone)
        try:
            if stat is not None and int(stat[1]) == launcher:  # its parent (field 4) is the launcher
                cmd = (d / "cmdline").read_bytes().split(b"\0")
                mod = cmd[cmd.index(b"-m") + 1].decode() if b"-m" in cmd else ""
                out.update({n: int(d.name) for n, desc in NODES.items() if desc.module == mod})
        except (OSError, ValueError, IndexError):
            pass
    return out


def ticks(ck: Path) -> int:
    try:
        return json.loads((ck / "homeo_decision.json").read_text())["ticks"]
    except (OSError, ValueError, KeyError):
        return -1


def window(pids: dict, ck: Path, seconds: float) -> dict:
    s = profile.Sampler()
    try:
        t0, c0 = ticks(ck), {n: cpu_s(p) for n, p in pids.items()}
        w0 = time.monotonic()
        s.start(pids)
        time.sleep(seconds)
        budgets = s.stop()
        t1, c1, w1 = ticks(ck), {n: cpu_s(p) for n, p in pids.items()}, time.monotonic()
    finally:
        s.close()
    n = max(1, t1 - t0)
    ms_tick = (w1 - w0) * 1e3 / n
    return {"ticks": [t0, t1], "ms_per_tick": ms_tick, "cpu_ms_per_tick": {k: (c1[k] - c0[k]) * 1e3 / n for k in pids},
            "shares": {k: {c: v / ms_tick for c, v in row.items()}
                       for k, row in profile.per_tick(budgets, ms_tick).items()}}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--iterations", type=int, default=60000)
    ap.add_argument("--early", type=int, default=3000)
    ap.add_argument("--late", type=int, default=50000)
    ap.add_argument("--window", type=float, default=20.0)
    ap.add_argument("--json", metavar="FILE")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="homeo-long-") as tmp:
        ck = Path(tmp) / "ck"
        t_start = time.monotonic()
        p = subprocess.Popen([sys.executable, "-m", "homeo_launch.cli", "sim", "--iterations", str(a.iterations),
                              "--rate", "0", "--quiet", "--data-dir", tmp, "--checkpoint-dir", str(ck)],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        out, mem = {}, {}
        for name, at in (("early", a.early), ("late", a.late)):
            while p.poll() is None and ticks(ck) < at:
                time.sleep(0.2)
            pids = node_pids(p.pid)
            mem.setdefault("start", {n: rss_mb(q) for n, q in pids.items()})
            if p.poll() is None:
                out[name] = window(pids, ck, a.window)
        mem["end"] = {n: rss_mb(q) for n, q in node_pids(p.pid).items()}
        stdout, stderr = p.communicate()
        wall = time.monotonic() - t_start
    print(stderr.strip().splitlines()[-1] if stderr.strip() else "", file=sys.stderr)
    print(f"whole run: {wall:.0f} s for {a.iterations} ticks (launch and stop included), exit {p.returncode}")
    for n in mem["start"]:
        print(f"{n:16s} RSS {mem['start'][n]:6.1f} MB at tick ~{a.early} -> {mem['end'].get(n, float('nan')):6.1f} MB "
              f"at tick ~{a.late + int(a.window * 300)}")
    if len(out) == 2:
        e, lt = out["early"], out["late"]
        print(f"window        ticks {e['ticks']} ({e['ms_per_tick']:.3f} ms/tick)   ticks {lt['ticks']} "
              f"({lt['ms_per_tick']:.3f} ms/tick)")
        for n in e["shares"]:
            print(f"{n}: CPU {e['cpu_ms_per_tick'][n]:.3f} -> {lt['cpu_ms_per_tick'][n]:.3f} ms/tick "
                  f"(late/early {lt['cpu_ms_per_tick'][n] / e['cpu_ms_per_tick'][n]:.2f})")
            cats = [c for c in profile.ORDER if c in e["shares"][n] or c in lt["shares"][n]]
            for c in cats:
                x, y = e["shares"][n].get(c, 0.0), lt["shares"][n].get(c, 0.0)
                print(f"    {c:14s} {100 * x:5.1f}% -> {100 * y:5.1f}% of the wall clock")
    if a.json:
        Path(a.json).write_text(json.dumps({"windows": out, "memory": mem, "wall_s": wall}))
    return p.returncode


if __name__ == "__main__":
    sys.exit(main())

"""``homeo-launch soak``: is a long run as cheap per tick, and as small, at its end as at its start?

Three parts, each optional:
- in-process: ``--iterations`` ticks (default 1,000,000) of the thesis simulation
  (``homeo_sim.runner.Simulation``, oracle recognition) in this process;
- ``--bus`` ticks of the graph's own code on an in-memory bus (no DDS, one process);
- the graph: ``--ticks`` ticks (default 200,000) of ``homeo-launch sim`` (Bayesian recognition,
  checkpoints every 100 ticks into a temporary folder), every node process watched from here.

For each process it prints the resident memory (VmRSS) at the start and at the end, the slope in
MB per 10,000 ticks (least squares over the samples after the first 10%: allocator and caches
settle first), and its CPU time per tick over the first and the last 10% of the ticks with their
ratio; for the whole run, the wall-clock time per tick at both ends. Targets (issue 12): slope below
0.1 MB per 10,000 ticks, last/first below 1.1. A benchmark, not a test: the figures depend on the
machine and its load.

On a shared machine the CPU time of a fixed piece of work is not fixed: it grows with the load (other
processes take the caches and the cores' shared parts). So each part also runs a reference, a process
doing the same small piece of Python work (JSON decode and encode, as a node does per message)
again and again with short sleeps, and prints its CPU time per piece over the same first and last 10%
of the ticks: a process's last/first divided by the reference's (``/ref``) is what is left once the
machine's drift is taken out, as far as a process feels the load as the reference does. ``--fresh M``
goes further: a fresh graph of M ticks runs beside the long one (another ROS domain) near its start
and again near its end, and the two graphs' CPU time per tick over the same minutes are compared
(docs/GRAPH.md, "Flat cost").
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
import time
from pathlib import Path

from homeo_record.procfs import rss_mb, stat_fields

SAMPLES = 40  # memory samples over a run


def cpu_s(pid: int | str = "self") -> float | None:
    """User + system CPU seconds of a process so far (on a shared machine a steadier measure of
    the cost of a tick than the wall clock)."""
    f = stat_fields(pid)
    try:
        return (int(f[11]) + int(f[12])) / os.sysconf("SC_CLK_TCK")
    except (TypeError, ValueError, IndexError):  # TypeError: no such process
        return None


def slope_per_10k(points: list[tuple[int, float]]) -> float:
    """Least-squares slope of (tick, MB) after the first 10% of the ticks, in MB per 10,000 ticks."""
    if not points:
        return float("nan")
    cut = points[-1][0] * 0.1
    pts = [p for p in points if p[0] >= cut] or points
    n = len(pts)
    if n < 2:
        return float("nan")
    mx = sum(p[0] for p in pts) / n
    my = sum(p[1] for p in pts) / n
    sxx = sum((p[0] - mx) ** 2 for p in pts)
    return sum((p[0] - mx) * (p[1] - my) for p in pts) / sxx * 1e4 if sxx else float("nan")


def per_tick_ends(times: list[tuple[int, float]], n: int) -> tuple[float, float]:
    """Seconds per tick over the first and the last tenth of ``n`` ticks, from (tick, time) samples:
    from the first sample to the first one at least n/10 ticks later, and from the last one at least
    n/10 ticks before the end to the end."""
    a, b, c, d = ends_index([t for t, _ in times], n)
    (t0, s0), (t1, s1), (t2, s2), (t3, s3) = times[a], times[b], times[c], times[d]
    return (s1 - s0) / max(1, t1 - t0), (s3 - s2) / max(1, t3 - t2)


REF_PIECE = json.dumps({"tick": 12345, "run": 0, "fields": {
    "drives": [0.125 * i for i in range(10)], "action": "approach", "intention": [0.1, 0.7, 0.2],
    "objects": {f"object_{i}": {"state": "idle", "near": i % 2 == 0, "p": [0.25, 0.5, 0.25]} for i in range(6)}}})
REF_PAUSE_S = 0.002  # between pieces: a node wakes up for each message; so does the reference


def reference_loop() -> None:
    """The reference process: pieces of fixed work, each followed by a short sleep; a line on stdin
    asks for "pieces CPU-seconds" on stdout; end of stdin ends it."""
    import select

    n = 0
    while True:
        for _ in range(2):
            m = json.loads(REF_PIECE)
            m["tick"] += n
            json.dumps(m, sort_keys=True)
        n += 1
        r, _, _ = select.select([sys.stdin], [], [], REF_PAUSE_S)
        if r:
            if not sys.stdin.readline():
                return
            sys.stdout.write(f"{n} {time.process_time()!r}\n")
            sys.stdout.flush()


class Reference:
    """The reference process, sampled as (tick, pieces, CPU seconds) alongside the processes watched."""

    def __init__(self):
        import subprocess

        self.proc = subprocess.Popen([sys.executable, "-c", "from homeo_ops.soak import reference_loop; "
                                      "reference_loop()"], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
                                     env=dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p)))
        self.samples: list[tuple[int, int, float]] = []

    def sample(self, tick: int) -> None:
        try:
            self.proc.stdin.write("\n")
            self.proc.stdin.flush()
            n, c = self.proc.stdout.readline().split()
            self.samples.append((tick, int(n), float(c)))
        except (OSError, ValueError):
            pass

    def __enter__(self) -> "Reference":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        try:
            self.proc.stdin.close()
            self.proc.wait(timeout=5)
        except Exception:  # noqa: BLE001 - it must not outlive the soak
            self.proc.kill()
            self.proc.wait()

    def summary(self, n: int) -> dict | None:
        """CPU seconds per piece over the first and the last tenth of ``n`` ticks."""
        if len(self.samples) < 2:
            return None
        a, b, c, d = ends_index([t for t, _, _ in self.samples], n)
        s = self.samples
        first = (s[b][2] - s[a][2]) / max(1, s[b][1] - s[a][1])
        last = (s[d][2] - s[c][2]) / max(1, s[d][1] - s[c][1])
        return {"cpu_s_per_piece_first": first, "cpu_s_per_piece_last": last,
                "last_over_first": last / first if first else float("nan")}


def ends_index(ticks: list[int], n: int) -> tuple[int, int, int, int]:
    """Indices of the samples ``per_tick_ends`` takes: the first tenth from a to b, the last from c to d."""
    w = max(1, n // 10)
    last = len(ticks) - 1
    b = next((i for i, t in enumerate(ticks) if t >= ticks[0] + w), last)
    c = next((i for i in range(last, -1, -1) if ticks[i] <= ticks[last] - w), 0)
    return 0, b, c, last


def soak_in_process(iterations: int, seed: int = 0, progress=None) -> dict:
    from homeo_sim.runner import RunConfig, Simulation, build_scenario

    cfg = RunConfig(iterations=iterations, seed=seed)
    sim = Simulation(build_scenario(cfg), cfg)
    every = max(1, iterations // 100)  # time samples: 1% steps; memory: SAMPLES
    mem_every = max(1, iterations // SAMPLES)
    times = [(0, time.perf_counter())]
    cpu = [(0, time.process_time())]
    mem = [(0, rss_mb())]

    def on_tick(t):
        k = t + 1
        if k % every == 0:
            times.append((k, time.perf_counter()))
            cpu.append((k, time.process_time()))
            ref.sample(k)
            if progress is not None:
                progress(k)
        if k % mem_every == 0:
            mem.append((k, rss_mb()))

    with Reference() as ref:
        ref.sample(0)
        times[0], cpu[0] = (0, time.perf_counter()), (0, time.process_time())
        res = sim.run(iterations, on_tick=on_tick)
    first, last = per_tick_ends(times, iterations)
    return {"ticks": iterations, "HSR": res.metrics["HSR"], "wall_s_per_tick": [first, last],
            "processes": {"homeo-sim (in-process)": _summary(mem, cpu, iterations)},
            "reference": ref.summary(iterations),
            "samples": {"time": times, "cpu": {"homeo-sim (in-process)": cpu}, "reference": ref.samples}}


def _summary(mem, cpu, n) -> dict:
    first, last = per_tick_ends(cpu, n)
    return {"rss_start_mb": mem[0][1], "rss_end_mb": mem[-1][1], "slope_mb_per_10k": slope_per_10k(mem),
            "cpu_s_per_tick_first": first, "cpu_s_per_tick_last": last,
            "last_over_first": last / first if first else float("nan")}


def soak_bus(ticks: int, seed: int = 0, progress=None) -> dict:
    """The graph's own code without DDS: the world host and the three robot nodes' hosts in this
    process (``homeo_ops.bus``, unshuffled), every message encoded, decoded and joined as the
    nodes do. Tells the code's cost apart from rclpy's and the machine's."""
    from homeo_decision.scenario import load_scenario
    from homeo_msgs_py.graph import BAYES
    from homeo_sim.world_backend import SimWorld

    from .bus import BusGraph

    sc = load_scenario()
    world = SimWorld(sc, {"seed": seed, "intention_learns": True})
    g = BusGraph(world, ticks, mode=BAYES, seed=seed)
    every, mem_every = max(1, ticks // 100), max(1, ticks // SAMPLES)
    with Reference() as ref:
        times, cpu, mem = [(0, time.perf_counter())], [(0, time.process_time())], [(0, rss_mb())]
        ref.sample(0)

        def on_round(k):
            if k >= times[-1][0] + every:
                times.append((k, time.perf_counter()))
                cpu.append((k, time.process_time()))
                ref.sample(k)
                world.status(False)  # the metrics, as the node publishes them
                if progress is not None:
                    progress(k)
            if k >= mem[-1][0] + mem_every:
                mem.append((k, rss_mb()))

        g.run(on_round)
    name = "graph code, no DDS (in-process)"
    return {"ticks": ticks, "HSR": world.status(True)["metrics"]["HSR"],
            "wall_s_per_tick": list(per_tick_ends(times, ticks)),
            "processes": {name: _summary(mem, cpu, ticks)}, "reference": ref.summary(ticks),
            "samples": {"time": times, "cpu": {name: cpu}, "reference": ref.samples}}


def _end_with_parent() -> None:
    """In a child before it runs: SIGTERM when the soak dies without ending it (no orphan graph)."""
    try:
        import ctypes
        import signal

        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass


class Fresh:
    """A short fresh graph run beside the long one (``homeo-launch soak --ticks N`` on another ROS
    domain, so the two graphs share the machine and nothing else), its samples kept."""

    def __init__(self, ticks: int, domain: int, tmp: str, name: str):
        import subprocess

        self.path = os.path.join(tmp, f"fresh-{name}.json")
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "homeo_launch.cli", "soak", "--iterations", "0", "--ticks", str(ticks), "--quiet",
             "--json", "--samples", self.path], stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE, text=True, preexec_fn=_end_with_parent,
            env=dict(os.environ, ROS_DOMAIN_ID=str(domain), PYTHONPATH=os.pathsep.join(p for p in sys.path if p)))

    def running(self) -> bool:
        return self.proc.poll() is None

    def result(self) -> dict | None:
        """The fresh run's graph samples (None if it failed); waits for it."""
        err = self.proc.communicate()[1]
        try:
            return json.loads(Path(self.path).read_text())["graph"]
        except (OSError, ValueError, KeyError):
            print(f"soak: the fresh graph failed: {err.strip()[-300:]}", file=sys.stderr)
            return None

    def stop(self) -> None:
        if self.running():
            self.proc.terminate()
            try:
                self.proc.communicate(timeout=30)
            except Exception:  # noqa: BLE001 - it must not outlive the soak
                self.proc.kill()
                self.proc.communicate()


def _at(pts: list, when: float) -> tuple[float, float] | None:
    """(count, CPU seconds) at the clock ``when`` from [(clock, count, CPU s)], interpolated; None outside."""
    import bisect

    clocks = [p[0] for p in pts]
    i = bisect.bisect_left(clocks, when)
    if not pts or i >= len(pts) or when < clocks[0]:
        return None
    if i == 0 or clocks[i] == when:
        return pts[i][1], pts[i][2]
    a, b = pts[i - 1], pts[i]
    f = (when - a[0]) / (b[0] - a[0])
    return a[1] + f * (b[1] - a[1]), a[2] + f * (b[2] - a[2])


def clocked(samples: dict) -> dict:
    """A graph part's samples as name -> [(clock, tick, CPU s)] (the reference: pieces, not ticks)."""
    clock = dict((k, w) for k, w in samples["time"])
    out = {name: [(clock[k], k, c) for k, c in pts if k in clock] for name, pts in samples["cpu"].items()}
    out["reference"] = [(clock[k], n, c) for k, n, c in samples.get("reference", []) if k in clock]
    return out


def side_by_side(long: dict, fresh: dict, skip: float = 0.2) -> dict:
    """Each process's CPU seconds per tick in the long run and in the fresh one over the same clock
    window: the fresh run's samples after its first ``skip`` (start-up) to its last before the final
    one. name -> {"long", "fresh", "ratio", "long_ticks"}; "seconds": the window's length."""
    long, fresh = clocked(long), clocked(fresh)
    clocks = [p[0] for p in fresh.get("homeo_sim", [])]
    if len(clocks) < 5:
        return {}
    own = [p[0] for p in long.get("homeo_sim", [])]
    if not own:
        return {}
    w0, w1 = max(clocks[int(len(clocks) * skip)], own[0]), min(clocks[-2], own[-1])
    if w1 <= w0:
        return {}
    out: dict = {"seconds": w1 - w0}
    for name, pts in fresh.items():
        if name not in long:
            continue
        a0, a1, b0, b1 = _at(long[name], w0), _at(long[name], w1), _at(pts, w0), _at(pts, w1)
        if None in (a0, a1, b0, b1) or a1[0] <= a0[0] or b1[0] <= b0[0]:
            continue
        ca, cb = (a1[1] - a0[1]) / (a1[0] - a0[0]), (b1[1] - b0[1]) / (b1[0] - b0[0])
        out[name] = {"long": ca, "fresh": cb, "ratio": ca / cb}
        if name != "reference":
            out[name]["long_ticks"] = [a0[0], a1[0]]
    return out


def soak_graph(ticks: int, seed: int = 0, progress=None, fresh: int = 0, fresh_domain: int | None = None) -> dict:
    """``fresh``: also run a fresh graph of that many ticks beside the long run near its start and
    again near its end (on ROS domain ``fresh_domain``), and compare the cost per tick over the same
    minutes (``side_by_side``): the long run's growth with the machine's drift taken out."""
    from homeo_launch.launch import run_graph, sim_options

    times: list = []
    mem: dict = {}
    cpu: dict = {}
    procs: dict = {}
    mem_every = max(1, ticks // SAMPLES)
    next_mem = [0]
    step = max(1, ticks // 200)

    def on_start(graph):
        procs.update({"homeo-launch": os.getpid()})
        procs.update(graph.pids())
        # a restarted node would have a new pid: the soak counts on none

    # the fresh runs: the early one once the long run is under way, the late one so that it ends
    # before the long run does (both graphs go at about the same pace; a graph takes seconds to start)
    fresh_at = {"early": max(100, ticks // 100), "late": max(ticks // 2, ticks - int(1.3 * fresh) - ticks // 50)}
    fresh_runs: dict = {}

    def on_status(tick, fields):
        now = time.perf_counter()
        if fresh and tmp_dir:
            for name, at in fresh_at.items():
                if name not in fresh_runs and tick >= at and not any(f.running() for f in fresh_runs.values()):
                    fresh_runs[name] = Fresh(fresh, fresh_domain, tmp_dir[0], name)
        # a bounded number of samples: the watcher must not grow with the run it watches
        if fields.get("state") in ("running", "finishing", "done") and (not times or tick >= times[-1][0] + step
                                                                        or fields.get("done")):
            times.append((tick, now))
            for name, pid in procs.items():
                c = cpu_s(pid)
                if c is not None:
                    cpu.setdefault(name, []).append((tick, c))
            ref.sample(tick)
        if tick >= next_mem[0] and procs:
            next_mem[0] = tick + mem_every
            for name, pid in procs.items():
                v = rss_mb(pid)
                if v is not None:
                    mem.setdefault(name, []).append((tick, v))
        if progress is not None:
            progress(tick)

    tmp_dir: list = []
    with Reference() as ref, tempfile.TemporaryDirectory(prefix="homeo-soak-") as tmp:
        tmp_dir.append(tmp)
        o = sim_options(ticks, seed=seed, data_dir=tmp, checkpoint_dir=os.path.join(tmp, "checkpoints"))
        try:
            status = run_graph(o, quiet=True, on_status=on_status, on_start=on_start)
            fresh_samples = {name: f.result() for name, f in fresh_runs.items()}
        finally:
            for f in fresh_runs.values():
                f.stop()
    samples = {"time": times, "cpu": cpu, "reference": ref.samples}
    out = {"ticks": ticks, "missed": status.get("missed"), "restarts": status.get("restarts", {}),
           "HSR": status["metrics"]["HSR"], "wall_s_per_tick": list(per_tick_ends(times, ticks)),
           "processes": {n: _summary(m, cpu[n], ticks) for n, m in mem.items() if n in cpu},
           "reference": ref.summary(ticks), "samples": samples}
    if fresh:
        out["fresh"] = {"ticks": fresh, **{name: side_by_side(samples, fs) if fs else {}
                                           for name, fs in fresh_samples.items()}}
        samples["fresh"] = fresh_samples
    return out


def format_part(title: str, part: dict) -> str:
    w0, w1 = part["wall_s_per_tick"]
    ref = part.get("reference")
    r = ref["last_over_first"] if ref else float("nan")
    lines = [f"{title}: {part['ticks']} ticks (HSR {part['HSR']:.3f}); wall clock per tick: first 10% "
             f"{w0 * 1e3:.4f} ms, last 10% {w1 * 1e3:.4f} ms (ratio {w1 / w0:.3f})",
             f"  {'process':32} {'RSS start':>10} {'RSS end':>9} {'MB/10k':>8} {'CPU ms/tick first':>18} "
             f"{'last':>7} {'last/first':>10} {'/ref':>6}"]
    for name, s in part["processes"].items():
        lines.append(f"  {name:32} {s['rss_start_mb']:9.1f}M {s['rss_end_mb']:8.1f}M {s['slope_mb_per_10k']:8.3f} "
                     f"{s['cpu_s_per_tick_first'] * 1e3:18.4f} {s['cpu_s_per_tick_last'] * 1e3:7.4f} "
                     f"{s['last_over_first']:10.3f} {s['last_over_first'] / r:6.3f}")
    if ref:
        lines.append(f"  {'reference (ms per piece of work)':32} {'':10} {'':9} {'':8} "
                     f"{ref['cpu_s_per_piece_first'] * 1e3:18.4f} {ref['cpu_s_per_piece_last'] * 1e3:7.4f} {r:10.3f}")
    if "fresh" in part:
        lines += format_fresh(part["fresh"])
    return "\n".join(lines)


def format_fresh(fr: dict) -> list[str]:
    e, la = fr.get("early", {}), fr.get("late", {})
    lines = [f"  beside a fresh graph of {fr['ticks']} ticks over the same minutes ({e.get('seconds', 0):.0f} s "
             f"early, {la.get('seconds', 0):.0f} s late): CPU ms/tick of the long run and of the fresh one",
             f"  {'process':16} {'early: long ticks':>18} {'long':>7} {'fresh':>7} {'ratio':>6} "
             f"{'late: long ticks':>17} {'long':>7} {'fresh':>7} {'ratio':>6} {'late/early':>10}"]

    def cols(x):
        if not x:
            return f"{'-':>18} {'':7} {'':7} {'':6}"
        t = f"{x['long_ticks'][0]:.0f}-{x['long_ticks'][1]:.0f}" if "long_ticks" in x else ""
        return f"{t:>18} {x['long'] * 1e3:7.4f} {x['fresh'] * 1e3:7.4f} {x['ratio']:6.3f}"

    for name in [n for n in e if n != "seconds"] + [n for n in la if n not in e and n != "seconds"]:
        a, b = e.get(name), la.get(name)
        q = f"{b['ratio'] / a['ratio']:10.3f}" if a and b else f"{'-':>10}"
        lines.append(f"  {name:16} {cols(a)} {cols(b)[1:]} {q}")
    return lines


def check_samples_file(path: str) -> None:
    """``--samples FILE`` can be written: not a directory, in a writable directory; else UserError."""
    from homeo_msgs_py.cli_args import UserError
    from homeo_msgs_py.schemas import one_line

    shown = one_line(path)
    if "\0" in path:
        raise UserError(f"--samples {shown}: not a file name")
    p = Path(path)
    if p.is_dir():
        raise UserError(f"--samples {shown} is a directory, not a file")
    parent = p.absolute().parent
    if not parent.is_dir() or not os.access(parent, os.W_OK | os.X_OK):
        raise UserError(f"--samples {shown}: {one_line(str(parent))} is not a writable directory")


def cmd_soak(a) -> int:
    from homeo_msgs_py.cli_args import UserError

    for opt, v in (("--iterations", a.iterations), ("--bus", a.bus), ("--ticks", a.ticks), ("--fresh", a.fresh)):
        if 0 < v < 100:
            raise UserError(f"{opt} {v}: at least 100 ticks (or 0 to skip)")
    if a.fresh and a.fresh * 10 > a.ticks:
        raise UserError(f"--fresh {a.fresh}: at most a tenth of --ticks (the late one must fit in the last tenth)")
    if a.fresh_domain is not None and a.fresh_domain > 232:
        raise UserError(f"--fresh-domain {a.fresh_domain}: a ROS domain id is at most 232")
    if a.samples:
        check_samples_file(a.samples)  # before the hours of the soak, not after them
    out = {}
    bar = None
    if not a.quiet:
        from tqdm import tqdm

        bar = tqdm(total=a.iterations + a.bus + a.ticks, unit="tick", file=sys.stderr, leave=False, desc="soak")
    base = [0]

    def progress(k):
        if bar is not None:
            bar.n = base[0] + k
            bar.refresh()

    try:
        if a.iterations:
            out["in_process"] = soak_in_process(a.iterations, a.seed, progress)
            base[0] = a.iterations
        if a.bus:
            out["bus"] = soak_bus(a.bus, a.seed, progress)
            base[0] += a.bus
        if a.ticks:
            domain = a.fresh_domain
            if domain is None:
                domain = (int(os.environ.get("ROS_DOMAIN_ID") or 0) + 1) % 233
            out["graph"] = soak_graph(a.ticks, a.seed, progress, fresh=a.fresh, fresh_domain=domain)
    finally:
        if bar is not None:
            bar.close()
    samples = {k: part.pop("samples") for k, part in out.items()}
    if a.samples:
        Path(a.samples).write_text(json.dumps(samples))
    if a.json:
        print(json.dumps(out))
        return 0
    print("target: slope < 0.1 MB per 10,000 ticks, last/first time per tick < 1.1 (per process: CPU time, "
          "steadier than the wall clock on a shared machine; the wall clock of the whole run above each table; "
          "/ref: last/first over the reference's, the same fixed work's CPU time over the same ticks, which "
          "takes out the machine's drift)")
    for key, title in (("in_process", "in-process"), ("bus", "graph code on an in-memory bus"), ("graph", "graph")):
        if key in out:
            print(format_part(title, out[key]))
    return 0


def add_parser(sub) -> None:
    from homeo_msgs_py.cli_args import int_at_least

    s = sub.add_parser("soak", help="memory and time per tick over a long run, in-process and as a graph")
    s.add_argument("--iterations", type=int_at_least(0), default=1_000_000,
                   help="in-process ticks (default 1,000,000; 0 = skip)")
    s.add_argument("--bus", type=int_at_least(0), default=0, metavar="TICKS",
                   help="also run the graph's code (driver, hosts, encode/decode, joins) on an in-memory bus in "
                        "this process for TICKS ticks: its cost without DDS (default 0 = skip)")
    s.add_argument("--ticks", type=int_at_least(0), default=200_000, help="graph ticks (default 200,000; 0 = skip)")
    s.add_argument("--fresh", type=int_at_least(0), default=0, metavar="TICKS",
                   help="also run a fresh graph of TICKS ticks beside the long one near its start and near its end, "
                        "and compare their CPU time per tick over the same minutes: the growth with the length of "
                        "the run, the machine's drift taken out (default 0 = skip)")
    s.add_argument("--fresh-domain", type=int_at_least(0), default=None, metavar="ID",
                   help="the fresh graph's ROS domain (default: this one's + 1)")
    s.add_argument("--seed", type=int_at_least(0), default=0)
    s.add_argument("--json", action="store_true")
    s.add_argument("--samples", metavar="FILE", help="also write the raw samples (tick, clock, each process's "
                   "CPU seconds; the reference's pieces and CPU seconds) to FILE as JSON")
    s.add_argument("--quiet", action="store_true", help="no progress bar")

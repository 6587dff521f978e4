"""``homeo-launch bench``: the graph's seconds per tick against the floor of rclpy itself.

The floor is a ring of processes that pass a message on with empty callbacks, with as
many publish-receive hops per tick as the graph has: per tick the graph delivers
observation -> intention, world -> drives, intention -> drives, outcome -> drives,
drives -> decision and action -> simulation, six hops (six publishes, six receptions).
For reference the bench also times a ring of four, the hops on the tick's critical path
(observation -> intention -> drives -> decision -> simulation). Graph and floors run in
the same invocation, alternating, and the medians are reported.
"""

from __future__ import annotations

import json
import os
import sys
import time

from homeo_msgs_py.graph import ORACLE

from ..launch import GraphOptions, run_graph, sim_options
from ..monitor import GraphError
from ..processes import Graph, NodeSpec, graph_env
from ..tap import Tap

HOPS = 6  # publish-receive hops per tick in the graph (see above)
CRITICAL_HOPS = 4


def floor_s_per_tick(iterations: int, hops: int = HOPS, bound_s: float = 120.0) -> float:
    # each process declares node name homeo_floor: renamed so that its parameters file applies
    specs = [NodeSpec(f"homeo_floor_{i}", "homeo_launch.ops.floor_chain",
                      {"index": i, "hops": hops, "iterations": iterations},
                      args=["--ros-args", "-r", f"__node:=homeo_floor_{i}"]) for i in range(hops)]
    graph = Graph(specs, graph_env(), auth=False)  # the floor: raw rclpy, nothing signed
    try:
        graph.start()
        end = time.monotonic() + bound_s
        head = graph.procs[specs[0].name]
        while head.poll() is None:
            dead = graph.dead()
            if dead and dead[0] != specs[0].name:
                raise GraphError(f"floor process {dead[0]} exited with code {dead[1]}: {graph.log_tail(dead[0])}")
            if time.monotonic() > end:
                raise GraphError(f"the floor chain did not finish within {bound_s:g} s")
            time.sleep(0.05)
        for line in graph.log_tail(specs[0].name, 50).splitlines():
            if line.startswith("{"):
                return json.loads(line)["s_per_tick"]
        raise GraphError(f"the floor chain printed no result: {graph.log_tail(specs[0].name)}")
    finally:
        graph.stop()
        graph.close()


def timed_run(o: GraphOptions, sinks=()) -> dict:
    """One graph run: wall seconds per tick (first tick to done), and CPU seconds per tick of the whole
    graph (every node process and the launcher with its tap) and of the launcher alone, counted between
    the first status of the running run and the final one, so start-up and shut-down are left out.
    CPU time is the steadier measure on a shared machine: other work stretches the wall clock."""
    from .soak import cpu_s

    pids: dict = {}
    marks: list = []  # (tick, {process: cpu seconds})

    def on_start(graph):
        pids.update(graph.pids(), launcher=os.getpid())

    def on_status(tick, fields):
        if fields.get("state") in ("running", "finishing", "done") and (not marks or fields.get("done")):
            marks.append((tick, {n: cpu_s(p) for n, p in pids.items()}))

    st = run_graph(o, quiet=True, sinks=sinks, on_start=on_start, on_status=on_status)
    out = {"s_per_tick": st["elapsed_s"] / o.iterations, "status": st}
    if len(marks) == 2 and marks[1][0] > marks[0][0]:
        (t0, c0), (t1, c1) = marks
        both = [n for n in c0 if c0[n] is not None and c1.get(n) is not None]
        out["cpu_s_per_tick"] = sum(c1[n] - c0[n] for n in both) / (t1 - t0)
        if "launcher" in both:
            out["launcher_cpu_s_per_tick"] = (c1["launcher"] - c0["launcher"]) / (t1 - t0)
    return out


def recorded_run(iterations: int, record_from: str = "writers") -> dict:
    """``timed_run`` of the graph recording every topic into a bag (``--record``, ``--record-from``), in a
    temporary folder; ``close_s``: what closing the bag took after the run (at the writers: the merge)."""
    import tempfile
    from pathlib import Path

    from homeo_decision.scenario import load_scenario

    from ..record import new_bag, run_info
    from ..tap import tapped_topics

    with tempfile.TemporaryDirectory(prefix="homeo-bench-bag-") as tmp:
        sink = new_bag(Path(tmp) / "bag", run_info("sim", iterations, 0, load_scenario(), {}), tapped_topics(),
                       record_from)
        o = sim_options(iterations, data_dir=str(Path(tmp) / "data"))
        try:
            out = timed_run(o, sinks=[sink])
        finally:
            t = time.monotonic()
            sink.close()
        out["close_s"] = time.monotonic() - t
        out["messages"] = sink.count
        return out


def spool_s_per_message(text: str, n: int = 20000) -> float:
    """What keeping one sent message costs its writer (``HomeoNode.spooled``: one append), timed alone:
    the work recording at the writers adds to the tick, which a shared machine's noise does not blur."""
    import tempfile

    from homeo_msgs_py.spool import SpoolWriter

    with tempfile.TemporaryDirectory(prefix="homeo-bench-spool-") as tmp:
        w = SpoolWriter(tmp, "bench")
        t = time.perf_counter()
        for _ in range(n):
            w.text("/homeo/drives", text)
        dt = time.perf_counter() - t
        w.close()
    return dt / n


def cmd_bench(args) -> int:
    """Alternate graph and floors ``rounds`` times; report the medians (this machine is shared
    and noisy: a single pair can be off by a factor of two either way)."""
    import statistics

    graph, oracle, floor, crit, rss, missed = [], [], [], [], [], 0
    recorded, unsigned, plain_runs, rec_runs = [], [], [], []
    for r in range(args.rounds):
        run = timed_run(sim_options(args.iterations))
        st = run["status"]
        plain_runs.append(run)
        graph.append(run["s_per_tick"])
        if getattr(args, "compare_auth", False):
            unsigned.append(run_graph(sim_options(args.iterations, auth=False),
                                      quiet=True)["elapsed_s"] / args.iterations)
        if getattr(args, "record", False):
            rec_runs.append(recorded_run(args.iterations, getattr(args, "record_from", "writers")))
            recorded.append(rec_runs[-1]["s_per_tick"])
        oracle.append(run_graph(sim_options(args.iterations, intention=ORACLE),
                                quiet=True)["elapsed_s"] / args.iterations)
        rss.append(st["rss_mb"])
        missed += st["missed"]
        floor.append(floor_s_per_tick(args.iterations, HOPS))
        crit.append(floor_s_per_tick(args.iterations, CRITICAL_HOPS))
        if not args.json:
            print(f"round {r + 1}: graph {graph[-1] * 1e3:.3f} ms/tick (oracle {oracle[-1] * 1e3:.3f}), floor {floor[-1] * 1e3:.3f} ms/tick "
                  f"({HOPS} hops), {crit[-1] * 1e3:.3f} ms/tick ({CRITICAL_HOPS} hops)", file=sys.stderr)
    g, f, c = statistics.median(graph), statistics.median(floor), statistics.median(crit)
    o = statistics.median(oracle)
    rec = {}
    if recorded:
        m = statistics.median(recorded)
        rec = {"recorded_s_per_tick": m, "record_ratio": m / g, "record_from": getattr(args, "record_from", "writers"),
               "record_ratio_per_round": [a / b for a, b in zip(recorded, graph)],
               "record_close_s": statistics.median(r["close_s"] for r in rec_runs),
               "recorded_messages_per_tick": statistics.median(r["messages"] for r in rec_runs) / args.iterations}
        if rec["record_from"] == "writers":
            # a typical message: the drives message of a run (the longest of the per-tick ones)
            per = spool_s_per_message(json.dumps({"schema": "homeo/drives", "version": 1, "run": 0, "tick": 500,
                                                  "stamp": 1.0, "drives": {f"N{i}": 12.5 for i in range(5)},
                                                  "intensities": {f"m{i}": 0.25 for i in range(4)},
                                                  "m_dom": "m0", "sig": "0" * 64}))
            rec.update(spool_s_per_message=per,
                       spool_share_of_tick=per * rec["recorded_messages_per_tick"] / g)
        # the CPU the whole graph spends a tick, without and with the recorder: less noisy than wall time
        pairs = [(a["cpu_s_per_tick"], b["cpu_s_per_tick"]) for a, b in zip(plain_runs, rec_runs)
                 if "cpu_s_per_tick" in a and "cpu_s_per_tick" in b]
        if pairs:
            rec.update(cpu_s_per_tick=statistics.median(a for a, _ in pairs),
                       cpu_s_per_tick_recording=statistics.median(b for _, b in pairs),
                       record_cpu_ratio_per_round=[b / a for a, b in pairs])
            rec["record_cpu_ratio"] = statistics.median(rec["record_cpu_ratio_per_round"])
        launcher = [(a["launcher_cpu_s_per_tick"], b["launcher_cpu_s_per_tick"]) for a, b in zip(plain_runs, rec_runs)
                    if "launcher_cpu_s_per_tick" in a and "launcher_cpu_s_per_tick" in b]
        if launcher:
            rec.update(launcher_cpu_s_per_tick=statistics.median(a for a, _ in launcher),
                       launcher_cpu_s_per_tick_recording=statistics.median(b for _, b in launcher))
    if unsigned:
        u = statistics.median(unsigned)
        rec.update(unsigned_s_per_tick=u, auth_ratio=g / u, unsigned_floor_ratio=u / f,
                   auth_ratio_per_round=[a / b for a, b in zip(graph, unsigned)])
    out = {**rec, "graph_s_per_tick": g, "floor_s_per_tick": f, "ratio": g / f, "rss_mb": max(rss),
           "hops": HOPS, "rounds": args.rounds, "ratio_per_round": [a / b for a, b in zip(graph, floor)],
           "critical_path_floor_s_per_tick": c, "critical_path_ratio": g / c,
           "oracle_graph_s_per_tick": o, "bayes_to_oracle": g / o}
    if args.json:
        print(json.dumps(out))
    else:
        print(f"graph (bayes), lockstep    : {g * 1e3:7.3f} ms/tick (median of {args.rounds} x {args.iterations} "
              f"ticks, {missed} missed)")
        print(f"floor, {HOPS} rclpy hops       : {f * 1e3:7.3f} ms/tick")
        print(f"ratio graph / floor        : {g / f:7.2f}  (target <= 2; per round: "
              f"{', '.join(f'{x:.2f}' for x in out['ratio_per_round'])})")
        print(f"critical path only, {CRITICAL_HOPS} hops: {c * 1e3:7.3f} ms/tick, ratio {g / c:.2f}")
        print(f"oracle intention graph     : {o * 1e3:7.3f} ms/tick; Bayesian recognition costs x{g / o:.2f}")
        print(f"graph resident memory      : {max(rss):7.0f} MiB (4 node processes)")
        if unsigned:
            print(f"graph without auth (--no-auth): {rec['unsigned_s_per_tick'] * 1e3:7.3f} ms/tick, ratio to the floor "
                  f"{rec['unsigned_floor_ratio']:.2f}; signed / unsigned {rec['auth_ratio']:.3f} (per round: "
                  f"{', '.join(f'{x:.3f}' for x in rec['auth_ratio_per_round'])})")
        if recorded:
            print(f"graph recording a bag      : {rec['recorded_s_per_tick'] * 1e3:7.3f} ms/tick; with / without --record "
                  f"{rec['record_ratio']:.3f} (target <= 1.10; per round: "
                  f"{', '.join(f'{x:.3f}' for x in rec['record_ratio_per_round'])}); recorded at the "
                  f"{rec['record_from']}, closing the bag took {rec['record_close_s']:.2f} s after the run")
            if "spool_s_per_message" in rec:
                print(f"recording at the writers   : {rec['spool_s_per_message'] * 1e6:.1f} us a message (timed alone) x "
                      f"{rec['recorded_messages_per_tick']:.1f} messages a tick = "
                      f"{rec['spool_share_of_tick'] * 100:.2f}% of the tick (the work it adds to the tick)")
            if "record_cpu_ratio" in rec:
                print(f"graph CPU a tick (all processes): {rec['cpu_s_per_tick'] * 1e3:7.3f} ms, recording "
                      f"{rec['cpu_s_per_tick_recording'] * 1e3:.3f} ms; with / without --record "
                      f"{rec['record_cpu_ratio']:.3f} (target <= 1.10; per round: "
                      f"{', '.join(f'{x:.3f}' for x in rec['record_cpu_ratio_per_round'])})")
            if "launcher_cpu_s_per_tick" in rec:
                print(f"launcher CPU a tick        : {rec['launcher_cpu_s_per_tick'] * 1e3:7.3f} ms, recording "
                      f"{rec['launcher_cpu_s_per_tick_recording'] * 1e3:.3f} ms (the tap's threads run at nice "
                      f"{Tap.NICE}, below the nodes)")
    return 0


def add_parser(sub) -> None:
    from homeo_msgs_py.cli_args import int_at_least

    b = sub.add_parser("bench", help="seconds per tick of the graph against a raw rclpy chain (the floor)")
    b.add_argument("--iterations", type=int_at_least(10), default=1000, help="ticks of each (default 1000)")
    b.add_argument("--rounds", type=int_at_least(1), default=3, help="alternating graph/floor pairs (default 3)")
    b.add_argument("--record", action="store_true",
                   help="also time the graph recording a bag, and print the ratio with / without recording")
    b.add_argument("--record-from", choices=("writers", "tap"), default="writers",
                   help="how the timed recording records (as sim --record-from; default writers)")
    b.add_argument("--compare-auth", action="store_true",
                   help="also time the graph without authentication (--no-auth), and print the ratio")
    b.add_argument("--json", action="store_true")

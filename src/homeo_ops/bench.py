"""``homeo-launch bench``: the graph's seconds per tick against the floor of rclpy itself.

The floor is a ring of six processes that pass a message on with empty callbacks: six publish-receive
hops a tick, as many as the graph delivered before the outcome of tick k-1 rode in the world and
observation of tick k (observation -> intention, world -> drives, intention -> drives, outcome -> drives,
drives -> decision, action -> world). The graph now delivers five (``homeo_msgs_py.graph``), four of
them on the critical path. The floor runs on the executor the graph runs on (``--executor``, rclpy's
EventsExecutor by default) and on the other, so the ratio compares like with like.
The graph runs as ``homeo-launch sim`` does by default: messages signed, checkpoints every 100
ticks (in a temporary folder). Graph and floor run in the same invocation, alternating, each
round printed, and the medians are reported. Comparisons in the same rounds, each pair in
alternating order: ``--compare-checkpoints`` (without checkpoints), ``--compare-auth`` (unsigned),
``--record``; and ``--oracle`` (the oracle recogniser), ``--critical-path`` (a ring of the four
hops on the tick's critical path: observation -> intention -> drives -> decision -> simulation).
``--profile`` samples one more run with py-spy and prints where each node's time goes
(``profile.py``).
"""

from __future__ import annotations

import json
import os
import sys
import time

from homeo_msgs_py.graph import ORACLE
from homeo_msgs_py.node_base import EXECUTOR

from homeo_launch.launch import GraphOptions, run_graph, sim_options
from . import profile
from homeo_launch.monitor import GraphError
from homeo_launch.processes import Graph, NodeSpec, graph_env
from homeo_record.tap import Tap

HOPS = 6  # publish-receive hops per tick in the graph (see above)
CRITICAL_HOPS = 4


def floor_s_per_tick(iterations: int, hops: int = HOPS, executor: str = EXECUTOR.default, bound_s: float = 120.0) -> float:
    # each process declares node name homeo_floor: renamed so that its parameters file applies
    specs = [NodeSpec(f"homeo_floor_{i}", "homeo_ops.floor_chain",
                      {"index": i, "hops": hops, "iterations": iterations, EXECUTOR.name: executor},
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


def timed_run(o: GraphOptions, sinks=(), sampler=None) -> dict:
    """One graph run: wall seconds per tick (first tick to done), and CPU seconds per tick of the whole
    graph (every node process and the launcher with its tap) and of the launcher alone, counted between
    the first status of the running run and the final one, so start-up and shut-down are left out.
    CPU time is the steadier measure on a shared machine: other work stretches the wall clock.
    ``sampler`` (``profile.Sampler``) samples the node processes over the same stretch: ``budgets``."""
    from .soak import cpu_s

    pids: dict = {}
    marks: list = []  # (tick, {process: cpu seconds})
    budgets: dict = {}

    def on_start(graph):
        pids.update(graph.pids(), launcher=os.getpid())

    def on_status(tick, fields):
        if fields.get("state") in ("running", "finishing", "done") and (not marks or fields.get("done")):
            marks.append((tick, {n: cpu_s(p) for n, p in pids.items()}))
            if sampler is not None:
                if len(marks) == 1:
                    sampler.start({n: p for n, p in pids.items() if n != "launcher"})
                if fields.get("done"):
                    budgets.update(sampler.stop())

    st = run_graph(o, quiet=True, sinks=sinks, on_start=on_start, on_status=on_status)
    out = {"s_per_tick": st["elapsed_s"] / o.iterations, "status": st, "budgets": budgets}
    if len(marks) == 2 and marks[1][0] > marks[0][0]:
        (t0, c0), (t1, c1) = marks
        both = [n for n in c0 if c0[n] is not None and c1.get(n) is not None]
        out["cpu_s_per_tick"] = sum(c1[n] - c0[n] for n in both) / (t1 - t0)
        out["node_cpu_s_per_tick"] = {n: (c1[n] - c0[n]) / (t1 - t0) for n in both if n != "launcher"}
        if "launcher" in both:
            out["launcher_cpu_s_per_tick"] = (c1["launcher"] - c0["launcher"]) / (t1 - t0)
    return out


def recorded_run(iterations: int, record_from: str = "writers") -> dict:
    """``timed_run`` of the graph recording every topic into a bag (``--record``, ``--record-from``), in a
    temporary folder; ``close_s``: what closing the bag took after the run (at the writers: the merge)."""
    import tempfile
    from pathlib import Path

    from homeo_decision.scenario import load_scenario

    from homeo_record.record import new_bag, run_info
    from homeo_record.tap import tapped_topics

    with tempfile.TemporaryDirectory(prefix="homeo-bench-bag-") as tmp:
        sink = new_bag(Path(tmp) / "bag", run_info("sim", iterations, 0, load_scenario(), {}), tapped_topics(),
                       record_from)
        o = bench_options(iterations, str(Path(tmp) / "data"))
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



def bench_options(iterations: int, data_dir: str, checkpoints: bool = True, **kw) -> GraphOptions:
    """The graph as ``homeo-launch sim`` runs it by default (signed; checkpoints every 100 ticks, here in
    a fresh folder of ``data_dir``), or without checkpoints; ``kw``: more ``GraphOptions`` (auth, intention)."""
    import tempfile

    os.makedirs(data_dir, exist_ok=True)
    ck = tempfile.mkdtemp(prefix="checkpoints-", dir=data_dir) if checkpoints else ""
    return sim_options(iterations, data_dir=data_dir, checkpoint_dir=ck, **kw)


# the graph runs of a round beside the graph: name -> (flag, bench_options' keywords); timed in turn with it
VARIANTS = {"no_checkpoints": ("compare_checkpoints", {"checkpoints": False}),
            "unsigned": ("compare_auth", {"auth": False}),
            "oracle": ("oracle", {"intention": ORACLE})}
TARGET_RATIO, TARGET_CHECKPOINTS = 1.3, 1.05


def pair_order(r: int, names: list) -> list:
    """The graph and its comparisons in round ``r``: the graph first in even rounds, last in odd ones, so
    a drift of the machine's load over the rounds weighs on both sides of every ratio alike."""
    return ["graph", *names] if r % 2 == 0 else [*names, "graph"]


def ratios(a: list, b: list) -> list:
    return [x / y for x, y in zip(a, b)]


def cmd_bench(args) -> int:
    """Alternate graph and floor ``rounds`` times; report the medians (this machine is shared
    and noisy: a single pair can be off by a factor of two either way)."""
    import statistics
    import tempfile

    if args.profile:
        try:
            profile.require_pyspy()
        except profile.ProfilerMissing as exc:
            print(f"homeo-launch bench: {exc}", file=sys.stderr)
            return 2
    med = statistics.median
    variants = [n for n, (flag, _) in VARIANTS.items() if getattr(args, flag, False)]
    s: dict = {n: [] for n in ["graph", *VARIANTS, "floor", "floor_other", "critical", "recorded"]}
    plain_runs, rec_runs, rss, missed = [], [], [], 0
    other = next(k for k in EXECUTOR.choices if k != args.executor)
    with tempfile.TemporaryDirectory(prefix="homeo-bench-") as tmp:
        for r in range(args.rounds):
            for name in pair_order(r, variants):
                run = timed_run(bench_options(args.iterations, tmp, executor=args.executor,
                                              **VARIANTS.get(name, ("", {}))[1]))
                s[name].append(run["s_per_tick"])
                if name == "graph":
                    plain_runs.append(run)
                    rss.append(run["status"]["rss_mb"])
                    missed += run["status"]["missed"]
            if args.record:
                rec_runs.append(recorded_run(args.iterations, args.record_from))
                s["recorded"].append(rec_runs[-1]["s_per_tick"])
            s["floor"].append(floor_s_per_tick(args.iterations, HOPS, args.executor))
            s["floor_other"].append(floor_s_per_tick(args.iterations, HOPS, other))
            if args.critical_path:
                s["critical"].append(floor_s_per_tick(args.iterations, CRITICAL_HOPS, args.executor))
            if not args.json:
                print(round_line(r, s), file=sys.stderr)
        try:
            prof = profiled(args, tmp) if args.profile else None
        except profile.ProfilerFailed as exc:  # py-spy could not read a node (ptrace not allowed, ...)
            print(f"homeo-launch bench: {exc}", file=sys.stderr)
            return 1
    g, f = med(s["graph"]), med(s["floor"])
    cpu = {n: med(r["node_cpu_s_per_tick"][n] for r in plain_runs) for n in plain_runs[0].get("node_cpu_s_per_tick", {})}
    out = {"graph_s_per_tick": g, "floor_s_per_tick": f, "ratio": g / f, "rss_mb": max(rss), "hops": HOPS,
           "executor": args.executor, "other_executor": other, "floor_other_s_per_tick": med(s["floor_other"]),
           "node_cpu_s_per_tick": cpu,
           "rounds": args.rounds, "iterations": args.iterations, "graph_s_per_tick_per_round": s["graph"],
           "floor_s_per_tick_per_round": s["floor"], "ratio_per_round": ratios(s["graph"], s["floor"]),
           "checkpoint_every": 100}
    if s["critical"]:
        c = med(s["critical"])
        out.update(critical_path_floor_s_per_tick=c, critical_path_ratio=g / c)
    if s["oracle"]:
        out.update(oracle_graph_s_per_tick=med(s["oracle"]), bayes_to_oracle=g / med(s["oracle"]))
    if s["no_checkpoints"]:
        per = ratios(s["graph"], s["no_checkpoints"])
        out.update(no_checkpoints_s_per_tick=med(s["no_checkpoints"]), checkpoint_ratio=med(per),
                   checkpoint_ratio_per_round=per, checkpoint_share=1 - 1 / med(per))
    if s["unsigned"]:
        per = ratios(s["graph"], s["unsigned"])
        u = med(s["unsigned"])
        out.update(unsigned_s_per_tick=u, auth_ratio=med(per), unsigned_floor_ratio=u / f, auth_ratio_per_round=per,
                   auth_share=1 - 1 / med(per))
    if rec_runs:
        out.update(record_summary(args, s["recorded"], s["graph"], plain_runs, rec_runs))
    if prof is not None:
        out["profile"] = prof
    if args.json:
        print(json.dumps(out))
    else:
        print_summary(out, missed, prof)
    return 0


def round_line(r: int, s: dict) -> str:
    g, f = s["graph"][-1], s["floor"][-1]
    text = f"round {r + 1}: graph {g * 1e3:.3f} ms/tick, floor {f * 1e3:.3f} ms/tick ({HOPS} hops): ratio {g / f:.2f}"
    for name, what in (("no_checkpoints", "checkpoints off"), ("unsigned", "unsigned"), ("oracle", "oracle"),
                       ("recorded", "recording")):
        if s[name]:
            text += f"; {what} {s[name][-1] * 1e3:.3f} (x{g / s[name][-1]:.3f})"
    if s["critical"]:
        text += f"; {CRITICAL_HOPS} hops {s['critical'][-1] * 1e3:.3f}"
    return text


def print_summary(out: dict, missed: int, prof) -> None:
    g, f, n = out["graph_s_per_tick"], out["floor_s_per_tick"], out["rounds"]
    per = lambda key, fmt=".2f": ", ".join(f"{x:{fmt}}" for x in out[key])  # noqa: E731
    print(f"graph (bayes), lockstep    : {g * 1e3:7.3f} ms/tick (median of {n} x {out['iterations']} ticks, {missed} "
          f"missed; signed, checkpoints every {out['checkpoint_every']} ticks)")
    print(f"floor, {HOPS} rclpy hops       : {f * 1e3:7.3f} ms/tick on the graph's executor ({out['executor']}); "
          f"{out['floor_other_s_per_tick'] * 1e3:.3f} ms/tick on {out['other_executor']}")
    print(f"ratio graph / floor        : {out['ratio']:7.2f}  (target <= {TARGET_RATIO}; per round: {per('ratio_per_round')})")
    if out["node_cpu_s_per_tick"]:
        print("each node's CPU a tick     : " + ", ".join(f"{n} {c * 1e3:.3f} ms" for n, c in
                                                          sorted(out["node_cpu_s_per_tick"].items())))
    if "critical_path_ratio" in out:
        print(f"critical path only, {CRITICAL_HOPS} hops: {out['critical_path_floor_s_per_tick'] * 1e3:7.3f} ms/tick, "
              f"ratio {out['critical_path_ratio']:.2f}")
    if "bayes_to_oracle" in out:
        print(f"oracle intention graph     : {out['oracle_graph_s_per_tick'] * 1e3:7.3f} ms/tick; Bayesian recognition "
              f"costs x{out['bayes_to_oracle']:.2f}")
    print(f"graph resident memory      : {out['rss_mb']:7.0f} MiB (4 node processes)")
    if "checkpoint_ratio" in out:
        print(f"graph without checkpoints  : {out['no_checkpoints_s_per_tick'] * 1e3:7.3f} ms/tick; on / off "
              f"{out['checkpoint_ratio']:.3f} (target <= {TARGET_CHECKPOINTS}; per round: "
              f"{per('checkpoint_ratio_per_round', '.3f')}): checkpoints' share of the tick "
              f"{100 * out['checkpoint_share']:.1f}%")
    if "auth_ratio" in out:
        print(f"graph without auth (--no-auth): {out['unsigned_s_per_tick'] * 1e3:7.3f} ms/tick, ratio to the floor "
              f"{out['unsigned_floor_ratio']:.2f}; signed / unsigned {out['auth_ratio']:.3f} (per round: "
              f"{per('auth_ratio_per_round', '.3f')}): signing's share of the tick {100 * out['auth_share']:.1f}%")
    if "recorded_s_per_tick" in out:
        print_record(out)
    if prof is not None:
        print(f"where each node's time goes (py-spy, {prof['rate_hz']} Hz, one run of {prof['iterations']} ticks at "
              f"{prof['ms_per_tick']:.3f} ms/tick; defaults as above):")
        print(profile.table(prof["ms"], prof["ms_per_tick"]))


PROFILE_TICKS = 2000  # at least: sampling starts with the first run status the launcher hears (0.25 s apart)


def profiled(args, tmp: str) -> dict:
    """One more graph run (the defaults) sampled by py-spy: each node's milliseconds a tick by category."""
    n = max(args.iterations, PROFILE_TICKS)
    sampler = profile.Sampler()
    try:
        run = timed_run(bench_options(n, tmp, executor=args.executor), sampler=sampler)
    finally:
        sampler.close()
    ms_tick = run["s_per_tick"] * 1e3
    return {"ms_per_tick": ms_tick, "iterations": n, "rate_hz": sampler.rate,
            "ms": profile.per_tick(run["budgets"], ms_tick)}


def record_summary(args, recorded: list, graph: list, plain_runs: list, rec_runs: list) -> dict:
    import statistics

    med = statistics.median
    m, g = med(recorded), med(graph)
    rec = {"recorded_s_per_tick": m, "record_ratio": m / g, "record_from": args.record_from,
           "record_ratio_per_round": ratios(recorded, graph),
           "record_close_s": med(r["close_s"] for r in rec_runs),
           "recorded_messages_per_tick": med(r["messages"] for r in rec_runs) / args.iterations}
    if rec["record_from"] == "writers":
        # a typical message: the drives message of a run (the longest of the per-tick ones)
        per = spool_s_per_message(json.dumps({"schema": "homeo/drives", "version": 1, "run": 0, "tick": 500,
                                              "stamp": 1.0, "drives": {f"N{i}": 12.5 for i in range(5)},
                                              "intensities": {f"m{i}": 0.25 for i in range(4)},
                                              "m_dom": "m0", "sig": "0" * 64}))
        rec.update(spool_s_per_message=per, spool_share_of_tick=per * rec["recorded_messages_per_tick"] / g)
    # the CPU the whole graph spends a tick, without and with the recorder: less noisy than wall time
    pairs = [(a["cpu_s_per_tick"], b["cpu_s_per_tick"]) for a, b in zip(plain_runs, rec_runs)
             if "cpu_s_per_tick" in a and "cpu_s_per_tick" in b]
    if pairs:
        rec.update(cpu_s_per_tick=med(a for a, _ in pairs), cpu_s_per_tick_recording=med(b for _, b in pairs),
                   record_cpu_ratio_per_round=[b / a for a, b in pairs])
        rec["record_cpu_ratio"] = med(rec["record_cpu_ratio_per_round"])
    launcher = [(a["launcher_cpu_s_per_tick"], b["launcher_cpu_s_per_tick"]) for a, b in zip(plain_runs, rec_runs)
                if "launcher_cpu_s_per_tick" in a and "launcher_cpu_s_per_tick" in b]
    if launcher:
        rec.update(launcher_cpu_s_per_tick=med(a for a, _ in launcher),
                   launcher_cpu_s_per_tick_recording=med(b for _, b in launcher))
    return rec


def print_record(rec: dict) -> None:
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


def add_parser(sub) -> None:
    from homeo_msgs_py.cli_args import int_at_least

    b = sub.add_parser("bench", help="seconds per tick of the graph against a raw rclpy chain (the floor)")
    b.add_argument("--iterations", type=int_at_least(10), default=1000, help="ticks of each (default 1000)")
    b.add_argument("--rounds", type=int_at_least(1), default=3, help="alternating graph/floor pairs (default 3)")
    b.add_argument("--compare-checkpoints", action="store_true",
                   help="also time the graph without checkpoints (--no-checkpoints) in each round, and print the "
                        "ratio and the checkpoints' share of the tick")
    b.add_argument("--compare-auth", action="store_true",
                   help="also time the graph without authentication (--no-auth), and print the ratio")
    b.add_argument("--oracle", action="store_true", help="also time the graph with the oracle recogniser")
    b.add_argument("--critical-path", action="store_true",
                   help=f"also time a floor of the {CRITICAL_HOPS} hops on the tick's critical path")
    b.add_argument("--record", action="store_true",
                   help="also time the graph recording a bag, and print the ratio with / without recording")
    b.add_argument("--record-from", choices=("writers", "tap"), default="writers",
                   help="how the timed recording records (as sim --record-from; default writers)")
    b.add_argument("--profile", action="store_true",
                   help="also sample one run with py-spy and print where each node's time goes in a tick (decode, "
                        f"HMAC check, join, core step, encode, sign, publish, checkpoint, waiting...); needs "
                        f"{profile.INSTALL}")
    from homeo_msgs_py.params import add_flag

    add_flag(b, EXECUTOR, default=EXECUTOR.default)
    b.add_argument("--json", action="store_true")

"""``homeo-launch watch``: the launcher's part of a graph that ROS 2's launch system started.

``ros2 launch homeo_robot sim.launch.py`` starts the four nodes and this command beside them
(``ros_launch.py``): it follows the world's run status with a progress bar, and at the end prints
what ``homeo-launch sim`` or ``pepper`` prints, saves the Q-table asked for, writes the recording
(the writers' spools, merged into the bag), and exits; the launch file then shuts the graph down.
Ctrl-C (ros2 launch passes it on) prints the run so far, with its real tick count and time.
"""

from __future__ import annotations

import json
import signal
import sys
from pathlib import Path

from homeo_msgs_py.cli_args import int_at_least, setting, user_path
from homeo_msgs_py.graph import SEED_MAX, TICKS_MAX

from .launch import PROG, save_q
from .options import _namespace_arg


def add_parser(sub) -> None:
    w = sub.add_parser("watch", help="follow a graph that ros2 launch started: its progress, then its result "
                                     "(the launch files run it)")
    w.add_argument("--world", default="sim", help="the world the graph runs (how its result reads)")
    w.add_argument("--iterations", type=int_at_least(0, TICKS_MAX), default=0, help="the run's ticks, for progress")
    w.add_argument("--seed", type=int_at_least(0, SEED_MAX), default=0)
    w.add_argument("--scenario", metavar="FILE", type=user_path, default=None)
    w.add_argument("--set", metavar="KEY=VALUE", type=setting, action="append", default=[])
    w.add_argument("--namespace", type=_namespace_arg, default="", metavar="NS")
    w.add_argument("--save-q", metavar="FILE", type=user_path, help="ask the decision node to save its Q-table at the end")
    w.add_argument("--record-spool", metavar="DIR", type=user_path,
                   help="the writers' spool folder of a --record: merged into its bag at the end")
    w.add_argument("--json", action="store_true", help="print the result as JSON")
    w.add_argument("--quiet", action="store_true", help="no progress bar")


def cmd_watch(a) -> int:
    from homeo_decision.scenario import load_scenario
    from homeo_msgs_py.auth import load_signer

    from .monitor import Monitor, RunFollower
    from .sim import progress_bar

    sc = load_scenario(a.scenario, overrides=dict(a.set))
    mon = Monitor(a.namespace, load_signer())
    bar = progress_bar(a.quiet, a.iterations)
    run, interrupted = RunFollower(), False
    last = run.last
    try:
        while not last.get("done"):
            mon.spin(0.05)
            if run.take(mon.status):
                bar(mon.status.tick, mon.status.fields)
        if a.save_q:
            ok, msg = save_q(mon, timeout=10.0)
            if not ok:
                print(f"{PROG}: warning: the Q-table was not saved: {msg}", file=sys.stderr)
    except KeyboardInterrupt:
        interrupted = True
        for sig in (signal.SIGINT, signal.SIGTERM):  # ros2 launch passes the terminal's Ctrl-C on: one is enough
            signal.signal(sig, signal.SIG_IGN)
    finally:
        bar.close()
        mon.close()
        if a.record_spool:
            merge_recording(Path(a.record_spool))
    last["elapsed_s"] = run.elapsed_s()
    if a.world == "pepper":
        return print_log(last, a.json)
    from .sim import print_result

    print_result(last, interrupted, sc, a.seed, a.iterations, a.json)
    return 0  # stopped or done: either is the end the user asked for


def print_log(status: dict, as_json: bool) -> int:
    """A robot world's result: its interaction log (the run status's ``extra.log``)."""
    from .pepper import print_log_table

    log = (status.get("extra") or {}).get("log") or []
    if as_json:
        print(json.dumps({"interactions": len(log), "missed": status.get("missed", 0), "log": log}, indent=1))
    else:
        print_log_table(log, status.get("missed", 0))
    return 0


def merge_recording(folder: Path) -> None:
    """The spool folder a launch file made (its manifest names the bag) merged into the bag; kept,
    with one line, when that cannot be done (``homeo-launch recover`` tries again)."""
    from .record import NotRecovered, read_manifest, spools_to_bag

    try:
        bag, _, info, topics = read_manifest(folder)
        spools_to_bag(folder, bag, info, topics)
    except (NotRecovered, OSError, ValueError) as exc:
        print(f"{PROG}: the recording stays: {exc}", file=sys.stderr)  # exc names the folder
        return
    print(f"{PROG}: recorded {bag}", file=sys.stderr)

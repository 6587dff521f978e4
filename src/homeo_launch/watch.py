"""``homeo-launch watch``: the launcher's part of a graph that ROS 2's launch system started.

``ros2 launch homeo_robot world.launch.py world:=NAME`` starts the four nodes and this command beside
them (``ros_launch.py``): it follows the world's run status as ``homeo-launch NAME`` does, and at the
end prints what it prints (the world's result), saves the Q-table asked for, writes the recording
(the writers' spools, merged into the bag), and exits; the launch file then shuts the graph down.
Ctrl-C (ros2 launch passes it on) prints the run so far, with its real tick count and time.
"""

from __future__ import annotations

import json
import signal
import sys
from pathlib import Path

from homeo_decision.world_api import ITERATIONS, SEED
from homeo_msgs_py.cli_args import setting, user_path
from homeo_msgs_py.params import add_flag

from .launch import PROG, save_q
from .options import _namespace_arg


def add_parser(sub) -> None:
    w = sub.add_parser("watch", help="follow a graph that ros2 launch started: its progress, then its result "
                                     "(the launch files run it)")
    w.add_argument("--world", default="sim", help="the world the graph runs (how its result reads)")
    w.add_argument("--setting", type=_setting, default={}, metavar="JSON",
                   help="the launch's setting for the world's result: {intention, learning, values}")
    add_flag(w, ITERATIONS, default=0)
    add_flag(w, SEED, default=0)
    w.add_argument("--scenario", metavar="FILE", type=user_path, default=None)
    w.add_argument("--set", metavar="KEY=VALUE", type=setting, action="append", default=[])
    w.add_argument("--namespace", type=_namespace_arg, default="", metavar="NS")
    w.add_argument("--save-q", metavar="FILE", type=user_path, help="ask the decision node to save its Q-table at the end")
    w.add_argument("--record-spool", metavar="DIR", type=user_path,
                   help="the writers' spool folder of a --record: merged into its bag at the end")
    w.add_argument("--json", action="store_true", help="print the result as JSON")
    w.add_argument("--quiet", action="store_true", help="no progress bar")


def _setting(text: str) -> dict:
    import argparse

    try:
        v = json.loads(text)
    except ValueError:
        v = None
    if not isinstance(v, dict) or set(v) - {"intention", "learning", "values"} \
            or not all(isinstance(v.get(k, {}), dict) for k in ("learning", "values")):
        raise argparse.ArgumentTypeError("must be a JSON object of intention, learning and values")
    return v


def cmd_watch(a) -> int:
    from homeo_decision.scenario import load_scenario
    from homeo_decision.world_api import world_class
    from homeo_msgs_py.auth import load_signer

    from .front import Progress, print_result
    from .monitor import Monitor, RunFollower

    cls = world_class(a.world)
    sc = load_scenario(a.scenario, overrides=dict(a.set))
    mon = Monitor(a.namespace, load_signer())
    show = Progress(cls, a.quiet or a.json, a.iterations)
    run, interrupted = RunFollower(), False
    last = run.last
    try:
        while not last.get("done"):
            mon.spin(0.05)
            if run.take(mon.status):
                show(mon.status.tick, mon.status.fields)
        if a.save_q:
            ok, msg = save_q(mon, timeout=10.0)
            if not ok:
                print(f"{PROG}: warning: the Q-table was not saved: {msg}", file=sys.stderr)
    except KeyboardInterrupt:
        interrupted = True
        for sig in (signal.SIGINT, signal.SIGTERM):  # ros2 launch passes the terminal's Ctrl-C on: one is enough
            signal.signal(sig, signal.SIG_IGN)
    finally:
        show.close()
        mon.close()
        if a.record_spool:
            merge_recording(Path(a.record_spool))
    last["elapsed_s"] = run.elapsed_s()
    setting = dict(a.setting, seed=a.seed, iterations=a.iterations, interrupted=interrupted)
    setting.setdefault("intention", next(iter(cls.INTENTIONS.values())))
    print_result(cls, sc, last, setting, a.json, bounded=False)
    return 0  # stopped or done: either is the end the user asked for


def merge_recording(folder: Path) -> None:
    """The spool folder a launch file made (its manifest names the bag) merged into the bag; kept,
    with one line, when that cannot be done (``homeo-launch recover`` tries again)."""
    from homeo_record.record import NotRecovered, read_manifest, spools_to_bag

    try:
        bag, _, info, topics = read_manifest(folder)
        spools_to_bag(folder, bag, info, topics)
    except (NotRecovered, OSError, ValueError) as exc:
        print(f"{PROG}: the recording stays: {exc}", file=sys.stderr)  # exc names the folder
        return
    print(f"{PROG}: recorded {bag}", file=sys.stderr)

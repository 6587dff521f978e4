"""``homeo-launch``: the node graph with any world of the registry, from one command.

    homeo-launch sim | pepper | day | <any registered world> [options]   the graph (``launch.py``)
    homeo-launch watch [options]       follow a graph ros2 launch started (``watch.py``, ``ros_launch.py``)
    homeo-launch bench | soak | recover [options]                        operations (``ops/``)

Each world of the ``homeo_robot.worlds`` registry is a command: the Pepper has its own front end
(``pepper.py``: a stand-in robot, the interaction log, the field test), every other world the
simulation's (``sim.py``: its parameters as flags, Table 4.5's metrics at the end).
"""

from __future__ import annotations

import argparse
import sys

from homeo_decision.qtable_io import QTableError
from homeo_decision.scenario import ScenarioError
from homeo_decision.world_api import WorldConfigError, registered
from homeo_msgs_py.cli_args import Parser, run_command

from .launch import PROG
from .monitor import GraphError


def build_parser() -> argparse.ArgumentParser:
    from . import pepper, sim, watch
    from .ops import bench, recover, soak

    ap = Parser(prog=PROG, description="Start the homeostatic robot's ROS 2 node graph.")
    sub = ap.add_subparsers(dest="cmd", required=True, parser_class=Parser)
    worlds = registered()
    for name in sorted(worlds, key=lambda n: (n != "sim", n)):  # sim first: the default world
        if name == "pepper":
            pepper.add_parser(sub)
        else:
            sim.add_parser(sub, name, worlds[name].load())
    watch.add_parser(sub)
    bench.add_parser(sub)
    soak.add_parser(sub)
    recover.add_parser(sub)
    return ap


def _sigterm_as_interrupt(signum, frame):
    raise KeyboardInterrupt  # `kill` or a CI timeout stops the nodes as Ctrl-C does


def main(argv=None) -> int:
    import signal

    signal.signal(signal.SIGTERM, _sigterm_as_interrupt)
    signal.signal(signal.SIGHUP, _sigterm_as_interrupt)  # a closed terminal: stop, save and clean up too
    # Ctrl-C however the launcher was started: a script's background job inherits SIGINT ignored
    signal.signal(signal.SIGINT, signal.default_int_handler)

    def command() -> int:
        args = build_parser().parse_args(argv)
        if args.cmd == "pepper":
            from .pepper import cmd_pepper

            return cmd_pepper(args)
        if args.cmd == "watch":
            from .watch import cmd_watch

            return cmd_watch(args)
        if args.cmd in ("bench", "soak", "recover"):
            from importlib import import_module

            return getattr(import_module(f".ops.{args.cmd}", __package__), f"cmd_{args.cmd}")(args)
        from .sim import cmd_sim

        return cmd_sim(args)

    return run_command(PROG, command, (ScenarioError, QTableError, WorldConfigError), (GraphError,))


if __name__ == "__main__":
    sys.exit(main())

"""``homeo-launch``: the node graph with any world of the registry, from one command.

    homeo-launch NAME [options]        the graph with the world NAME of the registry (``front.py``)
    homeo-launch watch [options]       follow a graph ros2 launch started (``watch.py``, ``ros_launch.py``)
    homeo-launch bench | soak | ...    the commands other packages add (entry points ``homeo_robot.commands``:
                                       the operations tools of ``homeo_ops``)
"""

from __future__ import annotations

import argparse
import sys

from homeo_decision.qtable_io import QTableError
from homeo_decision.scenario import ScenarioError
from homeo_decision.world_api import WorldConfigError, registered, world_class
from homeo_msgs_py.cli_args import Parser, run_command

from .launch import PROG
from .monitor import GraphError

COMMANDS = "homeo_robot.commands"  # name -> a module with add_parser(sub) and cmd_NAME(args)


def commands() -> dict:
    from importlib.metadata import entry_points

    return {ep.name: ep for ep in entry_points(group=COMMANDS)}


def build_parser() -> argparse.ArgumentParser:
    from . import front, watch

    ap = Parser(prog=PROG, description="Start the homeostatic robot's ROS 2 node graph.")
    sub = ap.add_subparsers(dest="cmd", required=True, parser_class=Parser)
    for name in sorted(registered(), key=lambda n: (n != "sim", n)):  # sim first: the default world
        try:
            front.add_parser(sub, name, world_class(name))
        except WorldConfigError as exc:  # another package's world that does not load: said, not fatal
            sub.add_parser(name, help=f"(does not load: {exc})").set_defaults(broken=str(exc))
    watch.add_parser(sub)
    for name, ep in sorted(commands().items()):
        ep.load().add_parser(sub)
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
        if getattr(args, "broken", None):
            raise WorldConfigError(args.broken)
        if args.cmd == "watch":
            from .watch import cmd_watch

            return cmd_watch(args)
        if args.cmd in commands():
            return getattr(commands()[args.cmd].load(), f"cmd_{args.cmd}")(args)
        from .front import cmd_world

        return cmd_world(args)

    return run_command(PROG, command, (ScenarioError, QTableError, WorldConfigError), (GraphError,))


if __name__ == "__main__":
    sys.exit(main())

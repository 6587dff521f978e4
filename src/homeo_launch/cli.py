"""``homeo-launch``: the node graphs from one command (sim, pepper, bench); see ``sim.py``."""

from __future__ import annotations

import argparse
import sys

from homeo_decision.qtable_io import QTableError
from homeo_decision.scenario import ScenarioError
from homeo_msgs_py.cli_args import Parser, UserError, float_in, int_at_least, run_command, setting
from homeo_msgs_py.graph import BAYES, INTENTION_MODES, SEED_MAX, TICKS_MAX
from homeo_msgs_py.learning import DOD, XI, add_learning_flags

from .durable_args import add_durable_options
from .live_args import add_live_options
from .monitor import GraphError
from .processes import add_graph_options
from .sim import PROG, cmd_sim


# -- command line -----------------------------------------------------------------------------
def build_parser() -> argparse.ArgumentParser:
    ap = Parser(prog=PROG, description="Start the homeostatic robot's ROS 2 node graph.")
    sub = ap.add_subparsers(dest="cmd", required=True, parser_class=Parser)
    s = sub.add_parser("sim", help="the graph with the simulated world and human; prints Table 4.5's metrics")
    s.add_argument("--iterations", type=int_at_least(0, TICKS_MAX), default=5000, help="ticks (0 = until Ctrl-C; default 5000)")
    s.add_argument("--rate", type=float_in(0.0, 1000.0), default=0.0, help="ticks per second (0 = as fast as lockstep allows)")
    s.add_argument("--seed", type=int_at_least(0, SEED_MAX), default=0, help="seed of every component (default 0)")
    add_learning_flags(s, (DOD, XI), help_extra=" (default: the scenario's)")
    s.add_argument("--no-pseudo", action="store_true", help="switch off pseudo updates (Eq 3.23)")
    s.add_argument("--intention", choices=INTENTION_MODES, default=BAYES,
                   help="recognise the intention with the Bayesian network (default) or observe it (the thesis's "
                        "simulation; what homeo-sim run does by default)")
    s.add_argument("--scenario", metavar="FILE", default=None, help="scenario JSON (default: the thesis scenario)")
    s.add_argument("--set", metavar="KEY=VALUE", type=setting, action="append", default=[],
                   help="override an open choice of the scenario")
    s.add_argument("--load-q", metavar="FILE", help="start from a saved Q-table")
    s.add_argument("--save-q", metavar="FILE", help="save the Q-table at the end")
    s.add_argument("--trace", metavar="FILE", help="the simulation writes one JSON line per tick")
    s.add_argument("--action-timeout", type=float_in(0.01, 3600.0), default=5.0,
                   help="seconds to wait for an action before the tick counts as none (default 5)")
    s.add_argument("--human", choices=("sim", "person"), default="sim",
                   help="who plays the human: the simulated one (default) or a person sending JSON on "
                        "/homeo/human_input (see the README)")
    s.add_argument("--human-timeout", type=float_in(0.01, 3600.0), default=10.0,
                   help="seconds a tick waits for the person before it counts as no intention (default 10)")
    s.add_argument("--log-dir", metavar="DIR", help="keep each node's log here (default: a temporary directory)")
    s.add_argument("--json", action="store_true", help="print the metrics as homeo-sim run --json does")
    s.add_argument("--quiet", action="store_true", help="no progress bar")
    add_live_options(s)
    add_graph_options(s)
    add_durable_options(s, "sim")
    from .pepper import add_parser as add_pepper

    add_pepper(sub)
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
    from .soak import add_parser as add_soak

    add_soak(sub)
    from .recover import add_parser as add_recover

    add_recover(sub)
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
        if args.cmd == "sim":
            return cmd_sim(args)
        if args.cmd == "pepper":
            from .pepper import cmd_pepper

            return cmd_pepper(args)
        if args.cmd == "soak":
            from .soak import cmd_soak

            return cmd_soak(args)
        if args.cmd == "recover":
            from .recover import cmd_recover

            return cmd_recover(args)
        from .bench import cmd_bench

        return cmd_bench(args)

    return run_command(PROG, command, (ScenarioError, QTableError), (GraphError,))

if __name__ == "__main__":
    sys.exit(main())

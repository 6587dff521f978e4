"""``homeo-launch sim`` (and ``homeo-launch day``, and any world of the registry but the Pepper): the
graph with that world, a progress bar, and at the end Table 4.5's metrics of the run (the JSON of
``homeo-sim run`` with ``--json``).

    homeo-launch sim [--iterations N (0 = until Ctrl-C)] [--rate HZ] [--seed S] [--dod X] [--xi X]
                     [--no-pseudo] [--intention oracle|bayes] [--scenario FILE] [--set KEY=VALUE]
                     [--load-q FILE] [--save-q FILE] [--trace FILE] [--human sim|person] [--json] ...
    homeo-launch day [--day FILE] ...              the simulated home through a scripted day

The world's own parameters become flags (``--human``, ``--day``: ``WorldBackend.PARAMS``); the run
is ``launch.run_graph``'s.
"""

from __future__ import annotations

import json
import sys

from homeo_msgs_py.cli_args import float_in, int_at_least, setting, user_path
from homeo_msgs_py.graph import BAYES, INTENTION_MODES, TICKS_MAX
from homeo_msgs_py.learning import DOD, PSEUDO_UPDATE, XI, add_learning_flags, add_no_pseudo_flag, learning_values
from homeo_msgs_py.params import add_flag

from .launch import PROG, GraphOptions, run_graph
from .options import add_run_options, check_files, close_sinks, durable_options, open_sinks

LAUNCH_LEARNING = (DOD, XI, PSEUDO_UPDATE)  # the decision's learning parameters a launch sets
HELP = {"sim": "the graph with the simulated world and human; prints Table 4.5's metrics",
        "day": "the graph in the simulated home through a scripted day (homeo_sim/days); prints its metrics"}


def add_parser(sub, name: str, world_cls) -> None:
    s = sub.add_parser(name, help=HELP.get(name, f"the graph with the {name!r} world of the registry"))
    s.add_argument("--iterations", type=int_at_least(0, TICKS_MAX), default=5000, help="ticks (0 = until Ctrl-C; default 5000)")
    s.add_argument("--rate", type=float_in(0.0, 1000.0), default=0.0, help="ticks per second (0 = as fast as lockstep allows)")
    add_learning_flags(s, LAUNCH_LEARNING, help_extra=" (default: the scenario's)")
    add_no_pseudo_flag(s)
    s.add_argument("--intention", choices=INTENTION_MODES, default=BAYES,
                   help="recognise the intention with the Bayesian network (default) or observe it (the thesis's "
                        "simulation; what homeo-sim run does by default)")
    s.add_argument("--set", metavar="KEY=VALUE", type=setting, action="append", default=[],
                   help="override an open choice of the scenario")
    s.add_argument("--load-q", metavar="FILE", type=user_path, help="start from a saved Q-table")
    s.add_argument("--save-q", metavar="FILE", type=user_path, help="save the Q-table at the end")
    s.add_argument("--trace", metavar="FILE", type=user_path, help="the world writes one JSON line per tick")
    for spec in world_cls.PARAMS:  # the world's own parameters (default: the node's)
        add_flag(s, spec)
    add_run_options(s, name)
    s.set_defaults(world=name, world_params=tuple(p.name for p in world_cls.PARAMS))


def options_from_args(a) -> GraphOptions:
    from homeo_decision.scenario import load_scenario

    sc = load_scenario(a.scenario, overrides=dict(a.set))  # a bad scenario is a one-line error here, not in four nodes
    durable = durable_options(a, a.world, sc, a.intention == BAYES)  # contradicting options first, then the files
    check_files(a, write=[("--save-q", a.save_q), ("--trace", a.trace)], tables=[("--load-q", a.load_q)], sc=sc)
    if getattr(a, "record", None):
        from .record import check_new_bag

        check_new_bag(a.record)
    import os

    world = {"iterations": a.iterations, "rate": float(a.rate), "action_timeout": float(a.action_timeout),
             "trace_path": os.path.abspath(a.trace) if a.trace else ""}  # '~' expanded by --trace's user_path
    world.update({n: getattr(a, n) for n in a.world_params if getattr(a, n) is not None})
    from homeo_decision.world_api import world_class

    world_class(a.world).check(sc, world)  # a world that cannot start is a one-line error here, not in a node
    return GraphOptions(world=a.world, world_params=world, seed=a.seed, learning=learning_values(a, LAUNCH_LEARNING),
                        intention=a.intention,
                        scenario=a.scenario or "", overrides=tuple(a.set), load_q=a.load_q, save_q=a.save_q,
                        data_dir=a.data_dir, namespace=a.namespace, auth=not a.no_auth,
                        **durable)


def cmd_sim(a) -> int:
    from homeo_decision.scenario import load_scenario

    o = options_from_args(a)
    sc = load_scenario(o.scenario or None, overrides=dict(o.overrides))
    bar = progress_bar(a.quiet, o.iterations)
    last: dict = {}
    status = None
    sinks = []
    try:
        sinks = open_sinks(a, a.world, o.iterations, o.seed, sc, o.overrides, intention=o.intention)
        status = run_graph(o, quiet=a.quiet, log_dir=a.log_dir, on_status=bar, last=last, sinks=sinks)
    except KeyboardInterrupt:
        pass
    finally:
        bar.close()
        close_sinks(sinks)
    return print_result(status if status is not None else last, status is None, sc, o.seed, o.iterations, a.json)


class progress_bar:
    """The run's progress on stderr (tqdm), fed by the run status: ``bar(tick, fields)``; none when quiet."""

    def __init__(self, quiet: bool, total: int):
        from tqdm import tqdm

        self.bar = None if quiet else tqdm(total=total or None, unit="tick", file=sys.stderr, leave=False,
                                           dynamic_ncols=True, desc="graph")

    def __call__(self, tick: int, fields: dict) -> None:
        bar = self.bar
        if bar is None:
            return
        if tick < bar.n:  # a new run (~/reset): its own count and clock
            bar.reset(total=fields.get("iterations") or None)
        bar.n = tick
        bar.set_postfix_str(fields["state"] + (f", {fields['missed']} missed" if fields["missed"] else ""),
                            refresh=False)
        bar.refresh()

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def print_result(status: dict, interrupted: bool, sc, seed: int, iterations: int, as_json: bool) -> int:
    """What a run of a world with metrics prints: Table 4.5's metrics (``homeo-sim run``'s JSON with
    ``as_json``), and the graph's time, misses, memory and restarts. An interrupted run shows what it
    measured so far, its real tick count and time; the exit code: 0, or 130 for a bounded run cut short."""
    from homeo_sim.cli import format_table, run_output
    from homeo_sim.stats import json_safe

    code = 0
    if interrupted:  # Ctrl-C: the nodes are stopped; show what the run measured so far
        print(f"{PROG}: interrupted; all nodes stopped", file=sys.stderr)
        if not status.get("metrics"):
            return 130
        print(f"{PROG}: metrics of the run so far:", file=sys.stderr)
        code = 0 if iterations == 0 else 130
    ticks = status.get("tick", iterations) if interrupted else (status.get("extra") or {}).get("ticks", iterations)
    out = run_output(ticks, [seed], [status["metrics"]], sc.drive_names)
    restarts = status.get("restarts")
    if restarts:  # only when there were any: an undisturbed run prints what homeo-sim run prints
        out["restarts"] = restarts
        out["missed"] = status.get("missed", 0)  # the ticks the restarts cost
    if as_json:
        print(json.dumps(json_safe(out)))
        return code
    print(format_table(out, sc.drive_names, sc.name))
    elapsed = status.get("elapsed_s", float("nan"))
    rss = f", {status['rss_mb']:.0f} MiB resident" if "rss_mb" in status else ""
    print(f"graph: {elapsed:.1f} s for {ticks} ticks ({elapsed / max(1, ticks) * 1e3:.2f} ms/tick), "
          f"{status.get('missed', 0)} missed{rss}")
    if restarts:
        print("restarts: " + ", ".join(f"{n} {k}" for n, k in sorted(restarts.items())))
    return code

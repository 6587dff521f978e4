"""``homeo-launch NAME``: the graph with any world of the registry, from one command; no world is named here.

    homeo-launch NAME [--iterations N] [--rate HZ] [--seed S] [--dod X] [--xi X] [--no-pseudo]
                      [--intention MODE] [--scenario FILE] [--set KEY=VALUE] [--load-q FILE] [--save-q FILE]
                      [--trace FILE] [the world's parameters and launch options] [--json] ...

The world's declarations make the command (``homeo_decision.world_api.WorldBackend``): ``TICKS`` names
the tick count (``--interactions`` for a robot), ``INTENTIONS`` the ``--intention`` values, ``PARAMS``
and ``LAUNCH`` the rest of the flags (``--help`` lists them). Its ``plan`` says what to start (the world
node's parameters, companions such as a stand-in robot, scenario overrides); while the run goes a world
with an interaction log prints each row (``log_line``), any other a progress bar; at the end its
``result`` (``--json``) or ``result_text``, then the graph's own time, misses, memory and restarts.
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

from homeo_decision.world_api import ITERATIONS, RATE, WorldConfigError, world_class
from homeo_msgs_py.cli_args import leave, setting, user_path
from homeo_msgs_py.graph import BAYES
from homeo_msgs_py.learning import DOD, PSEUDO_UPDATE, XI, add_learning_flags, add_no_pseudo_flag, learning_values
from homeo_msgs_py.params import add_flag

from .launch import PROG, GraphOptions, run_graph
from .options import add_run_options, check_files, close_sinks, durable_options, open_sinks

LAUNCH_LEARNING = (DOD, XI, PSEUDO_UPDATE)  # the decision's learning parameters a launch sets


def add_parser(sub, name: str, cls) -> None:
    doc = (cls.__doc__ or "").strip().splitlines()
    s = sub.add_parser(name, help=doc[0] if doc else f"the graph with the {name!r} world of the registry",
                       description=f"The node graph with the world {name!r} ({cls.__module__}.{cls.__name__}).")
    ticks, default = cls.TICKS
    add_flag(s, replace(ITERATIONS, name=ticks, default=default), default=default)
    add_flag(s, RATE, default=RATE.default)
    add_learning_flags(s, LAUNCH_LEARNING, help_extra=" (default: the scenario's)")
    add_no_pseudo_flag(s)
    modes = tuple(cls.INTENTIONS)
    s.add_argument("--intention", choices=modes, default=modes[0],
                   help=f"how the robot knows the user's intention: {', '.join(modes)} (default {modes[0]}; "
                        + ", ".join(f"{k}: the intention node's {v} mode" for k, v in cls.INTENTIONS.items()) + ")")
    s.add_argument("--set", metavar="KEY=VALUE", type=setting, action="append", default=[],
                   help="override an open choice of the scenario")
    s.add_argument("--load-q", "--q-table", metavar="FILE", type=user_path, help="start from a saved Q-table (or a "
                   "decision checkpoint)")
    s.add_argument("--save-q", metavar="FILE", type=user_path, help="save the Q-table at the end")
    s.add_argument("--trace", metavar="FILE", type=user_path, help="the world writes one JSON line per tick")
    for spec in (*cls.PARAMS, *cls.LAUNCH):  # the world's own (default: the node's, or the plan's)
        add_flag(s, spec)
    add_run_options(s, name)
    s.set_defaults(world=name, ticks=ticks)


def cmd_world(a) -> int:
    from homeo_decision.scenario import load_scenario

    cls = world_class(a.world)
    sc = load_scenario(a.scenario, overrides=dict(a.set))  # a bad scenario is one line here, not in four nodes
    a.iterations = getattr(a, a.ticks)
    durable = check_args(a, cls, sc)  # every option and file the user named, before anything is made
    with tempfile.TemporaryDirectory(prefix=f"homeo-{a.world}-") as tmp:
        base = Path(a.log_dir or tmp)
        base.mkdir(parents=True, exist_ok=True)
        given = {s.name: getattr(a, s.name) for s in (*cls.PARAMS, *cls.LAUNCH)}
        given.update(intention=a.intention, load_q=a.load_q, seed=a.seed, scenario=a.scenario, iterations=a.iterations)
        try:
            plan = cls.plan(sc, given, str(base))
        except WorldConfigError as exc:
            if getattr(exc, "hard_exit", False):  # e.g. libqi's threads may abort the interpreter's teardown
                print(f"{PROG}: error: {exc}", file=sys.stderr)
                leave(2)
            raise
        o = graph_options(a, cls, sc, plan, durable)
        setting_ = {"seed": a.seed, "iterations": a.iterations, "intention": o.intention, "learning": o.learning,
                    "values": dict(given, **plan.params), "interrupted": False}
        show = Progress(cls, a.quiet or a.json, a.iterations)
        last: dict = {}
        status = None
        sinks = []
        try:
            sinks = open_sinks(a, a.world, a.iterations, a.seed, sc, a.set, intention=o.intention, inputs=plan.inputs)
            status = run_graph(o, quiet=a.quiet, log_dir=str(base), on_status=show, last=last, sinks=sinks)
        except KeyboardInterrupt:
            setting_["interrupted"] = True
        finally:
            show.close()
            close_sinks(sinks)
        bounded = plan.bounded if plan.bounded is not None else a.iterations > 0
        return print_result(cls, sc, status if status is not None else last, setting_, a.json, bounded)


def check_args(a, cls, sc) -> dict:
    """The options that name files and checkpoints, checked before anything starts; the durable options."""
    durable = durable_options(a, a.world, sc, cls.INTENTIONS[a.intention] == BAYES)  # contradictions first
    check_files(a, write=[("--save-q", a.save_q), ("--trace", a.trace)], tables=[("--load-q", a.load_q)], sc=sc)
    if getattr(a, "record", None):
        from homeo_record.record import check_new_bag

        check_new_bag(a.record)
    return durable


def graph_options(a, cls, sc, plan, durable: dict) -> GraphOptions:
    """The graph's options from the arguments and the world's plan."""
    world = {"iterations": a.iterations, "rate": float(a.rate), "action_timeout": float(a.action_timeout),
             "trace_path": os.path.abspath(a.trace) if a.trace else "", **plan.params}
    cls.check(sc, world)  # a world that cannot start is a one-line error here, not in a node
    return GraphOptions(world=a.world, world_params=world, seed=a.seed, learning=learning_values(a, LAUNCH_LEARNING),
                        intention=cls.INTENTIONS[a.intention], scenario=plan.scenario or a.scenario or "",
                        overrides=tuple(a.set) + tuple(plan.overrides.items()), load_q=a.load_q, save_q=a.save_q,
                        data_dir=a.data_dir, namespace=a.namespace, auth=not a.no_auth, companions=plan.companions,
                        executor=a.executor, **durable)


class Progress:
    """The run as it goes, on stderr: each new row of a world's interaction log, or a progress bar (tqdm)."""

    def __init__(self, cls, quiet: bool, total: int):
        self.cls, self.shown, self.bar = cls, 0, None
        if quiet:
            self.cls = None
        elif cls.LOG_HEADER:
            print(cls.LOG_HEADER, file=sys.stderr)
        else:
            from tqdm import tqdm

            self.bar = tqdm(total=total or None, unit="tick", file=sys.stderr, leave=False, dynamic_ncols=True,
                            desc="graph")

    def __call__(self, tick: int, fields: dict) -> None:
        if self.bar is not None:
            bar = self.bar
            if tick < bar.n:  # a new run (~/reset): its own count and clock
                bar.reset(total=fields.get("iterations") or None)
            bar.n = tick
            bar.set_postfix_str(fields["state"] + (f", {fields['missed']} missed" if fields["missed"] else ""),
                                refresh=False)
            bar.refresh()
        elif self.cls is not None:
            for r in (fields.get("extra") or {}).get("log") or []:  # each row once: a restarted world's log goes on
                k = r.get("interaction") if isinstance(r, dict) else None
                if type(k) is int and k > self.shown:
                    self.shown = k
                    print(self.cls.log_line(r), file=sys.stderr)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def print_result(cls, sc, status: dict, setting: dict, as_json: bool, bounded: bool) -> int:
    """What a run prints: the world's result, and the graph's time, misses, memory and restarts. An
    interrupted run shows what it has so far; the exit code: 0, or 130 for a bounded run cut short."""
    from homeo_msgs_py.schemas import finite

    code = 0
    if setting["interrupted"]:  # Ctrl-C: the nodes are stopped; show what the run has so far
        print(f"{PROG}: interrupted; all nodes stopped", file=sys.stderr)
        code = 130 if bounded else 0
    out = cls.result(sc, status, setting)
    if out is None:
        return 130 if setting["interrupted"] else code
    if setting["interrupted"]:
        print(f"{PROG}: the run so far:", file=sys.stderr)
    if as_json:
        print(json.dumps(finite(out)))
        return code
    print(cls.result_text(sc, out, setting))
    elapsed, ticks = status.get("elapsed_s", float("nan")), (status.get("extra") or {}).get("ticks", 0)
    rss = f", {status['rss_mb']:.0f} MiB resident" if "rss_mb" in status else ""
    print(f"graph: {elapsed:.1f} s for {ticks} ticks ({elapsed / max(1, ticks) * 1e3:.2f} ms/tick), "
          f"{status.get('missed', 0)} missed{rss}")
    if status.get("restarts"):
        print("restarts: " + ", ".join(f"{n} {k}" for n, k in sorted(status["restarts"].items())))
    return code

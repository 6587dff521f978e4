"""The one graph launcher: the world node with any world, and the three robot nodes, as processes.

``run_graph`` starts the graph of ``homeo_msgs_py.graph`` (the nodes' parameters from
``GraphOptions``), waits until every node and endpoint is discovered, supervises it (a node that
dies is restarted from its checkpoint: ``supervise.py``), follows the world's run status and
returns its last one. Ctrl-C stops every node after saving what was asked (``--save-q``, the
nodes' final checkpoints). ``homeo-launch NAME`` (``front.py``) is its front end for every world of
the registry, and the world's companions (a stand-in robot) run beside the nodes.
"""

from __future__ import annotations

import os
import sys
import time
from dataclasses import dataclass, field, replace

from homeo_msgs_py.data_dir import DEFAULT as DATA_DIR
from homeo_msgs_py.graph import BAYES, GRAPH, NODES, ROBOT_NODES, WORLD, endpoints

from .monitor import DISCOVERY_TIMEOUT_S, GraphError, Monitor, RunFollower, check_alive
from .processes import Graph, NodeSpec, dds_defaults, graph_env
from .supervise import Supervisor
from .supervise import wait_until_up as supervised_wait

PROG = "homeo-launch"
# on Ctrl-C, how long to wait for the run's status when none came yet (it is latched: it comes once the
# monitor has matched the world node, which on a loaded machine once took over 2 s)
INTERRUPT_STATUS_S = 5.0


@dataclass
class GraphOptions:
    world: str = "sim"  # a name of the homeo_robot.worlds registry
    world_params: dict = field(default_factory=dict)  # the world node's: iterations, rate, ..., and the world's own
    seed: int = 0  # the decision's and the world's random streams
    learning: dict = field(default_factory=dict)  # the decision's learning parameters given (dod, xi, ...)
    intention: str = BAYES  # the intention node's mode; BAYES learns from the outcome
    scenario: str = ""  # a scenario file ('' = the thesis scenario)
    overrides: tuple = ()  # (key, value) of the scenario's open choices
    load_q: str | None = None
    save_q: str | None = None
    extra_readers: int = 0  # the launcher's tap (a recorder, a live view): the run waits for it
    checkpoint_dir: str = ""  # '' = no checkpoints (restarted nodes then start fresh)
    checkpoint_every: int = 100
    resume: str | None = None  # a checkpoint folder to start the robot nodes from
    max_restarts: int = 3  # per node; 0 = a node that dies stops the graph
    session: str = ""  # this launch's id, in every checkpoint (a restarted node takes only its own)
    data_dir: str = DATA_DIR  # files named by parameters live here (homeo_msgs_py.data_dir)
    namespace: str = ""  # the whole graph under /namespace
    auth: bool = True  # the graph signs its messages (docs/SECURITY.md); --no-auth for debugging
    companions: tuple = ()  # world_api.Companion: processes beside the nodes (a stand-in robot), started first
    executor: str = "events"  # every node's rclpy executor (node_base.EXECUTOR)

    @property
    def iterations(self) -> int:
        return self.world_params.get("iterations", 0)


def sim_options(iterations: int, **kw) -> GraphOptions:
    """The simulated world's graph with ``homeo-launch sim``'s defaults (the bench's and the soak's run)."""
    return GraphOptions(world="sim", world_params={"iterations": iterations}, **kw)


def graph_specs(o: GraphOptions) -> list[NodeSpec]:
    """Every node of the graph with its parameters (the world's from ``o.world_params``)."""
    from homeo_decision.node_runtime import overrides_param

    common = {"scenario": o.scenario or "", "overrides": overrides_param(dict(o.overrides)),
              "data_dir": os.path.abspath(o.data_dir), "extra_readers": o.extra_readers, "executor": o.executor}
    decision = dict(common, seed=o.seed, **o.learning)
    # where ~/save_q writes: the user's own paths (anywhere), '~' expanded by every front end (cli_args.user_path)
    q_path = o.save_q or o.load_q
    if q_path:
        decision["q_table_path"] = os.path.abspath(q_path)
    if o.load_q:  # a Q-table file or a decision checkpoint
        decision["start_from"] = os.path.abspath(o.load_q)
    world = dict(common, world=o.world, seed=o.seed, intention_learns=o.intention == BAYES, **o.world_params)
    params = {WORLD: world, "homeo_intention": dict(common, mode=o.intention), "homeo_drives": dict(common),
              "homeo_decision": decision}
    for n, p in params.items():  # checkpoints and supervision (homeo_decision.durable)
        if n in ROBOT_NODES and o.max_restarts > 0:
            p["supervised"] = True
        if o.checkpoint_dir:
            p.update(checkpoint_dir=os.path.abspath(o.checkpoint_dir), checkpoint_every=int(o.checkpoint_every),
                     session=o.session)
        if o.resume and n in ("homeo_intention", "homeo_decision"):  # the learned state; a world starts a new run
            p["resume_dir"] = os.path.abspath(o.resume)
    return ([NodeSpec(c.name, "", argv=list(c.argv)) for c in o.companions]
            + [NodeSpec(n, NODES[n].module, params[n]) for n in GRAPH])


def run_graph(o: GraphOptions, *, quiet: bool = False, log_dir: str | None = None, on_status=None,
              discovery_timeout: float = DISCOVERY_TIMEOUT_S, last: dict | None = None, sinks=(), on_start=None,
              check=None) -> dict:
    """Run the graph to the end of the world's run; returns the last run status fields plus
    ``elapsed_s`` (first tick to done), ``rss_mb`` and ``restarts`` (when there were any). Raises
    GraphError or KeyboardInterrupt (``last`` then holds the run so far).

    ``on_status(tick, fields)``: every new run status. ``sinks`` (a bag, a live view) get every message
    of the run: from the launcher's tap (``tap.py``; the world waits for the tap's subscriptions
    before tick 0), or, for a bag recorded at the writers (``record.WriterBag``), from what each
    node keeps of what it sends. ``on_start(graph)`` once every node is up; ``check()`` on every
    turn (raises GraphError to stop, e.g. when a stand-in robot died)."""
    os.environ.update(dds_defaults())  # the launcher's own node too
    tap_sinks, writers = split_sinks(sinks)
    if tap_sinks:
        o = replace(o, extra_readers=1)
    if o.checkpoint_dir and not o.session:
        o = replace(o, session=new_session())
    graph = Graph(with_spool(graph_specs(o), writers, o.data_dir), graph_env(), log_dir, namespace=o.namespace,
                  auth=o.auth)
    mon = tap = sup = None
    run = RunFollower(last)
    last = run.last
    try:
        mon = Monitor(graph.namespace, graph.signer)
        sup = Supervisor(graph, mon.node, o.max_restarts, os.path.abspath(o.checkpoint_dir) if o.checkpoint_dir else "",
                         log=(lambda text: None) if quiet else None, spool=writers.own if writers else None)
        checks = (lambda: (sup.check(), check())) if check is not None else sup.check
        tap = open_tap(mon, graph, tap_sinks, writers)
        if tap_sinks:
            for s in tap_sinks:
                if hasattr(s, "attach"):
                    s.attach(mon.node)
            start_robot_first(graph, mon, tap, discovery_timeout)
        graph.start()
        supervised_wait(graph, mon, checks, GRAPH, endpoints(o.intention == BAYES), discovery_timeout)
        if on_start is not None:
            on_start(graph)
        while True:
            mon.spin(0.05)
            checks()  # a node that died is restarted (bounded); the world node goes on with the run
            if sup.restarts:
                last["restarts"] = dict(sup.restarts)
            if not run.take(mon.status):
                continue
            if on_status is not None:
                on_status(mon.status.tick, mon.status.fields)
            if last["done"]:
                break
        if tap_sinks:
            drain(mon, tap)
        out = dict(last)
        out["elapsed_s"] = run.elapsed_s()
        out["rss_mb"] = graph.rss_mb()
        if o.save_q:
            ok, msg = save_q(mon)
            if not ok:
                raise GraphError(f"saving the Q-table failed: {msg}")
        return out
    except KeyboardInterrupt:
        if mon is not None and o.save_q:  # what the user asked for, before the nodes stop
            ok, msg = save_q(mon)
            if not quiet or not ok:
                print(f"{PROG}: " + (f"saved the Q-table {o.save_q}" if ok else f"warning: the Q-table was not saved: "
                                     f"{msg}"), file=sys.stderr)
        # the run so far: the status is latched, so a launcher whose node has not heard it yet gets it now
        if mon is not None and not last.get("done"):
            end = time.monotonic() + INTERRUPT_STATUS_S
            while time.monotonic() < end and mon.status is None:
                mon.spin(0.05)
            mon.spin(0.1)  # the newest status on its way
            if mon.status is not None:
                last.update(mon.status.fields, tick=mon.status.tick)
        if run.t_start is not None:  # what ran until now: the ticks and the run's time of the last status
            last.update(elapsed_s=run.elapsed_s(), rss_mb=graph.rss_mb())
        raise
    finally:
        if tap is not None:
            tap.close()
        if mon is not None:
            mon.close()
        try:
            codes = graph.stop()
        finally:
            graph.close()  # the temporary log folder goes, even if a second Ctrl-C cuts the stop short
        if not quiet and any(c not in (0, None, -2, 130) for c in codes.values()):
            bad = ", ".join(f"{n}={c}" for n, c in codes.items() if c not in (0, None, -2, 130))
            print(f"{PROG}: note: nodes stopped with exit codes {bad}", file=sys.stderr)


def split_sinks(sinks) -> tuple[list, object]:
    """The sinks fed by the launcher's tap (a live view, a bag recorded at the tap), and the bag
    recorded at the writers (``record.WriterBag``) or None."""
    writers = next((s for s in sinks if getattr(s, "at_writers", False)), None)
    return [s for s in sinks if s is not writers], writers


def with_spool(specs: list, writers, data_dir: str) -> list:
    """``specs`` with every node appending what it sends to the writers' spool, when recording there."""
    if writers is not None:
        folder = writers.prepare(os.path.abspath(data_dir))
        for s in specs:
            s.params["record_spool"] = folder
    return specs


def open_tap(mon: Monitor, graph: Graph, tap_sinks: list, writers):
    """The launcher's tap: every topic for ``tap_sinks``, and (recording at the writers) the topics
    the graph takes from outside; None when nothing needs one."""
    if not tap_sinks and (writers is None or not writers.tap_topics):
        return None
    from homeo_record.tap import Tap

    sinks = tap_sinks + ([writers] if writers is not None else [])
    return Tap(mon.node, sinks, topics=None if tap_sinks else writers.tap_topics, signer=graph.signer)


def start_robot_first(graph: Graph, mon: Monitor, tap, bound: float) -> None:
    """With a tap: start the robot nodes, wait until the tap hears each of their topics, then the
    world node (started by the caller), which waits for the tap on its own topics (``extra_readers``)
    before tick 0. So the tap misses no tick of any topic."""
    graph.start(ROBOT_NODES)
    keys = {k for n in ROBOT_NODES for k in NODES[n].publishes}
    end = time.monotonic() + bound
    while True:
        check_alive(graph)
        missing = tap.unmatched(keys)
        if not missing:
            return
        if time.monotonic() > end:
            raise GraphError(f"the recorder did not hear {', '.join(missing)} within {bound:g} s")
        mon.spin(0.1)


def drain(mon: Monitor, tap, bound: float = 10.0, quiet: float = 0.5) -> None:
    """After the run: take in what is still on its way to the tap (the final messages), until the tap has
    seen the final run status and nothing new for ``quiet`` s, a few of its wakes (it yields the CPU: on a
    busy machine a 50 ms lull came before a final drives message); bounded."""
    end, n, since = time.monotonic() + bound, tap.count, time.monotonic()
    while time.monotonic() < end:
        mon.spin(0.05)  # the tap spins in its own thread; this only lets time pass
        if tap.count != n:
            n, since = tap.count, time.monotonic()
        elif tap.done and time.monotonic() - since >= quiet:
            return


def new_session() -> str:
    import uuid

    return uuid.uuid4().hex[:12]


def save_q(mon: Monitor, timeout: float = 5.0) -> tuple[bool, str]:
    """Ask the decision node to save its table to ``--save-q``, its q_table_path (also on Ctrl-C);
    ``homeo-launch watch`` asks the same, with its own timeout."""
    return mon.call_trigger("homeo_decision/save_q", timeout=timeout)

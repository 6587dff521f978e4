"""``homeo-launch sim``: the whole node graph as separate processes, from one command.

    homeo-launch sim [--iterations N (0 = until Ctrl-C)] [--rate HZ] [--seed S] [--dod X] [--xi X]
                     [--no-pseudo] [--scenario FILE] [--set KEY=VALUE] [--load-q FILE] [--save-q FILE]
                     [--trace FILE] [--json] [--quiet] [--log-dir DIR]
                     [--checkpoint-dir DIR] [--checkpoint-every N] [--no-checkpoints] [--resume DIR]
                     [--max-restarts N]
    homeo-launch pepper [--qi-url URL | --standin --script FILE] [--q-table FILE] [--dod X] [--json]
    homeo-launch bench [--iterations N] [--rounds R] [--json]

``sim`` starts homeo_sim, homeo_intention, homeo_drives and homeo_decision, waits until all
are discovered and matched, shows progress, and prints the metrics of ``homeo-sim run``
(the same JSON with ``--json``). Ctrl-C stops every node after saving what was asked (``--save-q``,
the nodes' final checkpoints). A robot node that dies is restarted from its checkpoint
and so is the world node, which goes on with the run (``supervise.py``); too many deaths of one
node stop the rest with its name.
"""

from __future__ import annotations

import json
import os
import sys
import time
from dataclasses import dataclass, replace

from homeo_msgs_py.cli_args import UserError
from homeo_msgs_py.data_dir import DEFAULT as DATA_DIR
from homeo_msgs_py.graph import BAYES, GRAPHS, NODES, endpoints
from homeo_sim.cli import format_table, run_output
from homeo_sim.stats import json_safe

from .monitor import DISCOVERY_TIMEOUT_S, GraphError, Monitor, check_alive, wait_until_up
from .processes import Graph, NodeSpec, dds_defaults, graph_env
from .supervise import Supervisor
from .supervise import wait_until_up as supervised_wait

PROG = "homeo-launch"
# on Ctrl-C, how long to wait for the run's status when none came yet (it is latched: it comes once the
# monitor has matched the world node, which on a loaded machine once took over 2 s)
INTERRUPT_STATUS_S = 5.0


@dataclass
class SimOptions:
    iterations: int = 5000
    rate: float = 0.0
    seed: int = 0
    dod: float | None = None
    xi: float | None = None
    pseudo_update: bool | None = None
    scenario: str | None = None
    overrides: tuple = ()
    load_q: str | None = None
    save_q: str | None = None
    trace: str | None = None
    action_timeout: float = 5.0
    intention: str = BAYES  # the graph recognises intentions; ORACLE is the thesis's simulation
    human: str = "sim"  # or "person": a person on homeo/human_input plays the human
    human_timeout: float = 10.0  # seconds a tick waits for the person
    extra_readers: int = 0  # the launcher's tap (a recorder, a live view): the run waits for it
    checkpoint_dir: str = ""  # '' = no checkpoints (restarted nodes then start fresh)
    checkpoint_every: int = 100
    resume: str | None = None  # a checkpoint folder to start the robot nodes from
    max_restarts: int = 3  # per robot node; 0 = a node that dies stops the graph
    session: str = ""  # this launch's id, in every checkpoint (a restarted node takes only its own)
    data_dir: str = DATA_DIR  # files named by parameters live here (homeo_msgs_py.data_dir)
    namespace: str = ""  # the whole graph under /namespace
    auth: bool = True  # the graph signs its messages (docs/SECURITY.md); --no-auth for debugging


def sim_specs(o: SimOptions) -> list[NodeSpec]:
    from homeo_decision.node_runtime import overrides_param

    common = {"scenario": o.scenario or "", "overrides": overrides_param(dict(o.overrides)),
              "data_dir": os.path.abspath(o.data_dir), "extra_readers": o.extra_readers}
    decision = dict(common, seed=o.seed)
    for k, v in (("dod", o.dod), ("xi", o.xi)):
        if v is not None:
            decision[k] = float(v)
    if o.pseudo_update is not None:
        decision["pseudo_update"] = bool(o.pseudo_update)
    q_path = o.load_q or o.save_q  # a different --save-q is set just before saving
    if q_path:
        decision["q_table_path"] = os.path.abspath(q_path)
    if o.load_q:
        decision["load_on_start"] = True
    sim = dict(common, seed=o.seed, iterations=o.iterations, rate=float(o.rate),
               action_timeout=float(o.action_timeout), trace_path=os.path.abspath(o.trace) if o.trace else "",
               intention_accuracy=o.intention == BAYES, human=o.human,
               human_timeout=float(o.human_timeout))
    params = {"homeo_sim": sim, "homeo_intention": dict(common, mode=o.intention), "homeo_drives": dict(common),
              "homeo_decision": decision}
    durable_params(o, params)
    return [NodeSpec(n, NODES[n].module, params[n]) for n in GRAPHS["sim"]]


def durable_params(o, params: dict) -> None:
    """Checkpoints and supervision (``homeo_decision.durable``) for the robot nodes of ``params``."""
    for n in ("homeo_intention", "homeo_drives", "homeo_decision"):
        if n in params and o.max_restarts > 0:
            params[n]["supervised"] = True
    for n in ("homeo_sim", "pepper_bridge", "homeo_intention", "homeo_drives", "homeo_decision"):
        if n not in params:
            continue
        p = params[n]
        if o.checkpoint_dir:
            p.update(checkpoint_dir=os.path.abspath(o.checkpoint_dir), checkpoint_every=int(o.checkpoint_every),
                     session=o.session)
        if o.resume and n in ("homeo_intention", "homeo_decision"):  # the learned state; a world starts a new run
            p["resume_dir"] = os.path.abspath(o.resume)


def run_graph(o: SimOptions, quiet: bool = False, log_dir: str | None = None, on_progress=None,
              discovery_timeout: float = DISCOVERY_TIMEOUT_S, last: dict | None = None, sinks=(),
              on_start=None) -> dict:
    """Run the simulated graph to the end; returns the last run status fields (metrics included)
    plus ``elapsed_s`` (first tick to done) and ``rss_mb``. Raises GraphError or KeyboardInterrupt.
    ``sinks`` (a bag, a live view) get every message of the run: from the launcher's tap (``tap.py``;
    the simulation waits for the tap's subscriptions before tick 0), or, for a bag recorded at the
    writers (``record.WriterBag``), from what each node keeps of what it sends. ``on_start(graph)``
    is called once every node is up (the soak benchmark watches their processes)."""
    env = graph_env()
    os.environ.update(dds_defaults())  # the launcher's own node too
    tap_sinks, writers = split_sinks(sinks)
    if tap_sinks:
        o = replace(o, extra_readers=1)
    if o.checkpoint_dir and not o.session:
        o = replace(o, session=new_session())
    graph = Graph(with_spool(sim_specs(o), writers, o.data_dir), env, log_dir, namespace=o.namespace, auth=o.auth)
    mon = tap = sup = None
    try:
        mon = Monitor(graph.namespace, graph.signer)
        sup = Supervisor(graph, mon.node, o.max_restarts, os.path.abspath(o.checkpoint_dir) if o.checkpoint_dir else "",
                         log=(lambda text: None) if quiet else None, spool=writers.own if writers else None)
        tap = open_tap(mon, graph, tap_sinks, writers)
        if tap_sinks:
            for s in tap_sinks:
                if hasattr(s, "attach"):
                    s.attach(mon.node)
            start_robot_first(graph, mon, tap, discovery_timeout)
        graph.start()
        supervised_wait(graph, mon, sup, GRAPHS["sim"], endpoints("sim", o.intention == BAYES), discovery_timeout)
        if on_start is not None:
            on_start(graph)
        t_start = None
        last_tick = -1
        while True:
            mon.spin(0.05)
            sup.check()  # a node that died is restarted (bounded); the world node goes on with the run
            st = mon.status
            if st is None:
                continue
            if t_start is None and st.fields["state"] in ("running", "finishing", "done"):
                t_start = time.monotonic()
            if st.tick != last_tick:
                last_tick = st.tick
                if last is not None:
                    last.update(st.fields)
                if on_progress is not None:
                    on_progress(st.tick, st.fields)
            if st.fields["done"]:
                break
        if tap_sinks:
            drain(mon, tap)
        out = dict(mon.status.fields)
        out["elapsed_s"] = (out.get("extra") or {}).get("elapsed_s", time.monotonic() - t_start)
        out["rss_mb"] = graph.rss_mb()
        if sup.restarts:
            out["restarts"] = dict(sup.restarts)
        if o.save_q:
            ok, msg = save_q(mon, o)
            if not ok:
                raise GraphError(f"saving the Q-table failed: {msg}")
        return out
    except KeyboardInterrupt:
        if last is not None and sup is not None and sup.restarts:
            last["restarts"] = dict(sup.restarts)
        if mon is not None and o.save_q:  # what the user asked for, before the nodes stop
            ok, msg = save_q(mon, o)
            if not quiet or not ok:
                print(f"{PROG}: " + (f"saved the Q-table {o.save_q}" if ok else f"warning: the Q-table was not saved: "
                                     f"{msg}"), file=sys.stderr)
        # the run so far: the status is latched, so a launcher whose node has not heard it yet gets it now
        if mon is not None and last is not None and not last.get("metrics"):
            end = time.monotonic() + INTERRUPT_STATUS_S
            while time.monotonic() < end and not (mon.status and mon.status.fields.get("metrics")):
                mon.spin(0.05)
            if mon.status is not None:
                last.update(mon.status.fields)
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
    from .tap import Tap

    sinks = tap_sinks + ([writers] if writers is not None else [])
    return Tap(mon.node, sinks, topics=None if tap_sinks else writers.tap_topics, signer=graph.signer)


def start_robot_first(graph: Graph, mon: Monitor, tap, bound: float) -> None:
    """With a tap: start the robot nodes, wait until the tap hears each of their topics, then the
    world node (started by the caller), which waits for the tap on its own topics (``extra_readers``)
    before tick 0. So the tap misses no tick of any topic."""
    robot = [s.name for s in graph.specs if NODES[s.name].role != "world"]
    graph.start(robot)
    keys = {k for n in robot for k in NODES[n].publishes}
    end = time.monotonic() + bound
    while True:
        check_alive(graph)
        missing = tap.unmatched(keys)
        if not missing:
            return
        if time.monotonic() > end:
            raise GraphError(f"the recorder did not hear {', '.join(missing)} within {bound:g} s")
        mon.spin(0.1)


def drain(mon: Monitor, tap, bound: float = 2.0) -> None:
    """After the run: take in what is still on its way to the tap (the final messages), until the
    tap has seen the final run status and a spin brings nothing new; bounded."""
    end = time.monotonic() + bound
    while time.monotonic() < end:
        n = tap.count
        mon.spin(0.05)  # the tap spins in its own thread; this only lets time pass
        if tap.done and tap.count == n:
            return


def new_session() -> str:
    import uuid

    return uuid.uuid4().hex[:12]


def save_q(mon: Monitor, o) -> tuple[bool, str]:
    """Ask the decision node to save its table to ``--save-q`` (also on Ctrl-C)."""
    ok, msg = True, ""
    if o.load_q and o.save_q != o.load_q:
        ok, msg = _set_param(mon, "homeo_decision", "q_table_path", os.path.abspath(o.save_q))
    if ok:
        ok, msg = mon.call_trigger("homeo_decision/save_q", timeout=5.0)
    return ok, msg


def _set_param(mon: Monitor, node: str, name: str, value) -> tuple[bool, str]:
    from rcl_interfaces.srv import SetParameters
    from rclpy.parameter import Parameter

    cli = mon.node.create_client(SetParameters, f"{node}/set_parameters")
    try:
        if not cli.wait_for_service(timeout_sec=10.0):
            return False, f"{node}/set_parameters is not available"
        req = SetParameters.Request(parameters=[Parameter(name, value=value).to_parameter_msg()])
        fut = cli.call_async(req)
        end = time.monotonic() + 10.0
        while not fut.done() and time.monotonic() < end:
            mon.spin(0.05)
        if not fut.done():
            return False, "set_parameters did not answer"
        r = fut.result().results[0]
        return r.successful, r.reason
    finally:
        mon.node.destroy_client(cli)


def check_files(a, read=(), write=()) -> None:
    """The file options of a launch, before anything starts: each inside ``--data-dir`` (the nodes
    refuse any other place), the ones read existing, the ones written not a directory and in a
    place that exists or can be made; ``--log-dir`` writable. Raises UserError (one line)."""
    from homeo_msgs_py.data_dir import options_inside

    options_inside(a.data_dir, [*read, *write])
    for opt, f in read:
        if f and not os.path.isfile(f):
            raise UserError(f"{opt} {f}: file not found")
    for opt, f in write:
        if f and os.path.isdir(f):
            raise UserError(f"{opt} {f} is a directory, not a file")
    if getattr(a, "log_dir", None):
        try:
            os.makedirs(a.log_dir, exist_ok=True)
        except OSError as exc:
            raise UserError(f"--log-dir {a.log_dir}: {exc.strerror}") from None
        if not os.access(a.log_dir, os.W_OK | os.X_OK):
            raise UserError(f"--log-dir {a.log_dir} is not writable")


def options_from_args(a) -> SimOptions:
    from homeo_decision.scenario import load_scenario

    check_files(a, read=[("--load-q", a.load_q)], write=[("--save-q", a.save_q), ("--trace", a.trace)])
    if getattr(a, "record", None):
        from .record import check_new_bag

        check_new_bag(a.record)
    sc = load_scenario(a.scenario, overrides=dict(a.set))  # a bad scenario is a one-line error here, not in four nodes
    from .durable_args import durable_options

    return SimOptions(iterations=a.iterations, rate=a.rate, seed=a.seed, dod=a.dod, xi=a.xi,
                      pseudo_update=False if a.no_pseudo else None, scenario=a.scenario, overrides=tuple(a.set),
                      load_q=a.load_q, save_q=a.save_q, trace=a.trace, action_timeout=a.action_timeout,
                      intention=a.intention, human=a.human, human_timeout=a.human_timeout,
                      data_dir=a.data_dir, namespace=a.namespace, auth=not a.no_auth,
                      **durable_options(a, "sim", sc, a.intention == BAYES))


def open_sinks(a, graph: str, iterations: int, seed: int, sc, overrides, **extra) -> list:
    """The tap's sinks the command line asks for: ``--record DIR`` (a bag), ``--foxglove`` (live)."""
    from .tap import tapped_topics

    topics = tapped_topics(namespace=getattr(a, "namespace", ""))
    sinks = []
    try:
        if getattr(a, "record", None):
            from .record import check_new_bag, new_bag, run_info

            sinks.append(new_bag(check_new_bag(a.record), run_info(graph, iterations, seed, sc, overrides, **extra),
                                 topics, getattr(a, "record_from", "writers")))
        if getattr(a, "foxglove", None):
            from .live import FoxgloveSink

            sinks.append(FoxgloveSink(a.foxglove, sc, topics, person=getattr(a, "human", "sim") == "person"))
            if not getattr(a, "quiet", False):
                print(f"{PROG}: Foxglove: open ws://{a.foxglove[0]}:{sinks[-1].port}", file=sys.stderr)
    except BaseException:
        close_sinks(sinks)
        raise
    return sinks


def close_sinks(sinks) -> None:
    for s in sinks:
        s.close()


def cmd_sim(a) -> int:
    from homeo_decision.scenario import load_scenario

    o = options_from_args(a)
    sc = load_scenario(o.scenario, overrides=dict(o.overrides))
    bar = None
    if not a.quiet:
        from tqdm import tqdm

        bar = tqdm(total=o.iterations or None, unit="tick", file=sys.stderr, leave=False, dynamic_ncols=True,
                   desc="graph")

    def progress(tick, fields):
        if bar is not None:
            bar.n = tick
            bar.set_postfix_str(fields["state"] + (f", {fields['missed']} missed" if fields["missed"] else ""),
                                refresh=False)
            bar.refresh()

    last: dict = {}
    status = None
    sinks = []
    try:
        sinks = open_sinks(a, "sim", o.iterations, o.seed, sc, o.overrides, intention=o.intention)
        status = run_graph(o, quiet=a.quiet, log_dir=a.log_dir, on_progress=progress, last=last, sinks=sinks)
    except KeyboardInterrupt:
        pass
    finally:
        if bar is not None:
            bar.close()
        close_sinks(sinks)
    if status is None:  # Ctrl-C: the nodes are stopped; show what the run measured so far
        print(f"{PROG}: interrupted; all nodes stopped", file=sys.stderr)
        if not last.get("metrics"):
            return 130
        print(f"{PROG}: metrics of the run so far:", file=sys.stderr)
        status = dict(last, elapsed_s=float("nan"), rss_mb=float("nan"))
        code = 0 if o.iterations == 0 else 130
    else:
        code = 0
    out = run_output(o.iterations, [o.seed], [status["metrics"]], sc.drive_names)
    restarts = status.get("restarts")
    if restarts:  # only when there were any: an undisturbed run prints what homeo-sim run prints
        out["restarts"] = restarts
        out["missed"] = status.get("missed", 0)  # the ticks the restarts cost
    if a.json:
        print(json.dumps(json_safe(out)))
    else:
        print(format_table(out, sc.drive_names, sc.name))
        print(f"graph: {status['elapsed_s']:.1f} s for {o.iterations} ticks "
              f"({status['elapsed_s'] / max(1, o.iterations) * 1e3:.2f} ms/tick), {status['missed']} missed, "
              f"{status['rss_mb']:.0f} MiB resident")
        if restarts:
            print("restarts: " + ", ".join(f"{n} {k}" for n, k in sorted(restarts.items())))
    return code



"""The graph for ROS 2's launch system: ``ros2 launch homeo_robot world.launch.py world:=NAME``.

``launch/world.launch.py`` calls ``launch_description()``; the other launch files of ``launch/`` are
shortcuts that fix the world. The nodes, their parameters and the topology are ``launch.graph_specs``'s,
from the graph description, as ``homeo-launch`` starts them: one ``launch_ros`` Node per node of the
graph, the world's companions (a stand-in robot) as processes, and ``homeo-launch watch`` beside them,
which follows the run, prints the world's result and ends the launch with it. The world's parameters
and launch options are launch arguments generated from its declarations (``WorldBackend.PARAMS``,
``LAUNCH``); ``world.launch.py --show-args`` lists every installed world's.

What ``homeo-launch`` does and ROS launch does too: every message signed with a secret made for the
launch (removed at its end); a node that dies is respawned (``max_restarts`` times, 0.5 s apart) and
rejoins the run from its checkpoints (``respawn_rejoins``: it finds this launch's checkpoints); the
end of the run, Ctrl-C or the watcher's exit shut every node down with SIGINT, and each exits 0 after
its final checkpoint. A launch argument left empty leaves the parameter to ``params_file`` (a file
``ros2 param dump`` wrote, or ``config/params.yaml``) or to the node's default; the launch's own
settings (session, checkpoints, the recording's spool, which world, the intention node's mode) are
always the launch's. Needs ``launch`` and ``launch_ros`` (a ROS 2 install); pip-only installs run
``homeo-launch`` instead and never import this module.
"""

from __future__ import annotations

import json
import os

from homeo_decision.world_api import ITERATIONS, RATE, SEED, registered, world_class
from homeo_msgs_py.cli_args import user_path
from homeo_msgs_py.graph import GRAPH, NODES, WORLD
from homeo_msgs_py.learning import DOD, XI
from homeo_msgs_py.node_base import EXECUTOR
from homeo_msgs_py.params import ParamSpec

from .options import MAX_RESTARTS

PACKAGE = "homeo_robot"
RESPAWN_DELAY_S = 0.5
FLAGS = tuple(ParamSpec(n, False, n) for n in ("checkpoints", "json"))
# (name, default, description); '' = not given: the params file's value, else the node's (or the world's) default
COMMON = (
    ("seed", "", "seed of every component (default: the node's, 0)"),
    ("iterations", "", "ticks of the run, 0 = until Ctrl-C (default: the world's)"),
    ("rate", "", "ticks per second, 0 = as fast as the lockstep allows"),
    *((s.name, "", f"{s.doc}, Eq {s.eq} (default: the scenario's)") for s in (DOD, XI)),
    ("intention", "", "how the robot knows the user's intention (default: the world's first mode)"),
    ("namespace", "", "put the whole graph under /NAMESPACE"),
    ("data_dir", "out", "the nodes' data directory: relative files, and paths set while running, live here"),
    ("record", "", "record every topic as a rosbag2 bag (MCAP) in this new folder"),
    ("params_file", "", "a parameters file for every node (one ros2 param dump wrote, or config/params.yaml)"),
    ("scenario", "", "scenario JSON (default: the thesis scenario)"),
    ("load_q", "", "start from a Q-table file or a decision checkpoint"),
    ("save_q", "", "save the Q-table here at the end"),
    ("trace", "", "the world writes one JSON line per tick here"),
    ("checkpoints", "true", "write checkpoints under DATA_DIR/checkpoints (a respawned node rejoins from them)"),
    ("max_restarts", "3", MAX_RESTARTS.doc),
    ("executor", "", EXECUTOR.doc),
    ("json", "false", "print the result as JSON"),
)
# the arguments that name the user's files: '~' is their home, as on homeo-launch's command line
USER_PATHS = ("data_dir", "record", "load_q", "save_q", "trace", "scenario")


class LaunchArgError(ValueError):
    """A launch argument that cannot be used: launch prints it as the reason the launch failed."""


def world_args(world: str | None) -> dict:
    """The launch arguments of ``world``'s own parameters and launch options (every installed world's for
    None): name -> [(world, its doc of it)], each world's own (two worlds may share a name)."""
    out: dict = {}
    for name in ([world] if world else sorted(registered())):
        try:
            cls = world_class(name)
        except ValueError:
            continue  # a world that does not load: world:= says so when it is chosen
        for s in (*cls.PARAMS, *cls.LAUNCH):
            out.setdefault(s.name, []).append((name, f"{s.doc} (default {s.default!r})"))
    return out


def launch_description(world: str | None = None):
    """``world``: the world of a shortcut (sim.launch.py); None: ``world:=`` chooses (world.launch.py)."""
    from launch import LaunchDescription
    from launch.actions import DeclareLaunchArgument, OpaqueFunction

    args = list(COMMON) + ([] if world else [("world", "sim", f"the world: {', '.join(sorted(registered()))}")])
    args += [(n, "", "; ".join(f"({w}) {doc}" for w, doc in docs)) for n, docs in world_args(world).items()]
    return LaunchDescription([DeclareLaunchArgument(n, default_value=d, description=t) for n, d, t in args]
                             + [OpaqueFunction(function=_graph, kwargs={"world": world, "names": [a[0] for a in args]})])


def values(given: dict, world: str) -> dict:
    """The launch arguments checked by the declarations of what they set (one line each)."""
    from homeo_decision.world_api import WORLD_PARAMS, WorldConfigError
    from homeo_msgs_py.learning import LEARNING

    try:
        cls = world_class(world)
    except WorldConfigError as exc:
        raise LaunchArgError(f"launch argument world: {exc}") from None
    own = {s.name: s for s in (*cls.PARAMS, *cls.LAUNCH)}
    specs = {s.name: s for s in (*WORLD_PARAMS, *LEARNING, MAX_RESTARTS, EXECUTOR, *FLAGS, *own.values())}
    out = dict(given)
    for name, text in given.items():
        if text == "" or name not in specs and name not in world_args(None):
            continue
        if name not in specs:
            raise LaunchArgError(f"launch argument {name} is not one of world {world}'s "
                                 f"({', '.join(own) or 'it has none'})")
        try:
            out[name] = specs[name].parse(text)
        except ValueError as exc:
            raise LaunchArgError(f"launch argument {exc}") from None
    for name in USER_PATHS:  # expanded once, here: every later use takes them as they are
        if out.get(name):
            out[name] = user_path(out[name])
    from .processes import check_namespace

    try:  # '/r1' as the nodes and the recorder's topic list both need it, whether 'r1' or '/r1' was given
        out["namespace"] = check_namespace(out["namespace"])
    except ValueError as exc:
        raise LaunchArgError(f"launch argument {exc}") from None
    if out.get("params_file"):  # read by rcl in every node: judged by rcl here, before any node starts
        from homeo_msgs_py.node_base import ros_args_refusal

        refusal = ros_args_refusal(["--ros-args", "--params-file", out["params_file"]])
        if refusal is not None:
            raise LaunchArgError(f"launch argument params_file: {refusal}")
    modes = cls.INTENTIONS
    out["intention"] = out.get("intention") or next(iter(modes))
    if out["intention"] not in modes:
        raise LaunchArgError(f"launch argument intention must be one of {', '.join(modes)}, not {out['intention']!r}")
    return out


def plan(world: str, v: dict, workdir: str):
    """The world's plan for this launch (``WorldBackend.plan``) and the scenario it runs."""
    from homeo_decision.scenario import load_scenario

    cls = world_class(world)
    sc = load_scenario(v["scenario"] or None)
    given = {s.name: (v.get(s.name) if v.get(s.name, "") != "" else None) for s in (*cls.PARAMS, *cls.LAUNCH)}
    given.update(intention=v["intention"], load_q=v["load_q"] or None, seed=v["seed"] or 0,
                 scenario=v["scenario"] or None, iterations=v["iterations"] if v["iterations"] != "" else cls.TICKS[1])
    return cls, sc, cls.plan(sc, given, workdir), given


def node_params(world: str, v: dict, session: str, spool: str, plan_) -> dict:
    """Node name -> its parameters: the launch's own, the world's plan, and the launch arguments given
    (``v`` as ``values`` made it)."""
    from .launch import GraphOptions, graph_specs

    cls, _, p, _ = plan_
    data_dir = os.path.abspath(v["data_dir"])
    world_params = dict(_given(v, (RATE.name,)), **p.params)
    if v["iterations"] != "" or cls.TICKS[1] != ITERATIONS.default:  # not given: the world's default tick count
        world_params[ITERATIONS.name] = v["iterations"] if v["iterations"] != "" else cls.TICKS[1]
    if v.get("trace"):
        world_params["trace_path"] = os.path.abspath(v["trace"])
    o = GraphOptions(world=world, world_params=world_params, seed=v["seed"] or 0,
                     learning=_given(v, (DOD.name, XI.name)), intention=cls.INTENTIONS[v["intention"]],
                     scenario=p.scenario or (os.path.abspath(v["scenario"]) if v["scenario"] else ""),
                     overrides=tuple(p.overrides.items()), load_q=v["load_q"] or None, save_q=v["save_q"] or None,
                     data_dir=data_dir,
                     checkpoint_dir=os.path.join(data_dir, "checkpoints", world) if v["checkpoints"] else "",
                     session=session, max_restarts=v["max_restarts"])
    params = {s.name: s.params for s in graph_specs(o) if s.argv is None}
    for prm in params.values():
        for name in (SEED.name, EXECUTOR.name):
            if v[name] == "":
                prm.pop(name, None)  # not given: the params file's, or the node's
        prm["respawn_rejoins"] = bool(o.checkpoint_dir)
        if spool:
            prm["record_spool"] = spool
    return params


def _given(v: dict, names) -> dict:
    """The launch arguments of ``names`` that were given ('' = not given: left to the params file or the node)."""
    return {n: v[n] for n in names if v.get(n, "") != ""}


def _graph(context, world: str | None, names: list):
    import shutil
    import tempfile
    import uuid

    from launch.actions import EmitEvent, ExecuteProcess, RegisterEventHandler, SetEnvironmentVariable
    from launch.event_handlers import OnProcessExit, OnShutdown
    from launch.events import Shutdown
    from launch.substitutions import LaunchConfiguration
    from launch_ros.actions import Node
    from launch_ros.substitutions import ExecutableInPackage

    from homeo_msgs_py.auth import ENV as AUTH_ENV
    from homeo_msgs_py.auth import make_secret

    from .processes import dds_defaults

    given = {n: LaunchConfiguration(n).perform(context) for n in names}
    world = world or given.pop("world")
    v = values(given, world)
    ns = v["namespace"]
    session = uuid.uuid4().hex[:12]
    workdir = tempfile.mkdtemp(prefix=f"homeo-{world}-")
    plan_ = plan(world, v, workdir)
    cls, sc, p, launch_given = plan_
    spool = _recording(v, world, sc, p) if v["record"] else ""
    key_file, secret_dir = make_secret()  # the graph signs its messages (docs/SECURITY.md)
    actions = [SetEnvironmentVariable(AUTH_ENV, str(key_file))]
    actions += [SetEnvironmentVariable(k, val) for k, val in dds_defaults().items()]
    actions.append(RegisterEventHandler(OnShutdown(on_shutdown=lambda e, c: [shutil.rmtree(d, True)
                                                                               for d in (secret_dir, workdir)])))
    actions += [ExecuteProcess(cmd=list(c.argv), name=c.name, output="log") for c in p.companions]
    params = node_params(world, v, session, spool, plan_)
    files = [v["params_file"]] if v["params_file"] else []
    for name in GRAPH:
        actions.append(Node(package=PACKAGE, executable=NODES[name].executable, name=name, namespace=ns or None,
                            parameters=files + [params[name]], respawn=v["max_restarts"] > 0,
                            respawn_delay=RESPAWN_DELAY_S, respawn_max_retries=v["max_restarts"], output="log"))
    setting = {"intention": cls.INTENTIONS[v["intention"]], "learning": _given(v, (DOD.name, XI.name)),
               "values": {k: val for k, val in dict(launch_given, **p.params).items() if val is not None}}
    watch = ["watch", "--world", world, "--iterations", str(params[WORLD].get("iterations", ITERATIONS.default)),
             "--seed", str(v["seed"] or 0), "--setting", json.dumps(setting)]
    watch += (["--namespace", ns] if ns else []) + (["--scenario", v["scenario"]] if v["scenario"] else [])
    watch += (["--json"] if v["json"] else []) + (["--save-q", v["save_q"]] if v["save_q"] else [])
    watch += ["--record-spool", spool] if spool else []
    watcher = ExecuteProcess(cmd=[ExecutableInPackage("homeo-launch", PACKAGE), *watch], name="homeo_watch",
                             output="screen", emulate_tty=True)
    actions += [watcher, RegisterEventHandler(OnProcessExit(target_action=watcher, on_exit=[
        EmitEvent(event=Shutdown(reason="the run is over"))]))]
    return actions


def _recording(v: dict, world: str, sc, p) -> str:
    """A writers' spool folder for ``record`` (its manifest names the bag), made before the nodes start."""
    from homeo_record.record import WriterBag, check_new_bag, run_info
    from homeo_record.tap import tapped_topics

    bag = WriterBag(check_new_bag(v["record"]),
                    run_info(world, v.get("iterations") or 0, v["seed"] or 0, sc, {},
                             intention=world_class(world).INTENTIONS[v["intention"]]),
                    tapped_topics(namespace=v["namespace"]))
    folder = bag.prepare(os.path.abspath(v["data_dir"]))
    bag.own.close()  # the launch process sends nothing itself
    return folder

"""The graph for ROS 2's launch system: ``ros2 launch homeo_robot sim.launch.py`` and ``pepper.launch.py``.

The launch files (``launch/`` of the package) call ``launch_description``; the nodes, their
parameters and the topology are ``launch.graph_specs``'s, from the graph description, as
``homeo-launch`` starts them: one ``launch_ros`` Node per node of the graph, and ``homeo-launch
watch`` beside them, which follows the run, prints its result and ends the launch with it.

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

import os

from homeo_msgs_py.cli_args import user_path
from homeo_msgs_py.graph import BAYES, GRAPH, INTENTION_MODES, NODES, WORLD
from homeo_msgs_py.learning import DOD, XI

PACKAGE = "homeo_robot"
RESPAWN_DELAY_S = 0.5
# (name, default, description); '' = not given: the params file's value, else the node's default
COMMON = (
    ("seed", "", "seed of every component (default: the node's, 0)"),
    ("iterations", "", "ticks of the run, 0 = until Ctrl-C (default: the node's, 5000; pepper: 0)"),
    ("rate", "", "ticks per second, 0 = as fast as the lockstep allows"),
    *((s.name, "", f"{s.doc}, Eq {s.eq} (default: the scenario's)") for s in (DOD, XI)),
    ("namespace", "", "put the whole graph under /NAMESPACE"),
    ("data_dir", "out", "the nodes' data directory: relative files, and paths set while running, live here"),
    ("record", "", "record every topic as a rosbag2 bag (MCAP) in this new folder"),
    ("params_file", "", "a parameters file for every node (one ros2 param dump wrote, or config/params.yaml)"),
    ("scenario", "", "scenario JSON (default: the thesis scenario)"),
    ("load_q", "", "start from a Q-table file or a decision checkpoint"),
    ("save_q", "", "save the Q-table here at the end"),
    ("checkpoints", "true", "write checkpoints under DATA_DIR/checkpoints (a respawned node rejoins from them)"),
    ("max_restarts", "3", "respawn a node that dies up to this many times (0: a death ends the launch)"),
    ("json", "false", "print the result as JSON"),
)
WORLD_ARGS = {
    "sim": (("intention", BAYES, "bayes: recognise the intention; oracle: observe it (the thesis's simulation)"),
            ("human", "", "who plays the human: sim (default) or person (on homeo/human_input)"),
            ("human_timeout", "", "seconds a tick waits for the person"),
            ("trace", "", "the world writes one JSON line per tick here")),
    "pepper": (("intention", "cues", "cues: the config's keyword/gesture cues name the intention; bayes: recognise it"),
               ("qi_url", "tcp://127.0.0.1:9559", "the robot's NAOqi URL"),
               ("standin", "false", "start a stand-in Pepper on loopback instead of reaching a robot"),
               ("script", "", "the stand-in's scripted user (a file of pepper_bridge/scripts/ or a path)"),
               ("config", "", "the robot's meaning of the scenario's names (default pepper_bridge/scripts/pepper.json)")),
}
# the arguments that are node parameters as they stand, routed as homeo-launch routes them
# (GraphOptions.world_params and .learning); seed, the world's and the decision's, is node_params' own
WORLD_AS_PARAMS = ("iterations", "rate", "human", "human_timeout")
LEARNING_AS_PARAMS = (DOD.name, XI.name)
# the arguments that name the user's files: '~' is their home, as on homeo-launch's command line
USER_PATHS = ("data_dir", "record", "load_q", "save_q", "trace", "config")


class LaunchArgError(ValueError):
    """A launch argument that cannot be used: launch prints it as the reason the launch failed."""


def launch_description(world: str):
    from launch import LaunchDescription
    from launch.actions import DeclareLaunchArgument, OpaqueFunction

    args = COMMON + WORLD_ARGS[world]
    return LaunchDescription([DeclareLaunchArgument(n, default_value=d, description=t) for n, d, t in args]
                             + [OpaqueFunction(function=_graph, kwargs={"world": world, "names": [a[0] for a in args]})])


def values(given: dict, world: str) -> dict:
    """The launch arguments checked by the declarations of what they set (one line each)."""
    from homeo_decision.world_api import WORLD_PARAMS, world_class
    from homeo_msgs_py.learning import LEARNING
    from homeo_msgs_py.params import ParamSpec

    specs = {s.name: s for s in (*WORLD_PARAMS, *LEARNING, *world_class(world).PARAMS)}
    specs["max_restarts"] = ParamSpec("max_restarts", 3, "respawns", 0, 100)
    for flag in ("checkpoints", "json", "standin"):
        specs[flag] = ParamSpec(flag, False, flag)
    out = dict(given)
    for name, text in given.items():
        if text != "" and name in specs:
            try:
                out[name] = specs[name].parse(text)
            except ValueError as exc:
                raise LaunchArgError(f"launch argument {exc}") from None
    for name in USER_PATHS:  # expanded once, here: every later use takes them as they are
        if name in out:
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
    modes = intention_modes(world)
    if out["intention"] not in modes:
        raise LaunchArgError(f"launch argument intention must be one of {', '.join(modes)}, not {out['intention']!r}")
    return out


def intention_modes(world: str) -> dict:
    """``intention:=`` -> the intention node's mode, as ``homeo-launch sim`` or ``pepper`` takes ``--intention``."""
    if world == "pepper":
        from .pepper import INTENTION_MODES as PEPPER_MODES

        return PEPPER_MODES
    return {m: m for m in INTENTION_MODES}


def node_params(world: str, v: dict, session: str, spool: str) -> dict:
    """Node name -> its parameters: the launch's own, and the launch arguments given (``v`` as
    ``values`` made it, its ``script`` resolved by ``_graph``)."""
    from .launch import GraphOptions, graph_specs

    data_dir = os.path.abspath(v["data_dir"])
    world_params = _world_params(world, v)
    overrides = ()
    if world == "pepper" and v["standin"] and v["script"]:  # a scripted user
        from .pepper import script_drives

        world_params["end_with_script"] = True  # the run ends with it
        drives = script_drives(v["script"])  # its robot.drives: the initial drives
        overrides = (("initial_drives", dict(drives)),) if drives else ()
    o = GraphOptions(world=world, world_params=world_params, seed=v["seed"] or 0,
                     learning=_given(v, LEARNING_AS_PARAMS), intention=intention_modes(world)[v["intention"]],
                     scenario=os.path.abspath(v["scenario"]) if v["scenario"] else "", overrides=overrides,
                     load_q=v["load_q"] or None, save_q=v["save_q"] or None, data_dir=data_dir,
                     checkpoint_dir=os.path.join(data_dir, "checkpoints", world) if v["checkpoints"] else "",
                     session=session, max_restarts=v["max_restarts"])
    params = {s.name: s.params for s in graph_specs(o)}
    for p in params.values():
        if v["seed"] == "":
            p.pop("seed", None)  # not given: the params file's, or the node's
        p["respawn_rejoins"] = bool(o.checkpoint_dir)
        if spool:
            p["record_spool"] = spool
    return params


def _world_params(world: str, v: dict) -> dict:
    """The world node's parameters: the launch's own (the robot, the intention's source, the files)
    and the launch arguments given."""
    out = {"qi_url": v["qi_url"], "intention_cues": v["intention"] == "cues"} if world == "pepper" else {}
    if v.get("trace"):
        out["trace_path"] = os.path.abspath(v["trace"])
    if world == "pepper" and v["config"]:
        out["config"] = os.path.abspath(v["config"])
    return dict(out, **_given(v, WORLD_AS_PARAMS))


def _given(v: dict, names) -> dict:
    """The launch arguments of ``names`` that were given ('' = not given: left to the params file or the node)."""
    return {n: v[n] for n in names if v.get(n, "") != ""}


def _graph(context, world: str, names: list):
    import shutil
    import socket
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

    v = values({n: LaunchConfiguration(n).perform(context) for n in names}, world)
    ns = v["namespace"]
    session = uuid.uuid4().hex[:12]
    spool = _recording(v, world) if v["record"] else ""
    key_file, secret_dir = make_secret()  # the graph signs its messages (docs/SECURITY.md)
    actions = [SetEnvironmentVariable(AUTH_ENV, str(key_file))]
    actions += [SetEnvironmentVariable(k, val) for k, val in dds_defaults().items()]
    actions.append(RegisterEventHandler(OnShutdown(on_shutdown=lambda e, c: shutil.rmtree(secret_dir, True))))
    if world == "pepper" and v["standin"]:
        with socket.socket() as s:  # a free port on loopback for the stand-in, known before the nodes start
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]
        v["qi_url"] = f"tcp://127.0.0.1:{port}"
        cmd = [ExecutableInPackage("homeo-pepper-standin", PACKAGE), "--listen", v["qi_url"], "--time-scale", "0"]
        if v["script"]:  # resolved once: for the stand-in here and for the drives in node_params
            from .pepper import _script_path

            v["script"] = str(_script_path(v["script"]))
            cmd += ["--script", v["script"]]
        cmd += ["--seed", str(v["seed"] or 0)]
        actions.append(ExecuteProcess(cmd=cmd, name="pepper_standin", output="log"))
    params = node_params(world, v, session, spool)
    files = [v["params_file"]] if v["params_file"] else []
    for name in GRAPH:
        actions.append(Node(package=PACKAGE, executable=NODES[name].executable, name=name, namespace=ns or None,
                            parameters=files + [params[name]], respawn=v["max_restarts"] > 0,
                            respawn_delay=RESPAWN_DELAY_S, respawn_max_retries=v["max_restarts"], output="log"))
    watch = ["watch", "--world", world, "--iterations", str(params[WORLD].get("iterations", 0 if world == "pepper"
                                                                                    else 5000))]
    watch += ["--seed", str(v["seed"] or 0)] + (["--namespace", ns] if ns else [])
    watch += (["--scenario", v["scenario"]] if v["scenario"] else []) + (["--json"] if v["json"] else [])
    watch += (["--save-q", v["save_q"]] if v["save_q"] else []) + (["--record-spool", spool] if spool else [])
    watcher = ExecuteProcess(cmd=[ExecutableInPackage("homeo-launch", PACKAGE), *watch], name="homeo_watch",
                             output="screen", emulate_tty=True)
    actions += [watcher, RegisterEventHandler(OnProcessExit(target_action=watcher, on_exit=[
        EmitEvent(event=Shutdown(reason="the run is over"))]))]
    return actions


def _recording(v: dict, world: str) -> str:
    """A writers' spool folder for ``record`` (its manifest names the bag), made before the nodes start."""
    from homeo_decision.scenario import load_scenario

    from .record import WriterBag, check_new_bag, run_info
    from .tap import tapped_topics

    bag = WriterBag(check_new_bag(v["record"]),
                    run_info(world, v.get("iterations") or 0, v["seed"] or 0, load_scenario(v["scenario"] or None), {},
                             intention=v["intention"]), tapped_topics(namespace=v["namespace"]))
    folder = bag.prepare(os.path.abspath(v["data_dir"]))
    bag.own.close()  # the launch process sends nothing itself
    return folder

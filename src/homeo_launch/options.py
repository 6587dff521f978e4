"""The command-line options every graph command shares (any world's, ``homeo-launch NAME``), and their
checks before anything starts: the run's (seed, scenario, timeouts, output), the graph's (namespace,
data directory, authentication), checkpoints and restarts, the recorder and the live view (the
launcher's tap and its sinks), and the files the options name.
"""

from __future__ import annotations

import argparse
import os
import sys

from dataclasses import replace

from homeo_decision.durable import CHECKPOINT_EVERY
from homeo_msgs_py import data_dir
from homeo_msgs_py.cli_args import UserError, user_path
from homeo_msgs_py.node_base import EXECUTOR
from homeo_msgs_py.params import ParamSpec, add_flag

from .launch import PROG

MAX_RESTARTS = ParamSpec("max_restarts", 3, "restart a robot node that dies up to this many times (0: a death stops "
                         "the graph)", 0, 100)


def add_run_options(p, name: str) -> None:
    """What every graph command takes: seed, scenario, action timeout, logs and output, the graph's
    options, the recorder and the live view, checkpoints and restarts."""
    from homeo_decision.world_api import ACTION_TIMEOUT, SEED

    add_flag(p, replace(SEED, doc="seed of every component"), default=SEED.default)
    p.add_argument("--scenario", metavar="FILE", type=user_path, default=None,
                   help="scenario JSON (default: the thesis scenario)")
    add_flag(p, ACTION_TIMEOUT, default=ACTION_TIMEOUT.default)
    add_flag(p, EXECUTOR, default=EXECUTOR.default)
    p.add_argument("--log-dir", metavar="DIR", type=user_path,
                   help="keep each node's log here (default: a temporary directory)")
    p.add_argument("--json", action="store_true", help="print the run's result as JSON")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    add_graph_options(p)
    add_live_options(p)
    add_durable_options(p, name)


def add_graph_options(p) -> None:
    """``--namespace``, ``--data-dir`` and ``--no-auth``."""
    p.add_argument("--namespace", type=_namespace_arg, default="", metavar="NS",
                   help="put the whole graph (nodes, topics, services) under /NS, so several robots share a domain")
    p.add_argument("--data-dir", metavar="DIR", type=user_path, default=data_dir.default_dir(),
                   help="the nodes' data directory (default out, or $HOMEO_DATA_DIR): relative file parameters resolve in it, and a "
                        "path set while the graph runs (ros2 param set, a service) must lie in it")
    p.add_argument("--no-auth", action="store_true",
                   help="do not sign the graph's messages: for debugging with ros2 topic pub; anyone on the "
                        "domain can then steer the robot (docs/SECURITY.md)")


def _namespace_arg(text: str) -> str:
    from .processes import check_namespace

    try:
        return check_namespace(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def add_live_options(p) -> None:
    """--record and --foxglove: the launcher's tap and what it feeds."""
    p.add_argument("--record", metavar="DIR", type=user_path,
                   help="record every topic as a rosbag2 bag (MCAP) in this new folder")
    p.add_argument("--record-from", choices=("writers", "tap"), default="writers",
                   help="writers (default): each node keeps what it sends, merged into the bag after the run (stamped "
                        "when sent; costs the tick a few microseconds a message); tap: the launcher subscribes to "
                        "every topic (stamped when received, strangers' messages kept; costs the tick about 10-30%%)")
    p.add_argument("--foxglove", metavar="[HOST:]PORT", type=host_port, default=None,
                   help="serve the run live to the Foxglove app over WebSocket (host 127.0.0.1 unless given)")


def host_port(text: str) -> tuple[str, int]:
    """``PORT`` or ``HOST:PORT``; the host defaults to loopback (nothing leaves the machine unasked)."""
    host, _, port = text.rpartition(":")
    host = host.strip("[]") or "127.0.0.1"
    try:
        n = int(port)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not [HOST:]PORT") from None
    if not 0 <= n <= 65535:
        raise argparse.ArgumentTypeError(f"port {n} is outside 0..65535")
    return host, n


CHECKPOINT_ROOT = "checkpoints"  # under --data-dir



def add_durable_options(p, graph: str) -> None:
    g = p.add_argument_group("checkpoints and restarts")
    g.add_argument("--checkpoint-dir", metavar="DIR", type=user_path, default=None,
                   help=f"write the robot nodes' learned state here every --checkpoint-every ticks and at the end "
                        f"(inside --data-dir; default: DATA_DIR/{CHECKPOINT_ROOT}/NAMESPACE or {graph}, or the --resume "
                        f"folder)")
    add_flag(g, CHECKPOINT_EVERY, default=CHECKPOINT_EVERY.default)
    g.add_argument("--no-checkpoints", action="store_true", help="write no checkpoints (a restarted node starts fresh)")
    g.add_argument("--resume", metavar="DIR", type=user_path, default=None,
                   help="continue from the checkpoints in DIR: the Q-table, the intention model, the random "
                        "streams, and the learning schedule from the ticks learned")
    add_flag(g, MAX_RESTARTS, default=MAX_RESTARTS.default)


def durable_options(a, graph: str, sc, bayes: bool) -> dict:
    """SimOptions fields from the arguments; a resume folder that cannot be used is a UserError."""
    if a.no_checkpoints and a.checkpoint_dir:
        raise UserError("--checkpoint-dir and --no-checkpoints contradict each other")
    if a.resume and getattr(a, "load_q", None):
        raise UserError("--resume and --load-q: the checkpoint holds the Q-table; give one of them")
    if a.resume:
        check_resume(a.resume, sc, bayes)
    if a.no_checkpoints:
        ck_dir = ""
    else:
        ns = (getattr(a, "namespace", "") or "").strip("/").replace("/", "_")
        ck_dir = a.checkpoint_dir or a.resume or os.path.join(a.data_dir, CHECKPOINT_ROOT, ns or graph)
        if os.path.exists(ck_dir) and not os.path.isdir(ck_dir):
            raise UserError(f"--checkpoint-dir {ck_dir}: not a directory")
    return {"checkpoint_dir": ck_dir, "checkpoint_every": a.checkpoint_every, "resume": a.resume,
            "max_restarts": a.max_restarts}


def check_resume(d: str, sc, bayes: bool) -> None:
    """Every checkpoint a resumed run needs is there and loads into this scenario (one-line errors
    here, not in the nodes)."""
    from homeo_decision import checkpoint

    if not os.path.isdir(d):
        raise UserError(f"--resume {d}: no such directory")
    try:
        p = checkpoint.path_for(d, "homeo_decision")
        checkpoint.check_decision(sc, checkpoint.load(p, "homeo_decision"), str(p))
        if bayes:
            from homeo_intention.checkpoint import restore_intention
            from homeo_intention.model import IntentionModel

            p = checkpoint.path_for(d, "homeo_intention")
            restore_intention(IntentionModel(sc), checkpoint.load(p, "homeo_intention"), "bayes", str(p))
    except checkpoint.CheckpointError as exc:
        raise UserError(f"--resume: {exc}") from None


def check_files(a, write=(), tables=(), sc=None) -> None:
    """The file options of a launch, before anything starts: the Q-tables (``tables``) existing and
    loading into the scenario ``sc`` (a Q-table file or a decision checkpoint), the ones written not
    a directory and in a folder that exists or can be made; ``--log-dir`` writable. Raises
    UserError (one line). They may lie anywhere: the user's own command line is trusted (the data
    directory confines only what arrives over the network, ``homeo_msgs_py.data_dir``); ``~`` is
    expanded already (``cli_args.user_path``)."""
    tables = [(opt, f) for opt, f in tables if f]
    for opt, f in tables:  # every missing file first, then what does not load
        if not os.path.isfile(f):
            raise UserError(f"{opt} {f}: file not found")
    for opt, f in tables:
        from homeo_decision.checkpoint import load_table
        from homeo_decision.objectq import ObjectQ

        load_table(ObjectQ(sc), f)  # QTableError: one line, exit 2
    for opt, f in write:
        if not f:
            continue
        if os.path.isdir(f):
            raise UserError(f"{opt} {f} is a directory, not a file")
        try:
            os.makedirs(os.path.dirname(os.path.abspath(f)), exist_ok=True)
        except OSError as exc:
            raise UserError(f"{opt} {f}: {exc.strerror}") from None
    if getattr(a, "log_dir", None):
        try:
            os.makedirs(a.log_dir, exist_ok=True)
        except OSError as exc:
            raise UserError(f"--log-dir {a.log_dir}: {exc.strerror}") from None
        if not os.access(a.log_dir, os.W_OK | os.X_OK):
            raise UserError(f"--log-dir {a.log_dir} is not writable")


def open_sinks(a, world: str, iterations: int, seed: int, sc, overrides, inputs=(), **extra) -> list:
    """The tap's sinks the command line asks for: ``--record DIR`` (a bag), ``--foxglove`` (live; its
    client may publish the topics the world reads from outside, ``inputs``)."""
    from homeo_record.tap import tapped_topics

    topics = tapped_topics(namespace=getattr(a, "namespace", ""))
    sinks = []
    try:
        if getattr(a, "record", None):
            from homeo_record.record import check_new_bag, new_bag, run_info

            sinks.append(new_bag(check_new_bag(a.record), run_info(world, iterations, seed, sc, overrides, **extra),
                                 topics, getattr(a, "record_from", "writers")))
        if getattr(a, "foxglove", None):
            from homeo_record.live import FoxgloveSink

            sinks.append(FoxgloveSink(a.foxglove, sc, topics, person="human_input" in inputs))
            if not getattr(a, "quiet", False):
                print(f"{PROG}: Foxglove: open ws://{a.foxglove[0]}:{sinks[-1].port}", file=sys.stderr)
    except BaseException:
        close_sinks(sinks)
        raise
    return sinks


def close_sinks(sinks) -> None:
    for s in sinks:
        s.close()

"""Starting and stopping a graph of node processes (no rclpy here).

Each node runs as ``python -m MODULE --ros-args --params-file FILE`` in its own session,
so a Ctrl-C at the terminal reaches the launcher alone and the launcher stops the nodes
in order. Nodes also get PR_SET_PDEATHSIG (``HOMEO_PARENT_PID``) so they cannot outlive a
launcher that was killed outright. Each node's output goes to a log file; when a node
dies, the launcher shows its last lines.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from homeo_msgs_py.auth import ENV as AUTH_ENV
from homeo_msgs_py.auth import load_signer, make_secret
from homeo_msgs_py.qos import dds_defaults  # noqa: F401 - the launchers' and tests' import

STOP_GRACE_S = 3.0  # SIGINT, then SIGTERM, then SIGKILL: the whole stop stays under 5 s


@dataclass
class NodeSpec:
    name: str  # the ROS node name, also the log file's name
    module: str  # python -m MODULE
    params: dict = field(default_factory=dict)
    args: list = field(default_factory=list)  # extra command-line arguments before --ros-args
    argv: list | None = None  # a companion of the graph (a stand-in robot): its own command line, not a node


def graph_env(domain_id: int | None = None) -> dict:
    """The environment of a graph: discovery kept on this machine unless the user chose otherwise."""
    env = dict(os.environ)
    env.update(dds_defaults(env))
    if domain_id is not None:
        env["ROS_DOMAIN_ID"] = str(domain_id)
    env["PYTHONUNBUFFERED"] = "1"
    return env


class Graph:
    """``auth``: the graph signs its messages with a secret made here (``homeo_msgs_py.auth``);
    ``namespace``: every node (and so every topic and service) under ``/namespace``."""

    def __init__(self, specs: list[NodeSpec], env: dict | None = None, log_dir: str | None = None,
                 namespace: str = "", auth: bool = True):
        self.specs = specs
        self.env = dict(env or graph_env())
        self.env["HOMEO_PARENT_PID"] = str(os.getpid())
        self.namespace = check_namespace(namespace)
        self._tmp = None
        self._auth_dir = None
        self.signer = None
        self.env.pop(AUTH_ENV, None)
        if auth:
            key_file, self._auth_dir = make_secret()
            self.env[AUTH_ENV] = str(key_file)
            self.signer = load_signer(self.env)
        if log_dir is None:
            self._tmp = tempfile.TemporaryDirectory(prefix="homeo-graph-")
            log_dir = self._tmp.name
        self.log_dir = Path(log_dir)
        self.log_dir.mkdir(parents=True, exist_ok=True)
        self.procs: dict[str, subprocess.Popen] = {}

    def start(self, names=None) -> None:
        """Start the nodes ``names`` (default: all) that are not started yet."""
        for s in self.specs:
            if s.name in self.procs or (names is not None and s.name not in names):
                continue
            cmd = list(s.argv or ())
            if s.argv is None:
                pfile = self.log_dir / f"{s.name}.params.json"
                # JSON is YAML: rcl reads it as a parameters file; strings stay strings
                pfile.write_text(json.dumps({"/**": {"ros__parameters": s.params}}))  # this node's file alone
                cmd = [sys.executable, "-m", s.module, *s.args, "--ros-args", "--params-file", str(pfile)]
                if self.namespace:
                    cmd += ["-r", f"__ns:={self.namespace}"]
            log = open(self.log_dir / f"{s.name}.log", "wb")
            self.procs[s.name] = subprocess.Popen(cmd, env=self.env, stdin=subprocess.DEVNULL, stdout=log,
                                                  stderr=subprocess.STDOUT, start_new_session=True)
            log.close()

    def pids(self) -> dict[str, int]:
        return {n: p.pid for n, p in self.procs.items()}

    def dead(self) -> tuple[str, int] | None:
        """The first node that has exited, with its exit code."""
        for n, p in self.procs.items():
            code = p.poll()
            if code is not None:
                return n, code
        return None

    def log_tail(self, name: str, lines: int = 12) -> str:
        try:
            text = (self.log_dir / f"{name}.log").read_text(errors="replace")
        except OSError:
            return ""
        return "\n".join(text.rstrip().splitlines()[-lines:])

    def rss_mb(self) -> float:
        """Resident memory of all node processes, in MiB (from /proc)."""
        from homeo_record.procfs import rss_mb

        nodes = {s.name for s in self.specs if s.argv is None}
        return sum(rss_mb(p.pid) or 0.0 for n, p in self.procs.items() if n in nodes)

    def stop(self) -> dict[str, int | None]:
        """SIGINT every node, then SIGTERM / SIGKILL the ones that linger; returns exit codes."""
        live = [p for p in self.procs.values() if p.poll() is None]
        for p in live:
            _signal(p, signal.SIGINT)
        deadline = time.monotonic() + STOP_GRACE_S
        for sig, until in ((signal.SIGTERM, deadline), (signal.SIGKILL, deadline + 1.0)):
            for p in live:
                try:
                    p.wait(timeout=max(0.0, until - time.monotonic()))
                except subprocess.TimeoutExpired:
                    _signal(p, sig)
        for p in live:
            try:
                p.wait(timeout=1.0)
            except subprocess.TimeoutExpired:
                pass
        return {n: p.returncode for n, p in self.procs.items()}

    def close(self) -> None:
        if self._tmp is not None:
            self._tmp.cleanup()
            self._tmp = None
        if self._auth_dir is not None:
            shutil.rmtree(self._auth_dir, ignore_errors=True)
            self._auth_dir = None


def check_namespace(ns: str) -> str:
    """``r1`` or ``/r1/a`` -> ``/r1`` / ``/r1/a``; '' stays ''. ROS names: letters, digits and '_',
    not starting with a digit (design.ros2.org/articles/topic_and_service_names.html)."""
    if not ns:
        return ""
    parts = ns.strip("/").split("/")
    for part in parts:
        if not part or not (part[0].isalpha() or part[0] == "_") or not all(c.isalnum() or c == "_" for c in part) \
                or not part.isascii():
            raise ValueError(f"namespace {ns!r} is not a ROS name (letters, digits and _, separated by /)")
    return "/" + "/".join(parts)


def _signal(p: subprocess.Popen, sig: int) -> None:
    try:
        os.killpg(p.pid, sig)  # the node's whole session: nothing it started survives
    except (ProcessLookupError, PermissionError):
        pass

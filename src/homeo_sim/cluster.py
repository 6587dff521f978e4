"""A study's runs as Ray tasks on a cluster (``--cluster ADDRESS``; Ray is the ``cluster`` extra).

Each run is one task; a task whose node dies is run again elsewhere (Ray's retries), and since a run is
seeded by its own arguments it gives the same result wherever and whenever it runs. A node whose code
differs from the driver's (``code_digest``, also the key of kept runs) is refused: its numbers could differ. Nothing here
imports Ray before a study asks for a cluster.
"""

from __future__ import annotations

import argparse
import functools
import hashlib
import os
import re
import socket
import subprocess
import sys
import threading
import time
from collections import deque
from pathlib import Path

from homeo_msgs_py.cli_args import UserError

INSTALL = "pip install '.[cluster]' (in a checkout: make cluster-setup)"
CONNECT_WAIT = 30.0  # s: how long an address may take to answer as a Ray cluster (a busy machine's included)
RETRIES = 3  # a task lost with its node is run again this many times
NODES_WINDOW = 10.0  # s: a node is in use if it finished a run this recently
PACKAGES = ("homeo_sim", "homeo_decision", "homeo_intention", "homeo_msgs_py")  # what a run's numbers depend on


@functools.lru_cache(maxsize=1)
def code_digest() -> str:
    """Digest of the packages' sources and scenarios: a kept job (or a cluster node) of other code differs."""
    import importlib

    h = hashlib.sha256()
    for pkg in PACKAGES:
        root = Path(importlib.import_module(pkg).__file__).parent
        for f in sorted(p for p in root.rglob("*") if p.suffix in (".py", ".json")):
            h.update(f.relative_to(root).as_posix().encode() + b"\0" + f.read_bytes())
    return h.hexdigest()[:16]


class ClusterError(UserError):
    """The cluster cannot be reached or cannot run the study (``str()``: one line)."""


_HOST = r"(?:[A-Za-z0-9](?:[A-Za-z0-9.-]{0,251}[A-Za-z0-9])?|\[[0-9A-Fa-f:.]{2,45}\])"


def address(s: str) -> str:
    """``auto``, ``HOST:PORT`` or ``ray://HOST:PORT`` (argparse type)."""
    m = re.fullmatch(rf"(ray://)?({_HOST}):(\d{{1,5}})", s)
    if s != "auto" and not (m and 1 <= int(m[3]) <= 65535):
        raise argparse.ArgumentTypeError(f"{s[:60]!r} is not auto, HOST:PORT or ray://HOST:PORT")
    return s


def _ray():
    # on these machines a 127.0.0.1 cluster must stay on 127.0.0.1 (else Ray swaps in the interface address)
    os.environ.setdefault("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER", "0")
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
    try:
        import ray
    except ImportError:
        raise ClusterError(f"--cluster needs Ray: {INSTALL}") from None
    return ray


def _probe(addr: str) -> None:
    """A bounded wait for ``addr`` to answer (Ray's own connect retries for minutes)."""
    host, _, port = addr.removeprefix("ray://").rpartition(":")
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=CONNECT_WAIT).close()
    except OSError as exc:
        raise ClusterError(f"cannot reach the Ray cluster at {addr}: {exc.strerror or exc}") from None
    if addr.startswith("ray://"):
        return  # Ray client: its own connect gives up on its own
    # asked from a process of its own: one that cannot be stopped otherwise, and whose retries print warnings
    ask = f"import ray._raylet as r; r.GcsClient(address={addr!r}).internal_kv_get(b'session_name', b'session', timeout=5)"
    try:
        ok = subprocess.run([sys.executable, "-c", ask], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            timeout=CONNECT_WAIT).returncode == 0
    except subprocess.TimeoutExpired:
        ok = False
    if not ok:
        raise ClusterError(f"{addr} does not answer as a Ray cluster within {CONNECT_WAIT:g} s")


_CONNECTING = threading.Lock()  # a search's parallel trials connect at once
_TASK: list = []  # the remote function, made once connected


def connect(addr: str):
    """Ray, connected to the cluster at ``addr`` (once per process)."""
    with _CONNECTING:
        return _connect(addr)


def _connect(addr: str):
    ray = _ray()
    if not ray.is_initialized():
        if addr == "auto":
            try:
                addr = ray._private.services.canonicalize_bootstrap_address_or_die("auto")
            except ConnectionError:
                raise ClusterError("--cluster auto: no running Ray cluster on this machine "
                                   "(ray start --head, or give HOST:PORT)") from None
        _probe(addr)
        import logging

        # Ray prints the cluster's news (a node died, with the node's state dump) on stdout, which is the
        # study's (--json): its first line, to stderr
        w = ray._private.worker
        w.print_to_stdstream = lambda data, _print=w.print_to_stdstream, **kw: _print(
            {**data, "is_err": True, "lines": [str(ln).split("\n")[0][:200] for ln in data["lines"]]}, **kw)
        try:
            ray.init(address=addr, logging_level=logging.ERROR, log_to_driver=False)
        except (ConnectionError, RuntimeError, ValueError) as exc:
            raise ClusterError(f"cannot join the Ray cluster at {addr}: {str(exc).splitlines()[0][:160]}") from None
    if not _TASK:
        _TASK.append(ray.remote(max_retries=RETRIES)(_on_node))
    return ray


def cpus(addr: str) -> int:
    return int(connect(addr).cluster_resources().get("CPU", 0))


def _on_node(fn, a):
    import ray

    return ray.get_runtime_context().get_node_id(), code_digest(), fn(a)


def run_tasks(addr: str, fn, todo: list, done, interrupted: list) -> None:
    """``done(i, fn(a), note)`` for each ``(i, a)`` of ``todo`` run as a task; Ctrl-C cancels the rest."""
    ray = connect(addr)
    refs = {_TASK[0].remote(fn, a): i for i, a in todo}
    pending, recent = list(refs), deque()
    try:
        while pending:
            if interrupted:
                raise KeyboardInterrupt
            ready, pending = ray.wait(pending, num_returns=min(len(pending), 64), timeout=0.2)
            for ref in ready:
                try:
                    node, code, r = ray.get(ref)
                except ray.exceptions.RayTaskError as exc:  # the run's own error, as it would be locally
                    raise exc.as_instanceof_cause() from None
                except ray.exceptions.RayError as exc:
                    raise ClusterError(f"a run failed on the cluster after {RETRIES} retries: "
                                       f"{type(exc).__name__}: {str(exc).splitlines()[0][:120]}") from None
                if code != code_digest():
                    raise ClusterError(f"node {node[:8]} runs other code than this one ({code} vs {code_digest()}): "
                                       "install the same homeo-robot on every node")
                now = time.monotonic()
                recent.append((now, node))
                while recent[0][0] < now - NODES_WINDOW:
                    recent.popleft()
                n = len({nd for _, nd in recent})
                done(refs[ref], r, f"{n} node{'s' if n > 1 else ''}")
    except BaseException:
        for ref in pending:
            try:
                ray.cancel(ref, force=True)
            except Exception:  # noqa: BLE001 (finished meanwhile)
                pass
        if pending:
            print(f"cancelled the study's {len(pending)} unfinished tasks on the cluster", file=sys.stderr)
        raise

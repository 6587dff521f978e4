"""Independent jobs on all cores or on a Ray cluster, results in submission order, clean on Ctrl-C,
each finished job kept on disk when asked.

Each job is seeded by its own arguments, so results depend neither on the worker count nor on the
order jobs finish in: they are put back by their place in ``args``. Workers ignore SIGINT: Ctrl-C is
the parent's to handle, which cancels what has not started (on a cluster: every unfinished task) and
says how many finished jobs are kept. ``Pool(keep=DIR)`` writes each job's result to DIR as it
finishes (atomically, keyed by the job's own arguments and the code's digest); the same call again
loads those and runs only the missing jobs.
"""

from __future__ import annotations

import argparse
import base64
import dataclasses
import hashlib
import json
import os
import signal
import sys
import threading
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from pathlib import Path
from typing import Callable, Sequence, TypeVar

from .cluster import address, code_digest, cpus, run_tasks

A = TypeVar("A")
R = TypeVar("R")


@dataclasses.dataclass(frozen=True)
class Pool:
    """Where a study's jobs run: ``workers`` local processes (default: all cores), or the Ray cluster at
    ``cluster`` (``homeo_sim.cluster.address``); ``keep``: a folder that keeps each finished job."""

    workers: int | None = None
    cluster: str | None = None
    keep: str | Path | None = None


def add_cluster_argument(p: argparse.ArgumentParser) -> None:
    """``--cluster ADDRESS``: the one definition every study command and search shares."""
    p.add_argument("--cluster", metavar="ADDRESS", type=address, default=None,
                   help="run on the Ray cluster at ADDRESS (auto, HOST:PORT or ray://HOST:PORT; pip install "
                        "'.[cluster]'); default: local processes")


def slots(workers: int | Pool | None, jobs: int) -> int:
    """How many jobs run at once: the local processes, or the cluster's CPUs."""
    pool = workers if isinstance(workers, Pool) else Pool(workers)
    if pool.cluster:
        return cpus(pool.cluster)
    return max(1, min(pool.workers or os.cpu_count() or 1, jobs or 1))


def _ignore_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def parallel_map(fn: Callable[[A], R], args: Sequence[A], workers: int | Pool | None = None, bar=None) -> list[R]:
    """``[fn(a) for a in args]`` on ``workers`` processes (default: all cores) or as a ``Pool`` says;
    ``bar`` (a tqdm bar) counts finished jobs and, on a cluster, shows the nodes in use."""
    pool = workers if isinstance(workers, Pool) else Pool(workers)
    args = list(args)
    kept = Kept(pool.keep, fn, args) if pool.keep else None
    results: dict[int, R] = kept.load() if kept else {}
    if bar is not None and results:
        bar.n = bar.initial = len(results)  # runs/s counts this run's runs only
        bar.refresh()

    def done(i: int, r: R, note: str | None = None) -> None:
        results[i] = r
        if kept:
            kept.put(i, r)
        if bar is not None:
            if note:
                bar.set_postfix_str(note, refresh=False)
            bar.update(1)

    todo = [(i, a) for i, a in enumerate(args) if i not in results]
    # Ctrl-C only sets a flag, checked between waits: a KeyboardInterrupt raised inside the pool's
    # own bookkeeping (submit, process start-up) can leave shutdown() waiting forever
    interrupted: list = []
    main_thread = threading.current_thread() is threading.main_thread()
    old = signal.signal(signal.SIGINT, lambda *_: interrupted.append(1)) if main_thread else None
    try:
        if pool.cluster and todo:  # all kept: no need of the cluster
            run_tasks(pool.cluster, fn, todo, done, interrupted)
        else:
            _run_local(fn, todo, pool.workers, done, interrupted)
    except KeyboardInterrupt:
        where = f"kept in {kept.dir}" if kept else "finished (none kept: --out DIR keeps them)"
        print(f"interrupted: {len(results)} of {len(args)} runs {where}", file=sys.stderr)
        raise
    finally:
        if main_thread:
            signal.signal(signal.SIGINT, old)
    return [results[i] for i in range(len(args))]


def _run_local(fn, todo: list, workers: int | None, done, interrupted: list) -> None:
    workers = max(1, min(workers or os.cpu_count() or 1, len(todo) or 1))
    if workers == 1:
        for i, a in todo:
            if interrupted:
                raise KeyboardInterrupt
            done(i, fn(a))
        return
    pool = ProcessPoolExecutor(max_workers=workers, initializer=_ignore_sigint)
    try:
        futs = {}
        for i, a in todo:
            if interrupted:
                raise KeyboardInterrupt
            futs[pool.submit(fn, a)] = i
        pending = set(futs)
        while pending:
            if interrupted:
                raise KeyboardInterrupt
            finished, pending = wait(pending, timeout=0.1, return_when=FIRST_COMPLETED)
            for f in finished:
                done(futs[f], f.result())
    except BaseException:
        pool.shutdown(wait=True, cancel_futures=True)
        raise
    pool.shutdown(wait=True)


# -- kept jobs ---------------------------------------------------------------------------

def _plain(x):
    if dataclasses.is_dataclass(x):
        return {"": type(x).__name__, **{f.name: _plain(getattr(x, f.name)) for f in dataclasses.fields(x)}}
    if isinstance(x, dict):
        return {str(k): _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if type(x).__module__ == "numpy":
        import numpy as np

        a = np.asarray(x)
        return {"dtype": a.dtype.str, "shape": list(a.shape), "b64": base64.b64encode(a.tobytes()).decode()}
    return x


ARRAY_TYPES = ("<f4", "<f8", "<i4", "<i8", "|b1")
KEPT_TYPES: dict[str, type] = {}  # the dataclasses a kept job may hold (``keeps``)


def keeps(cls: type) -> type:
    """Class decorator: results of this dataclass may be kept (and decoded back)."""
    KEPT_TYPES[cls.__name__] = cls
    return cls


def _typed(x, types: dict):
    """``_plain``'s inverse for the dataclasses of ``types`` and numpy arrays; ValueError on anything else."""
    if isinstance(x, list):
        return [_typed(v, types) for v in x]
    if not isinstance(x, dict):
        return x
    if "b64" in x:
        import numpy as np

        if x.get("dtype") not in ARRAY_TYPES:
            raise ValueError("not an array of a kept run")
        a = np.frombuffer(base64.b64decode(x["b64"], validate=True), x["dtype"]).reshape(x["shape"]).copy()
        return a[()] if a.ndim == 0 else a  # a numpy scalar stays one
    d = {k: _typed(v, types) for k, v in x.items() if k != ""}
    if "" in x:
        if x[""] not in types:
            raise ValueError(f"not a kept run's type: {str(x[''])[:40]!r}")
        return types[x[""]](**d)
    return d


class Kept:
    """The jobs of one ``parallel_map`` kept under ``DIR/<code digest>/<job key>.json``: a job's key is the
    digest of its function and arguments (and the content of a scenario file they name; a shipped
    scenario's name is in the code's digest)."""

    def __init__(self, root, fn, args: list):
        self.dir = Path(root) / code_digest()
        self.dir.mkdir(parents=True, exist_ok=True)
        self.keys = [self.key(fn, a) for a in args]

    @staticmethod
    def key(fn, a) -> str:
        cfg = a[0] if isinstance(a, tuple) and a else a
        scenario = getattr(cfg, "scenario", None)
        text = Path(scenario).read_bytes() if isinstance(scenario, str) and Path(scenario).is_file() else b""
        blob = json.dumps([fn.__module__, fn.__qualname__, _plain(a)], sort_keys=True, default=repr)
        return hashlib.sha256(blob.encode() + b"\0" + text).hexdigest()[:32]

    def load(self) -> dict:
        """The jobs already kept (a file that does not decode is run again)."""
        out = {}
        for i, k in enumerate(self.keys):
            f = self.dir / f"{k}.json"
            if f.is_file():
                try:
                    out[i] = _typed(json.loads(f.read_text()), KEPT_TYPES)
                except (ValueError, TypeError, KeyError, AttributeError, RecursionError):
                    continue
        return out

    def put(self, i: int, r) -> None:
        f = self.dir / f"{self.keys[i]}.json"
        tmp = f.with_name(f"{f.name}.{os.getpid()}.tmp")
        tmp.write_text(json.dumps(_plain(r)))
        os.replace(tmp, f)  # a job is kept whole or not at all

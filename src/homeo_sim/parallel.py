"""Independent jobs on all cores, results in submission order, clean on Ctrl-C.

Each job is seeded by its own arguments, so results do not depend on the worker count.
Workers ignore SIGINT: Ctrl-C is the parent's to handle, which cancels what has not
started and waits only for the jobs already running (one per worker).
"""

from __future__ import annotations

import os
import signal
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from typing import Callable, Sequence, TypeVar

A = TypeVar("A")
R = TypeVar("R")


def _ignore_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def parallel_map(fn: Callable[[A], R], args: Sequence[A], workers: int | None = None,
                 on_done: Callable[[R], None] | None = None) -> list[R]:
    """``[fn(a) for a in args]`` on ``workers`` processes (default: all cores)."""
    args = list(args)
    workers = max(1, min(workers or os.cpu_count() or 1, len(args) or 1))
    if workers == 1:
        out = []
        for a in args:
            out.append(fn(a))
            if on_done:
                on_done(out[-1])
        return out
    results: dict[int, R] = {}
    pool = ProcessPoolExecutor(max_workers=workers, initializer=_ignore_sigint)
    try:
        futs = {pool.submit(fn, a): i for i, a in enumerate(args)}
        pending = set(futs)
        while pending:
            finished, pending = wait(pending, return_when=FIRST_COMPLETED)
            for f in finished:
                results[futs[f]] = f.result()
                if on_done:
                    on_done(results[futs[f]])
    except BaseException:
        pool.shutdown(wait=True, cancel_futures=True)
        raise
    pool.shutdown(wait=True)
    return [results[i] for i in range(len(args))]

"""Independent jobs on all cores, results in submission order, clean on Ctrl-C.

Each job is seeded by its own arguments, so results do not depend on the worker count.
Workers ignore SIGINT: Ctrl-C is the parent's to handle, which cancels what has not
started and waits only for the jobs already running (one per worker).
"""

from __future__ import annotations

import os
import signal
import threading
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
    # Ctrl-C only sets a flag, checked between waits: a KeyboardInterrupt raised inside the pool's
    # own bookkeeping (submit, process start-up) can leave shutdown() waiting forever
    interrupted = []
    main_thread = threading.current_thread() is threading.main_thread()
    old = signal.signal(signal.SIGINT, lambda *_: interrupted.append(1)) if main_thread else None
    pool = ProcessPoolExecutor(max_workers=workers, initializer=_ignore_sigint)
    try:
        futs = {}
        for i, a in enumerate(args):
            if interrupted:
                raise KeyboardInterrupt
            futs[pool.submit(fn, a)] = i
        pending = set(futs)
        while pending:
            if interrupted:
                raise KeyboardInterrupt
            finished, pending = wait(pending, timeout=0.1, return_when=FIRST_COMPLETED)
            for f in finished:
                results[futs[f]] = f.result()
                if on_done:
                    on_done(results[futs[f]])
    except BaseException:
        pool.shutdown(wait=True, cancel_futures=True)
        raise
    finally:
        if main_thread:
            signal.signal(signal.SIGINT, old)
    pool.shutdown(wait=True)
    return [results[i] for i in range(len(args))]

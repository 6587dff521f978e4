"""Checkpoints written off the tick's path (no rclpy): the tick hands over a snapshot, a thread writes it.

A node's tick takes a snapshot of its state (a copy sharing nothing the node goes on changing, or
a call that builds the envelope from such a copy) and hands it to its ``BackgroundWriter``; the
writer's one thread serialises it, writes it and syncs it (``jsonfile.write_atomic``, or a slot of
``checkpoint.SlotWriter``), so a slow disk slows the writer, never the lockstep. The files stay
what they were: atomic, checked on load. Each checkpoint supersedes the one before, so a snapshot
still waiting when a newer one comes is dropped (counted): the writer is never more than one
write behind. ``flush`` waits for what was handed over (the final checkpoint at shutdown).
"""

from __future__ import annotations

import threading
from typing import Callable


class BackgroundWriter:
    """One thread that calls ``write(snapshot)`` for the newest snapshot handed over. ``write``
    reports its own failures (``checkpoint.Checkpointer`` counts and logs them); anything it raises
    anyway is kept in ``error`` and the thread goes on."""

    def __init__(self, write: Callable[[object], None], name: str = "checkpoint-writer"):
        self._write = write
        self._cv = threading.Condition()
        self._pending = None
        self._has_pending = self._busy = self._closed = False
        self.superseded = 0  # snapshots dropped for a newer one before they were written
        self.error: BaseException | None = None
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()

    def submit(self, snapshot) -> None:
        with self._cv:
            if self._closed:
                raise RuntimeError("the checkpoint writer is closed")
            self.superseded += self._has_pending
            self._pending, self._has_pending = snapshot, True
            self._cv.notify_all()

    def _run(self) -> None:
        while True:
            with self._cv:
                self._cv.wait_for(lambda: self._has_pending or self._closed)
                if not self._has_pending:
                    return  # closed, nothing left
                snap, self._pending, self._has_pending = self._pending, None, False
                self._busy = True
            try:
                self._write(snap)
            except Exception as exc:  # noqa: BLE001 - the writer outlives a bug in one write
                self.error = exc
            finally:
                with self._cv:
                    self._busy = False
                    self._cv.notify_all()

    def idle(self) -> bool:
        with self._cv:
            return not (self._has_pending or self._busy)

    def flush(self, timeout: float | None = None) -> bool:
        """Wait until everything handed over is written; False if ``timeout`` ran out first."""
        with self._cv:
            return self._cv.wait_for(lambda: not (self._has_pending or self._busy), timeout)

    def close(self, timeout: float | None = None) -> bool:
        """Write what is pending, then end the thread; False if it had not ended within ``timeout``."""
        with self._cv:
            self._closed = True
            self._cv.notify_all()
        self._thread.join(timeout)
        return not self._thread.is_alive()

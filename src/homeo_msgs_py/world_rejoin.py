"""Where a restarted world node goes on with its run (no rclpy).

The world node holds the run: when it dies, the robot nodes stay where they were, each with the
newest tick it answered. Their answers are latched (``homeo/intention``, ``homeo/drives`` are
state topics: a new reader gets the last one), so the restarted world learns from them the newest
tick the robot took in and goes on with the next one. Going back to its checkpoint's tick instead
would hand the robot nodes ticks they have already answered (stale to their joins); the ticks
between the checkpoint and that point are lost and counted as missed.
"""

from __future__ import annotations

from .schemas import Message

LATCHED = ("intention", "drives")  # the robot nodes' latched answers (graph.TOPICS keys)
WAIT_S = 3.0  # after the start gate, how long to wait for a latched answer that has not come


class RejoinPoint:
    """``run``: the checkpoint's run (None: no checkpoint, take the robot's); ``floor``: its tick,
    the earliest the world can go on at (its environment stands there)."""

    def __init__(self, run: int | None, floor: int = 0):
        self.run, self.floor = run, floor
        self.heard: dict[str, tuple[int, int]] = {}  # topic key -> newest (run, tick)

    def put(self, key: str, msg: Message) -> None:
        if key in LATCHED and (msg.run, msg.tick) > self.heard.get(key, (-1, -1)):
            self.heard[key] = (msg.run, msg.tick)

    @property
    def complete(self) -> bool:
        return all(k in self.heard for k in LATCHED)

    def where(self, iterations: int) -> tuple[int, int]:
        """(run, tick) to go on at: the tick after the newest one answered in the run, not before the
        floor; at most the final tick of a bounded run (a final world answered again is answered
        with the same messages)."""
        run = self.run if self.run is not None else max((r for r, _ in self.heard.values()), default=0)
        tick = max([self.floor] + [t + 1 for r, t in self.heard.values() if r == run])
        return run, min(tick, iterations) if iterations else tick

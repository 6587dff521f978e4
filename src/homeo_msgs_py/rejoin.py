"""A tick join that survives a long gap in one of its inputs (no rclpy).

``TickJoin`` starts mid-run when a node has no run yet (one the launcher restarted) and skips a
tick whose lost input a later, complete tick proves will not come; but it refuses a message more
than ``window`` ticks ahead. When an upstream node is down for longer than that (the launcher is
restarting it), a node that joins several inputs keeps the oldest ticks, refuses every newer one,
and waits for ever. Two facts of the graph let it go on: every topic has one writer and is
delivered in order (RELIABLE), so a tick that still lacks input X when X of a later tick arrives
will never get it; and the world moves on only once a tick is answered or timed out, so a tick
more than ``window`` behind the newest input is over. Such ticks are dropped (counted in
``skipped``) rather than waited for; the world counts them as missed on its side. Used by the
robot nodes when the launcher supervises them (``homeo_decision.durable``); messages are
authenticated before they reach a join, so a forged far-ahead tick cannot make it skip.
"""

from __future__ import annotations

from dataclasses import dataclass  # noqa: F401 (the subclass stays a dataclass)

from .lockstep import JoinedStage, TickJoin
from .schemas import Message


@dataclass
class RejoiningJoin(TickJoin):
    def put(self, name: str, msg: Message) -> list[tuple[int, dict]]:
        if msg.run == self.run:  # runs are TickJoin's (a new one only at its start)
            k = msg.tick - self.offsets[name]
            if k - self.window > self.expected:  # far behind the newest input (an upstream gap): jump
                self._drop_below(k - self.window)
            while self.expected < k:
                slot = self._pending.get(self.expected, {})
                needs = self.expected + self.offsets[name] >= 0
                if needs and name not in slot:  # its `name` went by already: it can never complete
                    self._drop_below(self.expected + 1)
                else:
                    break
        return super().put(name, msg)

    def _drop_below(self, k: int) -> None:
        for t in [t for t in self._pending if t < k]:
            del self._pending[t]
        self.skipped += k - self.expected
        self.expected = k


def make_rejoinable(stage: JoinedStage) -> JoinedStage:
    """Give ``stage`` a :class:`RejoiningJoin` (before its first input)."""
    j = stage.join
    stage.join = RejoiningJoin(dict(j.offsets), j.window)
    return stage

"""A tick join that a restarted node can rejoin mid-run, and that a missing input cannot wedge
(no rclpy).

``TickJoin`` waits for every input of a tick and refuses a message more than ``window`` ticks
ahead. A node that starts while the world is at tick 4,000 (a node the launcher restarted), or a
node whose upstream died for a while, would then wait for ever. Two facts of the graph let it go
on instead: every topic has one writer and is delivered in order (RELIABLE), so a tick that still
lacks input X when X of a later tick arrives will never get it; and the world moves on only once
a tick is answered or timed out, so a tick more than ``window`` behind the newest input is over.
Such ticks are dropped (counted in ``skipped``) rather than waited for; the world counts them as
missed on its side.
"""

from __future__ import annotations

from dataclasses import dataclass

from .lockstep import JoinedStage, TickJoin
from .schemas import Message


@dataclass
class RejoiningJoin(TickJoin):
    skipped: int = 0

    def put(self, name: str, msg: Message) -> list[tuple[int, dict]]:
        if msg.run > self.run:
            self.restart(msg.run)
        if msg.run == self.run:
            k = msg.tick - self.offsets[name]
            if k - self.window > self.expected:  # far behind (a fresh start mid-run): jump
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

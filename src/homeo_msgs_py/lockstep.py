"""Joining a tick's inputs that arrive on different topics (no rclpy).

DDS orders messages within a topic, not across topics: a node that needs the world of
tick k, the intention of tick k and the outcome of tick k-1 may get them in any order.
:class:`TickJoin` holds them until tick k is complete, then hands them over at once.
``offsets`` says which tick of an input belongs to the node's tick: ``{"outcome": -1}``
means tick k needs the outcome of k-1 (tick 0 needs none). A message of a tick already
handled is stale; one more than ``window`` ticks ahead cannot belong to this run.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .schemas import Message, Rejected


@dataclass
class TickJoin:
    offsets: dict  # input name -> tick offset (0 or negative)
    window: int = 2
    run: int = -1
    expected: int = 0
    _pending: dict = field(default_factory=dict)  # node tick -> {input: Message}

    def restart(self, run: int) -> None:
        self.run, self.expected = run, 0
        self._pending.clear()

    def put(self, name: str, msg: Message) -> list[tuple[int, dict]]:
        """Store one input; returns the ticks it completed, in order, each with its inputs.

        Raises :class:`Rejected` for a stale tick, a tick too far ahead, or an older run.
        A newer run restarts the join at tick 0 (the simulation was reset).
        """
        if msg.run < self.run:
            raise Rejected(f"stale run {msg.run} (current run {self.run})")
        if msg.run > self.run:
            self.restart(msg.run)
        k = msg.tick - self.offsets[name]
        if k < self.expected:
            raise Rejected(f"stale tick {msg.tick} on {name} (now at tick {self.expected})")
        if k > self.expected + self.window:
            raise Rejected(f"tick {msg.tick} on {name} is ahead of the run (now at tick {self.expected})")
        slot = self._pending.setdefault(k, {})
        if name in slot:
            raise Rejected(f"duplicate {name} for tick {msg.tick}")
        slot[name] = msg
        done = []
        while self._complete(self.expected):
            done.append((self.expected, self._pending.pop(self.expected, {})))
            self.expected += 1
        return done

    def _complete(self, k: int) -> bool:
        slot = self._pending.get(k, {})
        return all(n in slot for n, off in self.offsets.items() if k + off >= 0)

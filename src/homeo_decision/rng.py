"""One seeded random stream per component.

Each component (the decision maker, the simulated human, ...) draws from its own
``numpy.random.Generator`` seeded by ``[seed, component id]``, so a component gives the
same draws for the same seed whether it runs in-process or as a node of the graph.
Uniforms are drawn in blocks because a scalar Generator call costs about a microsecond.
"""

from __future__ import annotations

import numpy as np

COMPONENTS = {"decision": 1, "human": 2, "world": 3, "intention": 4, "observation": 5, "standin": 6, "policy": 7}


def component_rng(seed: int, component: str) -> np.random.Generator:
    if component not in COMPONENTS:
        raise ValueError(f"unknown random component {component!r}")
    return np.random.default_rng([int(seed), COMPONENTS[component]])


class UniformStream:
    """Uniform floats in [0, 1) from a component's generator, drawn in blocks."""

    __slots__ = ("rng", "_buf", "_i", "_block", "_before")

    def __init__(self, seed: int, component: str, block: int = 4096):
        self.rng = component_rng(seed, component)
        self._block = block
        self._buf: list[float] = []
        self._i = block  # past the end: the first draw fills the buffer
        self._before = self.rng.bit_generator.state  # the generator before the current block

    def random(self) -> float:
        i = self._i
        if i >= self._block:  # the buffer always holds exactly one block
            self._before = self.rng.bit_generator.state
            self._buf = self.rng.random(self._block).tolist()
            i = 0
        self._i = i + 1
        return self._buf[i]

    def state(self) -> dict:
        """Where the stream stands, as JSON-able data (a checkpoint): the generator before the
        current block and the draws taken from it; ``set_state`` continues with the very next draw."""
        return {"generator": self._before, "block": self._block, "drawn": self._i if self._buf else 0}

    def set_state(self, st: dict) -> None:
        """Continue from ``state()``; raises ValueError for data that is not such a state."""
        try:
            block, drawn = int(st["block"]), int(st["drawn"])
            if block != self._block or not 0 <= drawn <= block:
                raise ValueError(f"block {block}, drawn {drawn}")
            self.rng.bit_generator.state = st["generator"]
        except (KeyError, TypeError, ValueError) as exc:
            raise ValueError(f"not a random-stream state ({exc})") from None
        self._before = self.rng.bit_generator.state
        self._buf = self.rng.random(block).tolist()  # the current block again; the generator after it
        self._i = drawn

    def index(self, n: int) -> int:
        """A uniform index in range(n)."""
        return int(self.random() * n)

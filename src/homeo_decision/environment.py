"""The environment boundary, in the spirit of Gymnasium: ``reset(seed)`` / ``observe()`` / ``step(action)``.

A robot lives in an environment: the simulated home of the thesis (``homeo_sim``) or a Pepper
over NAOqi (``pepper_bridge``). Both offer the same three calls and the same two records, so
the in-process runner, the world nodes of the graph and the field test drive them alike:

- ``reset(seed) -> Observation``: a new episode; the observation of tick 0.
- ``observe() -> Observation``: what the robot can sense at the start of the current tick.
- ``step(action) -> Outcome``: perform the action of this tick (None: do nothing), let the
  human answer and time pass; the environment is then at the next tick.

Everything is in the scenario's indices (world codes, action and intention indices, drives
indexed like ``Scenario.drives``); ``homeo_decision.codec`` turns both records into messages.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, Sequence


@dataclass(slots=True)
class Observation:
    """What the robot can sense at the start of a tick."""

    code: int  # the world (robot location, object states, human presence) as a world code; intention `none`
    body: Sequence[float]  # body readings indexed like all drives (only body drives are read)
    intention: int | None = None  # the human's true intention: an oracle recogniser reads it (None: not observable)
    cues: dict | None = None  # what the robot sees of the human (gesture, movement, keyword); None: not observed
    readings: dict | None = None  # raw robot readings behind ``body`` (battery percent, temperature status...)


@dataclass(slots=True)
class Outcome:
    """What the action of a tick did and how the human answered."""

    action: int | None  # the action performed (None: nothing was done: no action came, or the robot refused it)
    feedback: int  # +1 praise, -1 scolding, 0 none (Eq 3.22)
    proposal: int | None  # the action the human proposed (Section 3.2.6)
    clarified: int | None  # the intention the answer revealed (Section 2.3's clarification)
    body: Sequence[float] | None = None  # body readings right after the action, before the time step
    # ground truth of a simulated human, for the metrics only (the robot never reads these)
    true_intention: int | None = None
    satisfied: bool = False
    failure: str | None = None  # why the requested action was not performed (a robot's refusal)


class Environment(Protocol):
    def reset(self, seed: int | None = None) -> Observation: ...

    def observe(self) -> Observation: ...

    def step(self, action: int | None) -> Outcome: ...


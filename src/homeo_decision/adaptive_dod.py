"""Degree of Dedication adjusted online (the thesis's future work, Chapter 5).

The thesis only sketches the idea: "the DoD could be adjusted in the interaction according
to the user's and robot's current satisfaction. If the user's satisfaction is lower while
the robot's satisfaction is still high enough, DoD could be increased online." The rule
below is ours (docs/EXPERIMENTS.md documents it and its constants):

* The robot estimates, from what it observes itself,
  - the user's satisfaction h: the share of positive feedback among the ticks with any
    feedback (an expressed intention), and
  - its own satisfaction r: the share of ticks on which it is secure, every drive
    below ``secure_below`` (Eq 4.7),
  each as a bias-corrected exponential moving average with time constant ``horizon``
  (counted in feedback events for h, in ticks for r).
* Every ``period`` ticks (from tick ``warmup`` on) it compares both with their targets:
  shortfall_user = max(0, target_hsr - h), shortfall_robot = max(0, target_rsr - r), and
      DoD <- clip(DoD + clip(gain * (shortfall_user - shortfall_robot), +-max_step),
                  dod_min, dod_max).
  The user short and the robot fine: DoD rises. The robot short and the user fine: DoD
  falls. Both fine: DoD stays. Both short: the larger shortfall wins.

The controller has no randomness: the same inputs give the same DoD trace.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

from .agent import DecisionCore, Learned, Percept


@dataclass(frozen=True)
class AdaptiveDoDSettings:
    target_hsr: float = 0.8  # the user's satisfaction aimed at (about Table 4.5's HSR 0.82)
    target_rsr: float = 0.9  # the robot's security aimed at (Table 4.5's RSR 0.90)
    horizon: float = 200.0  # EMA time constant (feedback events for the user, ticks for the robot)
    period: int = 50  # ticks between adjustments
    gain: float = 0.5  # DoD change per unit of shortfall difference
    max_step: float = 0.05  # largest change of one adjustment
    warmup: int = 0  # no adjustment before this tick
    dod_min: float = 0.0
    dod_max: float = 1.0
    secure_below: float = 90.0  # Eq 4.7

    def __post_init__(self):
        for name in ("target_hsr", "target_rsr"):
            v = getattr(self, name)
            if not 0.0 <= v <= 1.0:
                raise ValueError(f"{name} must be in [0, 1], got {v}")
        if self.horizon < 1 or self.period < 1 or self.gain < 0 or self.max_step < 0 or self.warmup < 0:
            raise ValueError("horizon and period must be >= 1; gain, max_step and warmup >= 0")
        if not 0.0 <= self.dod_min <= self.dod_max <= 1.0:
            raise ValueError(f"need 0 <= dod_min <= dod_max <= 1, got {self.dod_min}, {self.dod_max}")


class _Ema:
    """Bias-corrected exponential moving average (no arbitrary starting value)."""

    __slots__ = ("beta", "s", "w")

    def __init__(self, horizon: float):
        self.beta = 1.0 / horizon
        self.s = 0.0
        self.w = 0.0

    def add(self, x: float) -> None:
        b = self.beta
        self.s += b * (x - self.s)
        self.w += b * (1.0 - self.w)

    @property
    def value(self) -> float | None:
        return self.s / self.w if self.w > 0 else None


class AdaptiveDoD:
    """The DoD controller: ``observe`` every tick, then ``adjust`` (see the module docstring)."""

    def __init__(self, dod: float, settings: AdaptiveDoDSettings | None = None):
        self.settings = s = settings or AdaptiveDoDSettings()
        self.dod = min(max(float(dod), s.dod_min), s.dod_max)
        self.user = _Ema(s.horizon)
        self.robot = _Ema(s.horizon)
        self.history: list[tuple[int, float]] = [(0, self.dod)]

    def observe(self, feedback: int, drives: Sequence[float]) -> None:
        """One tick: the human's feedback (+1 / -1 / 0) and the drives after the tick."""
        if feedback:
            self.user.add(1.0 if feedback > 0 else 0.0)
        lim = self.settings.secure_below
        self.robot.add(1.0 if all(d < lim for d in drives) else 0.0)

    def shortfalls(self) -> tuple[float, float]:
        s = self.settings
        h, r = self.user.value, self.robot.value
        return (0.0 if h is None else max(0.0, s.target_hsr - h), 0.0 if r is None else max(0.0, s.target_rsr - r))

    def adjust(self, t: int) -> float | None:
        """At the end of tick ``t``: the new DoD when one is due and it changed, else None."""
        s = self.settings
        if (t + 1) % s.period or t + 1 < s.warmup:
            return None
        su, sr = self.shortfalls()
        step = max(-s.max_step, min(s.max_step, s.gain * (su - sr)))
        new = min(max(self.dod + step, s.dod_min), s.dod_max)
        if new == self.dod:
            return None
        self.dod = new
        self.history.append((t + 1, new))
        return new


class AdaptiveDoDRobot:
    """A DecisionCore whose DoD the controller sets between ticks; same interface."""

    def __init__(self, core: DecisionCore, settings: AdaptiveDoDSettings | None = None):
        self.core = core
        self.controller = AdaptiveDoD(core.dod, settings)
        if self.controller.dod != core.dod:
            core.set_params(dod=self.controller.dod)
        self.q = core.q
        self.sc = core.sc

    @property
    def dod(self) -> float:
        return self.core.dod

    @property
    def xi(self) -> float:
        return self.core.xi

    @property
    def pseudo_update(self) -> bool:
        return self.core.pseudo_update

    def perceive(self, drives: Sequence[float], code: int) -> Percept:
        return self.core.perceive(drives, code)

    def percept(self, code: int, drives: Sequence[float], inten: list, m_dom: int) -> Percept:
        return self.core.percept(code, drives, inten, m_dom)

    def select(self, p: Percept, t: int) -> int:
        return self.core.select(p, t)

    def learn(self, p: Percept, action: int, after: Sequence[float], feedback: int, proposal: int | None,
              p_next: Percept, t: int) -> Learned:
        out = self.core.learn(p, action, after, feedback, proposal, p_next, t)
        ctl = self.controller
        ctl.observe(feedback, p_next.drives)
        new = ctl.adjust(t)
        if new is not None:
            self.core.set_params(dod=new)
        return out

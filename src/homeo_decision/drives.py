"""Drive dynamics: time increase (Table 4.2), action effects (Table 4.1), feedback.

The robot computes its *internal* drives (NAch, NSoc) itself; *body* drives (NRes,
NEng) are read from the body: the simulated one in ``homeo_sim.body`` or Pepper's
sensors. Both apply the same scenario rules to their own subset of drives.
"""

from __future__ import annotations

from typing import Sequence

from .motivation import clamp
from .scenario import Scenario


class DriveDynamics:
    """Rates and action effects of the scenario, applied to a subset of the drives."""

    def __init__(self, sc: Scenario, source: str):
        self.sc = sc
        self.idx = tuple(i for i, d in enumerate(sc.drives) if d.source == source)
        self.rates = [d.rate for d in sc.drives]
        self.delta = sc.c.drive_delta
        self.values = [0.0] * len(sc.drives)
        # the open choice drive_growth: drives of this subset that grow only on some ticks
        names = [d.name for d in sc.drives]
        self.growth_when = tuple((names.index(n), r) for n, r in sc.open.drive_growth.items()
                                 if names.index(n) in self.idx)
        self.reset()

    def reset(self, initial: Sequence[float] | None = None) -> None:
        init = self.sc.open.initial_drives if initial is None else initial
        for i in self.idx:
            self.values[i] = clamp(float(init[i]))

    def apply_action(self, code: int, action: int) -> None:
        """Table 4.1: the drive effects of ``action`` taken in world ``code``."""
        d = self.delta[code][action]
        v = self.values
        for i in self.idx:
            if d[i]:
                x = v[i] + d[i]
                v[i] = 0.0 if x < 0.0 else 100.0 if x > 100.0 else x  # clamp, inlined: hot path

    def still(self, code: int, action: int | None) -> tuple:
        """The drives of the subset that do not grow on a tick whose action ``action`` was taken in
        world ``code`` (the open choice ``drive_growth``; empty when every drive always grows)."""
        c = self.sc.c
        out = []
        for i, reading in self.growth_when:
            if reading == "human_not_near":  # RELATIONS[0] is "near"
                grows = c.relation_of[code] != 0
            elif reading == "robot_moved":
                grows = action is not None and c.location_of[c.next_code[code][action]] != c.location_of[code]
            elif reading == "not_lowered":
                grows = action is None or c.drive_delta[code][action][i] >= 0
            else:
                grows = True
            if not grows:
                out.append(i)
        return tuple(out)

    def apply_time(self, skip: int = -1, still: tuple = ()) -> None:
        """Table 4.2: every drive of the subset grows by its rate (``skip`` one of them, and those in
        ``still``)."""
        v, r = self.values, self.rates
        for i in self.idx:
            if i != skip and i not in still:
                x = v[i] + r[i]
                v[i] = 0.0 if x < 0.0 else 100.0 if x > 100.0 else x


class DriveModel(DriveDynamics):
    """The robot's drives: internal ones computed here, body ones copied from readings."""

    def __init__(self, sc: Scenario):
        super().__init__(sc, "internal")
        self.body_idx = tuple(i for i, d in enumerate(sc.drives) if d.source == "body")
        self.serving = sc.serving
        self.serving_internal = sc.drives[sc.serving].source == "internal"
        self.praise = sc.praise_change
        self.scold = sc.open.scold_drive_change
        self.growth = sc.open.serving_growth
        init = sc.open.initial_drives
        for i in self.body_idx:
            self.values[i] = clamp(float(init[i]))

    def set_body(self, body_values: Sequence[float]) -> None:
        """Copy the body drives (indexed like all drives) from a body reading."""
        v = self.values
        for i in self.body_idx:
            x = body_values[i]
            v[i] = 0.0 if x < 0.0 else 100.0 if x > 100.0 else float(x)

    def apply_feedback(self, feedback: int) -> None:
        """Positive feedback lowers the serving drive by 10 (Section 4.2.1); a scolding moves it by an open amount."""
        if not self.serving_internal or feedback == 0:
            return
        s = self.serving
        self.values[s] = clamp(self.values[s] + (self.praise if feedback > 0 else self.scold))

    def apply_time(self, expressed: bool = True, satisfied: bool = False,  # type: ignore[override]
                   still: tuple = ()) -> None:
        """Table 4.2 growth; whether the serving drive grows on a tick is the open choice ``serving_growth``
        (the others': ``drive_growth``, the drives in ``still`` do not grow)."""
        g = self.growth
        grow_serving = g == "always" or (g == "expressed" and expressed) or (g == "unsatisfied" and expressed and not satisfied)
        DriveDynamics.apply_time(self, -1 if grow_serving else self.serving, still)

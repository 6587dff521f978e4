"""The stand-in Pepper's body (no qi import): battery, joint heat, where it stands, awake or resting, plugged in.

Per simulated second (every motion / speech / rest call also lasts ``action_seconds`` simulated seconds, so a
run at ``time_scale`` 0 is reproducible): the battery drains ``drain`` %/s awake (``drain_rest`` at rest) and
``drain_per_m`` % per metre moved, charges ``charge`` %/s while plugged (the scripted user plugs it in when asked
for help at the charger; moving away unplugs it); heat rises ``heat_per_m`` per metre and ``heat_awake`` /s
awake, falls ``cool_rest`` /s at rest; the wheel and leg joints' temperature status is floor(heat) (0..3), the
other joints' floor(heat / 2). What ALMemory shows of it: ``body_memory``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .standin_naoqi import BATTERY_KEY, JOINTS, PLUGGED_EVENT, TEMPERATURE_KEY

MOTION_JOINTS = ("HipRoll", "HipPitch", "KneePitch", "WheelFL", "WheelFR", "WheelB")


@dataclass
class BodyParams:
    action_seconds: float = 10.0
    drain: float = 0.2
    drain_rest: float = 0.05
    drain_per_m: float = 0.5
    charge: float = 2.0
    heat_per_m: float = 0.12
    heat_awake: float = 0.005
    cool_rest: float = 0.05


class StandinBody:
    """Mixed into ``StandinRobot``: its ``battery`` (percent), ``heat``, ``x``, ``y``, ``awake``, ``plugged``,
    ``moved_m``, with ``p`` (BodyParams), ``clock`` and ``time_scale``."""

    def _advance(self) -> None:
        now = self.clock()
        dt, self._last = (now - self._last) * self.time_scale, now
        if dt > 0:
            self._evolve(dt)

    def _evolve(self, dt: float) -> None:
        p = self.p
        if self.plugged:
            self.battery = min(100.0, self.battery + p.charge * dt)
        else:
            self.battery = max(0.0, self.battery - (p.drain if self.awake else p.drain_rest) * dt)
        if self.awake:
            self.heat = min(3.99, self.heat + p.heat_awake * dt)
        else:
            self.heat = max(0.0, self.heat - p.cool_rest * dt)

    def _act(self) -> None:
        """An action call lasts ``action_seconds`` simulated seconds."""
        self._evolve(self.p.action_seconds)

    def _move(self, dx: float, dy: float) -> None:
        d = math.hypot(dx, dy)
        if d > 1e-9 and self.plugged:
            self.plugged = False  # driving away pulls the plug
        self.x += dx
        self.y += dy
        self.moved_m += d
        self.battery = max(0.0, self.battery - self.p.drain_per_m * d)
        self.heat = min(3.99, self.heat + self.p.heat_per_m * d)
        self._act()

    def statuses(self) -> dict:
        h = int(self.heat)
        return {j: min(3, h if j in MOTION_JOINTS else h // 2) for j in JOINTS}

    def body_memory(self) -> dict:
        """The body's ALMemory keys: the charge as a 0..1 fraction, plugged or not, each joint's temperature status."""
        out = {BATTERY_KEY: round(self.battery / 100.0, 6), PLUGGED_EVENT: self.plugged}
        out.update((TEMPERATURE_KEY.format(j), s) for j, s in self.statuses().items())
        return out

"""The simulated home: robot location, object states, and the human's presence (Section 4.2.1).

The whole world is one world code of the scenario (see ``homeo_decision.scenario``);
actions move it through the compiled effect table (Table 4.1). The human stays at the scenario's
human location: its relation to the robot is derived from the two locations (Section 4.2.1: near
iff the robot is there), on every move and whenever the human comes or goes.
"""

from __future__ import annotations

from homeo_decision.scenario import NONE_INTENTION, Scenario


class World:
    def __init__(self, sc: Scenario):
        self.sc = sc
        self.next_code = sc.c.next_code
        self.reset()

    def reset(self) -> None:
        o = self.sc.open
        values = {"robot.location": o.initial_location, "human.presence": "present", "intention": NONE_INTENTION}
        values.update(o.initial_objects)
        self.code = self.sc.encode(values)

    def execute(self, action: int) -> int:
        """Apply an action's effects on the environment; returns the world code before it."""
        before = self.code
        self.code = self.next_code[before][action]
        return before

    def set_human(self, present: bool, intention: int) -> None:
        """The human present at its location (the located relation) or absent, wanting ``intention``."""
        c = self.sc.c
        self.code = c.with_intention[c.with_presence[self.code][0 if present else 1]][intention]

"""The drives node's core: the robot's drives across ticks, from outcomes and body readings.

Per tick k it applies what tick k-1 did (Table 4.1 action effects, the feedback's change
of the serving drive, the Table 4.2 time increase), copies the body drives read at tick k,
and computes stimuli, intensities (Eq 3.2) and the dominant motivation (Eq 3.3) for the
perceived world. The order is the in-process runner's, so both give the same drives.
"""

from __future__ import annotations

from .drives import DriveModel
from .motivation import dominant, intensities
from .perception import body_vector
from .scenario import Scenario


class DriveTracker:
    def __init__(self, sc: Scenario):
        self.sc = sc
        self.model = DriveModel(sc)
        self.thresholds = [d.threshold for d in sc.drives]
        self.tie_break = sc.open["tie_break"]
        # the drives right after the action are needed by these two open choices only
        self.keep_after = sc.open["reward_span"] == "action" or sc.open["metrics_sample"] == "after_action"
        self.after_action: tuple | None = None

    def reset(self) -> None:
        self.model = DriveModel(self.sc)
        self.after_action = None

    def apply_outcome(self, code: int, action: int | None, feedback: int, expressed: bool, satisfied: bool,
                      body_after: dict | None) -> None:
        """What tick k-1 did; ``code`` is the world perceived at k-1 (before the action)."""
        m = self.model
        if action is not None:
            m.apply_action(code, action)  # Table 4.1
        m.apply_feedback(feedback)  # Section 4.2.1: praise -10, scolding an open amount
        if self.keep_after:
            if body_after is not None:
                m.set_body(body_vector(self.sc, body_after))
            self.after_action = tuple(m.values)
        m.apply_time(expressed, satisfied)  # Table 4.2, with the open choice serving_growth

    def perceive(self, body: dict, code: int) -> dict:
        """Fields of ``homeo/drives`` for the perceived world ``code`` and the body of this tick."""
        sc, m = self.sc, self.model
        m.set_body(body_vector(sc, body))
        stim = sc.c.stim[code]
        inten = intensities(m.values, self.thresholds, stim)  # Eq 3.2
        mdom = dominant(inten, self.tie_break)  # Eq 3.3
        mot = sc.motivation_names
        out = {
            "drives": dict(zip(sc.drive_names, m.values)),
            "stimuli": dict(zip(mot, (float(s) for s in stim))),
            "intensities": dict(zip(mot, inten)),
            "m_dom": mot[mdom],
        }
        if self.keep_after and self.after_action is not None:
            out["after_action"] = dict(zip(sc.drive_names, self.after_action))
        return out


class DrivesStage:
    """The drives node without ROS: message fields in, ``homeo/drives`` fields out."""

    def __init__(self, sc: Scenario):
        self.sc = sc
        self.tracker = DriveTracker(sc)
        self.restart()

    def restart(self) -> None:
        self.tracker.reset()
        self.prev_code: int | None = None
        self.prev_intention = "none"

    def tick(self, world: dict, intention: str, outcome: dict | None) -> dict:
        """Tick k: the world and recognised intention of k, the outcome of k-1 (None at tick 0).
        Raises ScenarioError for a world the scenario cannot encode."""
        from .perception import perceived_code

        sc = self.sc
        learned_from = None
        if outcome is not None and self.prev_code is not None:
            learned_from = {k: outcome[k] for k in ("action", "feedback", "proposal")}
            action = sc.action_index(outcome["action"]) if outcome["action"] is not None else None
            fb = outcome["feedback"]
            # what the robot itself can tell: it saw an intention, or the human reacted
            expressed = self.prev_intention != "none" or fb != 0
            self.tracker.apply_outcome(self.prev_code, action, fb, expressed, fb > 0, outcome.get("body"))
        code = perceived_code(sc, world, intention)
        fields = self.tracker.perceive(world["body"], code)
        fields["intention"] = intention
        fields["world"] = {k: world[k] for k in ("robot", "objects", "human")}
        if learned_from is not None:
            fields["outcome"] = learned_from
        if world.get("final"):
            fields["final"] = True
        self.prev_code, self.prev_intention = code, intention
        return fields

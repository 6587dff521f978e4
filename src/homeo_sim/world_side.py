"""The simulation node's side of the lockstep (``homeo_msgs_py.lockstep.WorldSide``), without ROS.

The simulated environment in message fields: observations out, actions in, outcomes out; and the
metrics of Section 4.1, which need the robot's drives after each tick: they come back with the
action of the next tick (d(t) after the iteration, as ``homeo-sim run`` records them).
"""

from __future__ import annotations

import json

from homeo_decision import codec
from homeo_decision.environment import Outcome
from homeo_decision.scenario import Scenario
from homeo_msgs_py.schemas import Rejected

from .environment import SimEnvironment
from .metrics import AccuracyEnds, MetricRecorder


class SimWorldSide:
    last_missed = False  # the simulation always acts

    def __init__(self, sc: Scenario, seed: int = 0, intention_accuracy: bool = False, trace=None, human=None):
        self.sc = sc
        self.intention_accuracy = intention_accuracy  # score the intention each action was chosen for
        self.sample_after = sc.open.metrics_sample == "after_action"
        self.drives_key = "after_action" if self.sample_after else "drives"
        self.trace = trace  # a text file: one JSON line per tick
        self.env = SimEnvironment(sc, seed, cues=True, body_after=True, human=human)
        self.reset(seed)

    def reset(self, seed: int | None = None) -> None:
        self.env.reset(seed)
        self.rec = MetricRecorder(self.sc.drive_names, [d.threshold for d in self.sc.drives])
        self.hits = AccuracyEnds()  # fixed memory: the node runs for hours
        self._last: Outcome | None = None

    # -- WorldSide ---------------------------------------------------------------------------
    def start(self) -> None:
        self.env.start()

    def observe(self, final: bool) -> tuple[dict, dict]:
        return codec.observation_messages(self.sc, self.env.observe(), final)

    def check_action(self, fields: dict, tick: int) -> None:
        if tick > 0 and fields.get(self.drives_key) is None:
            raise Rejected(f"no {self.drives_key}: the metrics need them")

    def step(self, action_fields: dict | None) -> dict:
        sc, env = self.sc, self.env
        names = sc.intention_names
        k = env.tick
        name = action_fields["action"] if action_fields is not None else None
        recognised = action_fields.get("intention") if action_fields is not None else None
        if recognised is not None:
            self.hits.append(recognised == names[env.human.intention])
        out = self._last = env.step(sc.action_index(name) if name is not None else None)
        if self.trace is not None:
            it = out.true_intention
            self.trace.write(json.dumps({"tick": k, "intention": names[it] if it else None, "action": name,
                                         "feedback": out.feedback, "proposal": codec.outcome_fields(sc, out)["proposal"]})
                             + "\n")
        return codec.outcome_fields(sc, out)

    def step_failed(self, action_fields: dict | None, reason: str) -> dict:
        raise RuntimeError(f"the simulation failed to step: {reason}")

    def record(self, action_fields: dict | None) -> None:
        if self._last is None or action_fields is None or action_fields.get(self.drives_key) is None:
            return
        d = action_fields[self.drives_key]
        self.rec.record([d[n] for n in self.sc.drive_names], self._last.true_intention != 0, self._last.satisfied)
        self._last = None  # recorded: a checkpoint from here on must not record it again

    # -- a restarted node ------------------------------------------------------------------------
    @property
    def pending_truth(self) -> list | None:
        """The truth of the last tick stepped but not yet recorded (its drives come with the next action)."""
        o = self._last
        return None if o is None else [o.true_intention != 0, bool(o.satisfied)]

    def set_pending_truth(self, truth: list | None) -> None:
        self._last = None if truth is None else Outcome(None, 0, None, None, None, int(truth[0]), bool(truth[1]))

    def skip(self, ticks: int) -> dict:
        """Step ``ticks`` ticks without an action (a world node down: time passed, nobody acted);
        the outcome fields of the last. Nothing of them is recorded: no robot drives came back."""
        fields = {}
        for _ in range(ticks):
            fields = self.step(None)
        self._last = None
        return fields

    def status(self, done: bool) -> dict:
        if not self.rec.n:
            return {}
        m = self.rec.summary()
        if self.intention_accuracy and self.hits:
            m["intention_accuracy"] = self.hits.ends()
        return {"metrics": m}

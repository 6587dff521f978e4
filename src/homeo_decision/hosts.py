"""The drives and decision nodes' work per tick, without ROS: inputs joined from the graph
(``homeo_msgs_py.graph``), the robot's part, fields out (``codec``). The nodes and the tests'
in-memory bus both run these."""

from __future__ import annotations

from homeo_msgs_py.graph import NODES
from homeo_msgs_py.lockstep import JoinedStage

from . import codec
from .robot import Decision, Perception
from .scenario import Scenario


class PerceptionHost:
    """``homeo_drives``: world(k) (carrying the outcome of k-1) + intention(k) -> drives(k)."""

    def __init__(self, sc: Scenario):
        self.sc = sc
        self.perception = Perception(sc)
        self.stage = JoinedStage(NODES["homeo_drives"].join_offsets(learning=True), self._tick, self.perception.restart)

    def _tick(self, k: int, inputs: dict) -> dict:
        sc, world = self.sc, inputs["world"]
        out = codec.outcome_from_fields(sc, world["outcome"]) if "outcome" in world else None  # of tick k-1
        obs = codec.observation_from_fields(sc, world, None)  # raises ScenarioError for a world it cannot encode
        perceived = self.perception.tick(obs.code, sc.intention_names.index(inputs["intention"]["intention"]),
                                         obs.body, out)
        return codec.drives_fields(sc, perceived, world, out, self.perception.after_action,
                                   final=bool(world.get("final")))


class DecisionHost:
    """``homeo_decision``: drives(k) (carrying the outcome of k-1) -> action(k)."""

    def __init__(self, sc: Scenario, core):
        self.sc, self.core = sc, core
        self.decision = Decision(core)
        self.stage = JoinedStage(NODES["homeo_decision"].join_offsets(learning=True), self._tick, self.decision.restart)

    def _tick(self, k: int, inputs: dict) -> dict:
        sc, core, d = self.sc, self.core, inputs["drives"]
        perceived, out, after, final = codec.perception_from_fields(sc, d)
        a = self.decision.tick(k, perceived, out, after, final)
        return codec.action_fields(sc, a, d, core.phase(k).tau, core.params(), final)

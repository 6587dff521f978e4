"""The simulation node's core: world, human and body stepped one lockstep tick at a time.

The same objects and order as ``runner.Simulation``, cut at the graph's messages: the
node publishes the world and the observation of tick k, waits for the action of tick k,
then ``step`` executes it, answers as the human, advances time and the human, and the
world of tick k+1 is ready. The metrics need the robot's drives after tick k, which come
back on /homeo/drives with tick k+1 (``record``).
"""

from __future__ import annotations

from dataclasses import dataclass

from homeo_decision.perception import world_fields
from homeo_decision.scenario import Scenario

from .body import SimBody
from .human import NO_RESPONSE, SimHuman
from .metrics import MetricRecorder, accuracy_ends
from .world import World


@dataclass
class StepResult:
    outcome: dict  # fields of homeo/outcome
    trace: dict  # one line of the sim's trace file


class SimCore:
    def __init__(self, sc: Scenario, seed: int = 0, intention_accuracy: bool = False):
        self.sc = sc
        self.seed = seed
        self.intention_accuracy = intention_accuracy  # report how often the robot recognised the intention
        self.reset(seed)

    def reset(self, seed: int | None = None) -> None:
        if seed is not None:
            self.seed = int(seed)
        sc = self.sc
        self.world = World(sc)
        self.human = SimHuman(sc, self.seed)
        self.body = SimBody(sc)
        self.rec = MetricRecorder(sc.drive_names, [d.threshold for d in sc.drives])
        self.tick = 0
        self.hits: list[bool] = []
        self._truth: tuple[bool, bool] | None = None  # (expressed, satisfied) of the last step
        self.human.advance(self.world.code)  # Algorithm 2 lines 1-6: the first intention
        self.world.set_human(self.human.present, self.human.intention)

    # -- what the robot sees at the start of a tick -------------------------------
    def world_msg(self, final: bool = False) -> dict:
        out = world_fields(self.sc, self.world.code)
        out["body"] = self.body.readings()
        if final:
            out["final"] = True
        return out

    def observation_msg(self) -> dict:
        out = {"intention": self.sc.intention_names[self.human.intention]}
        if getattr(self.sc, "observations", None) is not None:  # noisy cues, when the scenario declares them
            out.update(self.human.observe())
        return out

    # -- one tick -------------------------------------------------------------------
    def step(self, action: int | None, recognised: str | None = None) -> StepResult:
        """Execute the action of this tick (None: the robot did nothing) and move to the next tick.
        ``recognised`` is the intention the robot acted for, scored against the human's."""
        sc, world, human, body = self.sc, self.world, self.human, self.body
        names = sc.intention_names
        intention = human.intention
        if recognised is not None:
            self.hits.append(recognised == names[intention])
        expressed = intention != 0
        if action is not None:
            before = world.execute(action)
            body.apply_action(before, action)
            resp = human.respond(action)
        else:
            resp = NO_RESPONSE
        body_after = body.readings()
        body.apply_time()
        human.advance(world.code)
        world.set_human(human.present, human.intention)
        self._truth = (expressed, resp.satisfied)
        clarified = getattr(resp, "clarified", None)
        act_name = sc.actions[action].name if action is not None else None
        prop_name = sc.actions[resp.proposal].name if resp.proposal is not None else None
        outcome = {
            "action": act_name,
            "feedback": resp.feedback,
            "proposal": prop_name,
            "clarified_intention": names[clarified] if clarified is not None else None,
            "body": body_after,
            "truth": {"intention": names[intention], "expressed": expressed, "satisfied": resp.satisfied},
        }
        trace = {"tick": self.tick, "intention": names[intention] if intention else None, "action": act_name,
                 "feedback": resp.feedback, "proposal": prop_name}
        self.tick += 1
        return StepResult(outcome, trace)

    def record(self, drives: list[float] | tuple) -> None:
        """Metrics of the last step, with the robot's drives after it (d(t) of Section 4.1)."""
        expressed, satisfied = self._truth
        self.rec.record(drives, expressed, satisfied)

    def metrics(self) -> dict:
        out = self.rec.summary()
        if self.intention_accuracy and self.hits:
            out["intention_accuracy"] = accuracy_ends(self.hits)
        return out

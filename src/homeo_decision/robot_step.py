"""The decision node's core: one lockstep tick of Algorithm 1 from the graph's messages.

At tick k the robot first learns from tick k-1 (Eq 3.14 and the pseudo update 3.23, with
the outcome the world reported and the drives of tick k as s'), then selects the action
of tick k (Eq 3.17). Learning before selecting is the in-process runner's order, so the
decision stream of random numbers is drawn identically.
"""

from __future__ import annotations

from dataclasses import dataclass

from .agent import DecisionCore, Learned, Percept


@dataclass
class Outcome:
    action: int | None  # what was actually executed (None: nothing, e.g. the action came late)
    feedback: int
    proposal: int | None


class RobotStep:
    def __init__(self, core: DecisionCore):
        self.core = core
        self.span_action = core.sc.open["reward_span"] == "action"
        self.prev: Percept | None = None

    def restart(self) -> None:
        """A new run of the world: forget the pending transition (the Q-table stays)."""
        self.prev = None

    def tick(self, k: int, p: Percept, outcome: Outcome | None, after_action: tuple | None,
             final: bool = False) -> tuple[int | None, Learned | None]:
        """Learn from k-1 (when there is one), then choose for k (unless the run ends here)."""
        learned = None
        if self.prev is not None and outcome is not None and outcome.action is not None:
            after = after_action if self.span_action and after_action is not None else p.drives
            learned = self.core.learn(self.prev, outcome.action, after, outcome.feedback, outcome.proposal, p, k - 1)
        if final:
            self.prev = None
            return None, learned
        a = self.core.select(p, k)
        self.prev = p
        return a, learned


class DecisionStage:
    """The decision node without ROS: ``homeo/drives`` in, ``homeo/action`` out."""

    def __init__(self, core: DecisionCore):
        self.core = core
        self.step = RobotStep(core)

    def restart(self) -> None:
        self.step.restart()

    def tick(self, k: int, d: dict) -> dict:
        """Tick k from the drives of k (with the outcome of k-1 they carry) -> ``homeo/action`` fields.

        The message also carries the drives the choice was made with: the simulation's metrics
        of tick k-1 need them (d(t) after the iteration). When the run ends at k, the action is
        null and ``final`` is set."""
        from .perception import perceived_code

        core, sc = self.core, self.core.sc
        mot = sc.motivation_names
        code = perceived_code(sc, d["world"], d["intention"])
        p = core.percept_from(code, [d["drives"][n] for n in sc.drive_names], [d["intensities"][m] for m in mot],
                              mot.index(d["m_dom"]))
        out = None
        outcome = d.get("outcome")
        if outcome is not None:
            out = Outcome(sc.action_index(outcome["action"]) if outcome["action"] is not None else None,
                          outcome["feedback"],
                          sc.action_index(outcome["proposal"]) if outcome["proposal"] is not None else None)
        after = tuple(d["after_action"][n] for n in sc.drive_names) if "after_action" in d else None
        final = bool(d.get("final"))
        a, _ = self.step.tick(k, p, out, after, final=final)
        fields = {"action": sc.actions[a].name if a is not None else None, "m_dom": d["m_dom"],
                  "tau": core.phase(k).tau, "drives": d["drives"], "intention": d["intention"],
                  "params": {"dod": core.dod, "xi": core.xi, "gamma": core.gamma, "feedback": core.use_feedback,
                             "pseudo_update": core.pseudo}}
        if "after_action" in d:
            fields["after_action"] = d["after_action"]
        if final:
            fields["final"] = True
        return fields

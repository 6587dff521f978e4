"""``homeo_intention`` node: the user's intention as the robot recognises it.

Publishes  /homeo/intention (state: the recognised intention and its posterior), /diagnostics
Subscribes /homeo/observation (event), and when the mode learns /homeo/outcome (event: a
           proposal or clarification reveals the intention)
Parameters mode ('oracle': the thesis's simulation, intention observed directly), scenario,
           overrides (read-only)

Tick k needs the observation of tick k and, in a learning mode, the outcome of tick k-1, so
the model has learned from k-1 before it recognises k, as in the in-process runner.
"""

from __future__ import annotations

import sys

from rcl_interfaces.msg import ParameterDescriptor

from homeo_msgs_py.lockstep import TickJoin
from homeo_msgs_py.node_base import HomeoNode, NodeConfigError, run_node
from homeo_msgs_py.schemas import Rejected
from homeo_msgs_py.topics import INTENTION, OBSERVATION, OUTCOME

from .oracle import OracleStage

MODES = ("oracle",)


class IntentionNode(HomeoNode):
    def __init__(self):
        super().__init__("homeo_intention")
        self.declare_parameter("mode", "oracle", ParameterDescriptor(
            description=f"recognition mode: {', '.join(MODES)}", read_only=True))
        self.mode = self.get_parameter("mode").value
        if self.mode not in MODES:
            raise NodeConfigError(f"parameter mode: unknown mode {self.mode!r}; known: {', '.join(MODES)}")
        self.stage = OracleStage(self.sc)
        learns = self.mode != "oracle"
        self.join = TickJoin({"observation": 0, "outcome": -1} if learns else {"observation": 0})
        self.pub = self.publisher(INTENTION)
        self.subscribe(OBSERVATION, lambda m: self._put("observation", m))
        if learns:  # a proposal or clarification teaches the model
            self.subscribe(OUTCOME, lambda m: self._put("outcome", m))

    def _put(self, name, msg) -> None:
        if name == "observation" and self.mode == "oracle" and msg.fields.get("intention") is None:
            raise Rejected("oracle mode needs the intention in the observation")
        run = self.join.run
        done = self.join.put(name, msg)
        if self.join.run != run:
            self.stage.restart()
        for k, inputs in done:
            self._tick(k, inputs)

    def _tick(self, k: int, inputs: dict) -> None:
        out = inputs.get("outcome")
        fields = self.stage.tick(inputs["observation"].fields, out.fields if out is not None else None)
        self.send(self.pub, k, fields, self.join.run)


def main(args=None) -> int:
    return run_node(IntentionNode, args)


if __name__ == "__main__":
    sys.exit(main())

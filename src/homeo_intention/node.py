"""``homeo_intention`` node: the user's intention as the robot recognises it.

Publishes  /homeo/intention (state: the recognised intention and its posterior, Eq 2.10), /diagnostics
Subscribes /homeo/observation (event: gesture, movement, keyword; and the true intention, which
           only the oracle reads), and in bayes mode /homeo/outcome (event: a proposal or
           clarification reveals the intention, and the network learns by EM)
Services   ~/save_model, ~/load_model (std_srvs/Trigger: the file in model_path; bayes mode)
Parameters mode ('bayes': the Bayesian network of Section 2.3; 'oracle': the thesis's simulation,
           intention observed directly), model_path, load_on_start, scenario, overrides (read-only)

Tick k needs the observation of tick k and, in bayes mode, the outcome of tick k-1, so the
model has learned from k-1 before it recognises k, as in the in-process runner.
"""

from __future__ import annotations

import sys
from pathlib import Path

from rcl_interfaces.msg import ParameterDescriptor
from std_srvs.srv import Trigger

from homeo_msgs_py.lockstep import TickJoin
from homeo_msgs_py.node_base import HomeoNode, NodeConfigError, run_node
from homeo_msgs_py.schemas import Rejected
from homeo_msgs_py.topics import INTENTION, OBSERVATION, OUTCOME

from .observation import UnknownObservation
from .stage import MODES, RecogniserStage


class IntentionNode(HomeoNode):
    def __init__(self):
        super().__init__("homeo_intention")
        self.declare_parameter("mode", "bayes", ParameterDescriptor(
            description=f"recognition mode: {', '.join(MODES)}", read_only=True))
        self.declare_parameter("model_path", "", ParameterDescriptor(description="model file of ~/save_model, ~/load_model"))
        self.declare_parameter("load_on_start", False, ParameterDescriptor(
            description="load model_path when the node starts", read_only=True))
        mode = self.get_parameter("mode").value
        try:
            self.stage = RecogniserStage(self.sc, mode)
        except ValueError as exc:  # unknown mode, or a scenario without observation alphabets
            raise NodeConfigError(f"parameter mode: {exc}") from None
        if self.get_parameter("load_on_start").value:
            ok, msg = self._load()
            if not ok:
                raise NodeConfigError(f"load_on_start: {msg}")
        self.join = TickJoin({"observation": 0, "outcome": -1} if self.stage.learns else {"observation": 0})
        self.pub = self.publisher(INTENTION)
        self.subscribe(OBSERVATION, lambda m: self._put("observation", m))
        if self.stage.learns:
            self.subscribe(OUTCOME, lambda m: self._put("outcome", m))
        self.create_service(Trigger, "~/save_model", self._on_save)
        self.create_service(Trigger, "~/load_model", self._on_load)

    def _put(self, name, msg) -> None:
        if name == "observation":
            try:
                self.stage.check(msg.fields)
            except UnknownObservation as exc:
                raise Rejected(str(exc)) from None
        run = self.join.run
        done = self.join.put(name, msg)
        if self.join.run != run:
            self.stage.restart()
        for k, inputs in done:
            out = inputs.get("outcome")
            fields = self.stage.tick(inputs["observation"].fields, out.fields if out is not None else None)
            self.send(self.pub, k, fields, self.join.run)

    # -- services -------------------------------------------------------------------------
    def _path(self) -> str:
        return self.get_parameter("model_path").value

    def _load(self) -> tuple[bool, str]:
        if not self.stage.learns:
            return False, "the oracle has no model"
        path = self._path()
        if not path:
            return False, "model_path is not set"
        if not Path(path).is_file():
            return False, f"model file not found: {path}"
        try:
            self.stage.model.load(path)
        except (ValueError, OSError) as exc:
            return False, str(exc)
        return True, f"loaded {path}"

    def _on_load(self, request, response):
        response.success, response.message = self._load()
        return response

    def _on_save(self, request, response):
        path = self._path()
        if not self.stage.learns or not path:
            response.success = False
            response.message = "the oracle has no model" if not self.stage.learns else "model_path is not set"
            return response
        try:
            self.stage.model.save(path, meta={"node": self.get_name()})
        except (ValueError, OSError) as exc:
            response.success, response.message = False, str(exc)
            return response
        response.success, response.message = True, f"saved {path}"
        return response


def main(args=None) -> int:
    return run_node(IntentionNode, args)


if __name__ == "__main__":
    sys.exit(main())

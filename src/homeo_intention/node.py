"""``homeo_intention`` node: the robot's recognition part (``homeo_intention.recognition``).

Publishes  homeo/intention (state: the recognised intention and its posterior, Eq 2.10), /diagnostics
Subscribes homeo/observation (event: gesture, movement, keyword; the true intention, which only the
           oracle reads; and the outcome of the tick before, whose proposal or clarification reveals
           the intention: in bayes mode the network learns from it by EM)
Services   ~/save_model, ~/load_model (std_srvs/Trigger: the file in model_path; bayes mode)
Parameters mode ('bayes': the Bayesian network of Section 2.3; 'oracle': the thesis's simulation,
           intention observed directly), model_path, load_on_start, scenario, overrides (read-only),
           and the checkpoint parameters of ``homeo_decision.durable`` (bayes mode: the model and
           the ticks learned; the oracle learns nothing and writes none)

Tick k needs the observation of tick k, which carries the outcome of tick k-1, so the model has
learned from k-1 before it recognises k, as in the in-process runner.
"""

from __future__ import annotations

import sys
from pathlib import Path

from rcl_interfaces.msg import ParameterDescriptor, SetParametersResult

from homeo_decision import checkpoint, durable
from homeo_decision.node_runtime import ScenarioNode, run_scenario_node
from homeo_msgs_py.graph import BAYES, INTENTION_MODES, NODES
from homeo_msgs_py.data_dir import OutsideDataDir
from homeo_msgs_py.node_base import NodeConfigError
from homeo_msgs_py.schemas import Rejected

from .checkpoint import intention_checkpoint, intention_learned, restore_intention
from .recognition import RecognitionHost

DESC = NODES["homeo_intention"]


class IntentionNode(durable.CheckpointedNode, ScenarioNode):
    def __init__(self):
        super().__init__(DESC.name)
        self.declare_fixed("mode", BAYES, ParameterDescriptor(
            description=f"recognition mode: {', '.join(INTENTION_MODES)} (set at start)"))
        self.declare_parameter("model_path", "", ParameterDescriptor(description="model file of ~/save_model, ~/load_model"))
        self.declare_fixed("load_on_start", False, ParameterDescriptor(
            description="load model_path when the node starts"))
        mode = self.get_parameter("mode").value
        try:
            self.model_path = self.data_path(self.get_parameter("model_path").value, "model_path", trusted=True)
        except OutsideDataDir as exc:
            raise NodeConfigError(str(exc)) from None
        self.add_on_set_parameters_callback(self._on_params)
        try:
            self.host = RecognitionHost(self.sc, mode)
            self.part = self.host.part
        except ValueError as exc:  # unknown mode, or a scenario without observation alphabets
            raise NodeConfigError(f"parameter mode: {exc}") from None
        if self.get_parameter("load_on_start").value:
            ok, msg = self._load()
            if not ok:
                raise NodeConfigError(f"load_on_start: {msg}")
        self.durable = durable.declare(self)
        durable.setup_stage(self, self.host.stage, self.durable)
        self.ticks = self.tick_offset = 0
        if self.part.learns:
            self._restore(durable.read_start(self, self.durable))
        self.checkpoints = durable.checkpointer(
            self, lambda: intention_checkpoint(self.part.model, self.ticks, self.tick_offset, max(0, self.host.stage.run),
                                               mode, self.durable["session"]),
            directory=None if self.part.learns else "")
        self.pub = self.robot_publisher("intention")
        for i in DESC.reads(self.part.learns):
            self.subscribe(i.topic, lambda m, key=i.topic: self._put(key, m))
        self.trigger("~/save_model", self._save)
        self.trigger("~/load_model", self._load)

    def _put(self, key, msg) -> None:
        if key == "observation":
            try:
                self.host.check(msg.fields)
            except ValueError as exc:  # an unknown symbol, or the oracle without the intention
                raise Rejected(str(exc)) from None
        for k, fields in self.host.stage.put(key, msg):
            self.send(self.pub, k, fields, self.host.stage.run)
            self.ticks = self.tick_offset + k + 1
            self.checkpoints.after_tick(self.ticks)

    def _restore(self, ck: dict | None) -> None:
        if ck is None:
            return
        where = str(checkpoint.path_for(self.durable["resume_dir"], DESC.name))
        respawned = self.durable["respawned"]
        try:
            restore_intention(self.part.model, ck, self.host.mode, where)
        except checkpoint.CheckpointError as exc:
            raise NodeConfigError(f"resume: {exc}") from None
        self.tick_offset = ck["tick_offset"] if respawned else ck["ticks"]
        self.ticks = ck["ticks"]
        self.get_logger().info(
            f"{'rejoined' if respawned else 'resumed'} from {where}: ticks {ck['ticks']}, tick offset "
            f"{self.tick_offset}, learned state {checkpoint.digest(intention_learned(self.part.model))}")

    def _on_params(self, params) -> SetParametersResult:
        for prm in params:
            if prm.name == "model_path":
                try:
                    self.model_path = self.data_path(prm.value, "model_path")
                except OutsideDataDir as exc:
                    return SetParametersResult(successful=False, reason=str(exc))
        return SetParametersResult(successful=True)

    # -- services -------------------------------------------------------------------------
    def _path(self) -> str:
        return self.model_path

    def _load(self) -> tuple[bool, str]:
        if not self.part.learns:
            return False, "the oracle has no model"
        path = self._path()
        if not path:
            return False, "model_path is not set"
        if not Path(path).is_file():
            return False, f"model file not found: {path}"
        try:
            self.part.model.load(path)
        except (ValueError, OSError) as exc:
            return False, str(exc)
        return True, f"loaded {path}"

    def _save(self) -> tuple[bool, str]:
        path = self._path()
        if not self.part.learns or not path:
            return False, "the oracle has no model" if not self.part.learns else "model_path is not set"
        try:
            self.part.model.save(path, meta={"node": self.get_name()})
        except (ValueError, OSError) as exc:
            return False, str(exc)
        return True, f"saved {path}"


def main(args=None) -> int:
    return run_scenario_node(IntentionNode, args)


if __name__ == "__main__":
    sys.exit(main())

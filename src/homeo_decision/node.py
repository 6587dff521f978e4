"""``homeo_decision`` node: the robot's decision part (``homeo_decision.robot.Decision``), Object-Q
selection and learning (Algorithm 1).

Publishes  homeo/action (event), /diagnostics
Subscribes homeo/drives (state: drives, m_dom, the world they were perceived in, and the
           outcome of the last tick: executed action, feedback, proposal)
Services   ~/save_q, ~/load_q (std_srvs/Trigger: the file in q_table_path),
           ~/reset (forget the Q-table and reseed)
Parameters the learning parameters of ``homeo_msgs_py.learning`` (dod, xi, gamma, feedback,
           pseudo_update: docs/GRAPH.md's table; defaults from the scenario's learning block), seed,
           q_table_path, load_on_start; all but the last take effect on the next tick; and the checkpoint
           parameters of ``durable`` (checkpoint_dir, checkpoint_every, resume_dir, respawned,
           supervised): a checkpoint holds the Q-table, the random stream, the parameters and the
           learned tick count, from which a resumed run's alpha/tau schedule goes on.

Tick k needs only the drives of tick k, which carry the outcome of tick k-1 as the drives
node took it in: learn from k-1, then choose for k. One input per tick keeps the decision off
the join and saves a delivery per tick (``homeo-launch bench``).
"""

from __future__ import annotations

import sys
from pathlib import Path

from rcl_interfaces.msg import ParameterDescriptor, SetParametersResult

from homeo_msgs_py.graph import NODES
from homeo_msgs_py.data_dir import OutsideDataDir
from homeo_msgs_py.learning import LEARNING, SEED
from homeo_msgs_py.node_base import NodeConfigError

from . import checkpoint, durable, qtable_io
from .agent import DecisionCore
from .hosts import DecisionHost
from .node_runtime import ScenarioNode, run_scenario_node

DESC = NODES["homeo_decision"]
LEARNING_NAMES = frozenset(s.name for s in LEARNING)


class DecisionNode(durable.CheckpointedNode, ScenarioNode):
    def __init__(self):
        super().__init__(DESC.name)
        learning = self.declare_specs(LEARNING, defaults=self.sc.learning)  # the scenario's values by default
        seed = self.declare_specs((SEED,))[SEED.name]
        self.declare_parameter("q_table_path", "", ParameterDescriptor(description="Q-table file of ~/save_q, ~/load_q"))
        self.declare_fixed("load_on_start", False, ParameterDescriptor(
            description="load q_table_path when the node starts"))
        self.declare_fixed("start_from", "", ParameterDescriptor(
            description="a Q-table file, or a decision checkpoint, to start from ('' = none); set at start"))
        p = lambda n: self.get_parameter(n).value  # noqa: E731
        self.core = DecisionCore(self.sc, seed, **learning)
        self.host = DecisionHost(self.sc, self.core)
        try:
            self.q_path = self.data_path(p("q_table_path"), "q_table_path", trusted=True)  # its start value
        except OutsideDataDir as exc:
            raise NodeConfigError(str(exc)) from None
        for what, path in (("load_on_start", self.q_path if p("load_on_start") else ""), ("start_from", p("start_from"))):
            if path:
                ok, msg = self._load(self.data_path(path, what, trusted=True))
                if not ok:
                    raise NodeConfigError(f"{what}: {msg}")
                self.get_logger().info(msg)
        self.durable = durable.declare(self)
        durable.setup_stage(self, self.host.stage, self.durable)
        self.ticks = 0  # ticks learned in all (the tick offset included)
        self._restore(durable.read_start(self, self.durable))
        self.checkpoints = durable.checkpointer(self, lambda: checkpoint.decision_snapshot(
            self.core, self.ticks, max(0, self.host.stage.run), self.durable["session"]))
        self.add_on_set_parameters_callback(self._on_params)

        self.pub = self.robot_publisher("action")
        self.subscribe("drives", lambda m: self._put("drives", m))
        self.trigger("~/save_q", self._save)
        self.trigger("~/load_q", self._load)
        self.trigger("~/reset", self._reset)

    # -- parameters ---------------------------------------------------------------------
    def _on_params(self, params) -> SetParametersResult:
        kw = {}
        q_path = self.q_path
        for prm in params:
            if prm.name == "q_table_path":
                try:
                    q_path = self.data_path(prm.value, "q_table_path")
                except OutsideDataDir as exc:
                    return SetParametersResult(successful=False, reason=str(exc))
            if prm.name in LEARNING_NAMES:
                kw[prm.name] = prm.value
        try:  # refused: one line, as the declaration says it (the core is left as it was)
            self.core.set_params(**kw)
        except ValueError as exc:
            return SetParametersResult(successful=False, reason=str(exc))
        for prm in params:
            if prm.name == SEED.name:
                self.core.reseed(prm.value)
        self.q_path = q_path
        return SetParametersResult(successful=True)

    def _restore(self, ck: dict | None) -> None:
        """Start from a checkpoint: a respawned node keeps its run's offset and parameters, a
        resumed run starts its schedule at the ticks learned."""
        if ck is None:
            return
        where = str(checkpoint.path_for(self.durable["resume_dir"], DESC.name))
        respawned = self.durable["respawned"]
        try:
            checkpoint.restore_decision(self.core, ck, where, params=respawned)
        except checkpoint.CheckpointError as exc:
            raise NodeConfigError(f"resume: {exc}") from None
        self.core.set_tick_offset(ck["tick_offset"] if respawned else ck["ticks"])
        self.ticks = ck["ticks"]
        if respawned:  # the node's parameters show what the core uses
            from rclpy.parameter import Parameter

            self.set_parameters([Parameter(n, value=v) for n, v in self.core.params().items()])
        self.get_logger().info(
            f"{'rejoined' if respawned else 'resumed'} from {where}: ticks {ck['ticks']}, tick offset "
            f"{self.core.tick_offset}, learned state {checkpoint.digest(checkpoint.decision_learned(self.core))}")

    # -- ticks ----------------------------------------------------------------------------
    def _put(self, key, msg) -> None:
        for k, fields in self.host.stage.put(key, msg):
            self.send(self.pub, k, fields, self.host.stage.run)
            self.ticks = self.core.tick_offset + k + (0 if fields.get("final") else 1)
            self.checkpoints.after_tick(self.ticks)

    # -- services -------------------------------------------------------------------------
    def _load(self, path: str | None = None) -> tuple[bool, str]:
        """Load ``path`` (default: q_table_path): a Q-table file or a decision checkpoint."""
        path = self.q_path if path is None else path
        if not path:
            return False, "q_table_path is not set"
        if not Path(path).is_file():
            return False, f"Q-table file not found: {path}"
        try:
            rep = checkpoint.load_table(self.core.q, path)
        except (qtable_io.QTableError, OSError) as exc:
            return False, str(exc)
        msg = f"loaded {path}: {', '.join(rep.loaded)}"
        if rep.new:
            msg += f"; new objects start fresh: {', '.join(rep.new)}"
        if rep.dropped:
            msg += f"; dropped: {', '.join(rep.dropped)}"
        return True, msg

    def _save(self) -> tuple[bool, str]:
        if not self.q_path:
            return False, "q_table_path is not set"
        c = self.core
        try:
            qtable_io.save(c.q, self.q_path, meta={"node": self.get_name(), **c.params(), SEED.name: c.seed})
        except qtable_io.QTableError as exc:  # a directory, a read-only place, a full disk
            return False, str(exc)
        return True, f"saved {self.q_path}"

    def _reset(self) -> tuple[bool, str]:
        self.core.reset()
        self.host.decision.restart()
        return True, f"Q-table cleared, decision stream reseeded with {self.core.seed}"


def main(args=None) -> int:
    return run_scenario_node(DecisionNode, args)


if __name__ == "__main__":
    sys.exit(main())

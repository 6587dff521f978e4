"""``homeo_drives`` node: the robot's perception part (``homeo_decision.robot.Perception``).

Publishes  homeo/drives (state), /diagnostics
Subscribes homeo/world (state, carrying the outcome of the tick before), homeo/intention (state)
Parameters scenario, overrides, and the checkpoint parameters of ``durable`` (read-only)

Tick k joins the world of tick k (which carries the outcome of tick k-1: ``homeo_msgs_py.graph``) and the
recognised intention of tick k: the effects of k-1, the body of k, Eq 3.2-3.3 for the perceived world.

The node carries the internal drives from tick to tick: no latched topic holds them once the node
is gone (its own latched drives die with it), so it checkpoints them every tick in two slots of one
file (``checkpoint.SlotWriter``: one ``pwrite``, no fsync, tens of microseconds), right after the
answer is sent: the write is off the lockstep's path (the decision is at work on the answer
meanwhile). A thread of its own would cost more than the write (handing the GIL over and back, about
0.1 ms a tick: ``homeo-launch bench --profile``). Restarted by the launcher within the run, it goes on
from the state it had after the last tick it answered (a SIGKILL between the answer and the write
loses that one tick: the slot of the tick before is whole); a resumed run starts a new episode from
the scenario's initial drives, as ever.
"""

from __future__ import annotations

import sys

from homeo_msgs_py.graph import NODES
from homeo_msgs_py.node_base import NodeConfigError
from homeo_msgs_py.schemas import Rejected

from . import checkpoint, durable
from .hosts import PerceptionHost
from .node_runtime import ScenarioNode, run_scenario_node
from .scenario import ScenarioError

DESC = NODES["homeo_drives"]


class DrivesNode(durable.CheckpointedNode, ScenarioNode):
    def __init__(self):
        super().__init__(DESC.name)
        self.host = PerceptionHost(self.sc)
        self.durable = durable.declare(self)
        durable.setup_stage(self, self.host.stage, self.durable)  # an upstream node that died must not wedge this one
        self.ticks = 0  # ticks perceived in this run
        self._answer: tuple | None = None  # (tick, fields) of the last answer
        ck = durable.read_start(self, self.durable) if self.durable["respawned"] else None  # not on --resume
        if ck is not None:
            where = str(checkpoint.path_for(self.durable["resume_dir"], DESC.name))
            try:
                checkpoint.restore_drives(self.host, ck, where)
            except checkpoint.CheckpointError as exc:
                raise NodeConfigError(f"resume: {exc}") from None
            self.ticks = ck["ticks"]
            self._answer = (ck["state"]["tick"], ck["state"]["answer"])
            self.get_logger().info(
                f"rejoined from {where}: run {ck['run']}, tick {ck['state']['tick']}, learned state "
                f"{checkpoint.digest(checkpoint.drives_learned(self.host.perception))}")
        self.checkpoints = durable.checkpointer(
            self, lambda: checkpoint.drives_checkpoint(self.host.perception, max(0, self.host.stage.run), *self._answer,
                                                       self.durable["session"]), every=1, throttle_s=5.0,
            background=False)
        self.pub = self.robot_publisher("drives")
        for i in DESC.inputs:
            self.subscribe(i.topic, lambda m, key=i.topic: self._put(key, m))

    def _put(self, key, msg) -> None:
        try:
            done = self.host.stage.put(key, msg)
        except ScenarioError as exc:  # validated fields always encode; stay up regardless
            raise Rejected(str(exc)) from None
        for k, fields in done:
            new = (k, fields) != self._answer  # not a repeat of the last answer
            if new:
                self._answer, self.ticks = (k, fields), k + 1
            self.send(self.pub, k, fields, self.host.stage.run)
            if new:
                self.checkpoints.save()  # every tick, once the answer is on its way


def main(args=None) -> int:
    return run_scenario_node(DrivesNode, args)


if __name__ == "__main__":
    sys.exit(main())

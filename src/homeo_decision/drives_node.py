"""``homeo_drives`` node: the robot's perception part (``homeo_decision.robot.Perception``).

Publishes  homeo/drives (state), /diagnostics
Subscribes homeo/world (state), homeo/intention (state), homeo/outcome (event)
Parameters scenario, overrides, supervised (read-only; see ``durable``)

Tick k joins the world and the recognised intention of tick k with the outcome of tick k-1
(``homeo_msgs_py.graph``): the effects of k-1, the body of k, Eq 3.2-3.3 for the perceived world.
"""

from __future__ import annotations

import sys

from rcl_interfaces.msg import ParameterDescriptor

from homeo_msgs_py.graph import NODES
from homeo_msgs_py.rejoin import make_rejoinable
from homeo_msgs_py.schemas import Rejected

from .hosts import PerceptionHost
from .node_runtime import ScenarioNode, run_scenario_node
from .scenario import ScenarioError

DESC = NODES["homeo_drives"]


class DrivesNode(ScenarioNode):
    def __init__(self):
        super().__init__(DESC.name)
        self.host = PerceptionHost(self.sc)
        if self.declare_fixed("supervised", False, ParameterDescriptor(
                description="restarted nodes rejoin the run: skip a gap of ticks")):
            make_rejoinable(self.host.stage)  # an upstream node that died must not wedge this one
        self.pub = self.robot_publisher("drives")
        for i in DESC.inputs:
            self.subscribe(i.topic, lambda m, key=i.topic: self._put(key, m))

    def _put(self, key, msg) -> None:
        try:
            done = self.host.stage.put(key, msg)
        except ScenarioError as exc:  # validated fields always encode; stay up regardless
            raise Rejected(str(exc)) from None
        for k, fields in done:
            self.send(self.pub, k, fields, self.host.stage.run)


def main(args=None) -> int:
    return run_scenario_node(DrivesNode, args)


if __name__ == "__main__":
    sys.exit(main())

"""``homeo_drives`` node: the robot's perception part (``homeo_decision.robot.Perception``).

Publishes  homeo/drives (state), /diagnostics
Subscribes homeo/world (state), homeo/intention (state), homeo/outcome (event)
Parameters scenario, overrides (read-only)

Tick k joins the world and the recognised intention of tick k with the outcome of tick k-1
(``homeo_msgs_py.graph``): the effects of k-1, the body of k, Eq 3.2-3.3 for the perceived world.
"""

from __future__ import annotations

import sys

from homeo_msgs_py.graph import NODES
from homeo_msgs_py.lockstep import TickJoin

from . import codec
from .node_runtime import ScenarioNode, run_scenario_node
from .robot import Perception
from .scenario import ScenarioError

DESC = NODES["homeo_drives"]


class DrivesNode(ScenarioNode):
    def __init__(self):
        super().__init__(DESC.name)
        self.perception = Perception(self.sc)
        self.join = TickJoin(DESC.join_offsets(learning=True))
        self.pub = self.publisher("drives")
        for i in DESC.inputs:
            self.subscribe(i.topic, lambda m, key=i.topic: self._put(key, m))

    def _put(self, key, msg) -> None:
        run = self.join.run
        done = self.join.put(key, msg)
        if self.join.run != run:  # a new run of the world: drives start over
            self.perception.restart()
        sc = self.sc
        for k, inputs in done:
            world = inputs["world"].fields
            out = codec.outcome_from_fields(sc, inputs["outcome"].fields) if "outcome" in inputs else None
            try:
                obs = codec.observation_from_fields(sc, world, None)
                perceived = self.perception.tick(obs.code, sc.intention_names.index(
                    inputs["intention"].fields["intention"]), obs.body, out)
            except ScenarioError as exc:  # validated fields always encode; stay up regardless
                self.reject(self.pub.topic, str(exc))
                continue
            fields = codec.drives_fields(sc, perceived, world, out, self.perception.after_action,
                                         final=bool(world.get("final")))
            self.send(self.pub, k, fields, self.join.run)


def main(args=None) -> int:
    return run_scenario_node(DrivesNode, args)


if __name__ == "__main__":
    sys.exit(main())

"""``homeo_drives`` node: the robot's drives, stimuli, intensities and dominant motivation.

Publishes  /homeo/drives (state), /diagnostics
Subscribes /homeo/world (state), /homeo/intention (state), /homeo/outcome (event)
Parameters scenario, overrides (read-only)

Tick k needs the world and the recognised intention of tick k and the outcome of tick k-1
(the action's effects, the feedback, the time step); see ``DriveTracker``.
"""

from __future__ import annotations

import sys

from homeo_msgs_py.lockstep import TickJoin
from homeo_msgs_py.node_base import HomeoNode, run_node
from homeo_msgs_py.topics import DRIVES, INTENTION, OUTCOME, WORLD

from .drive_tracker import DrivesStage
from .scenario import ScenarioError


class DrivesNode(HomeoNode):
    def __init__(self):
        super().__init__("homeo_drives")
        self.stage = DrivesStage(self.sc)
        self.join = TickJoin({"world": 0, "intention": 0, "outcome": -1})
        self.pub = self.publisher(DRIVES)
        self.subscribe(WORLD, lambda m: self._put("world", m))
        self.subscribe(INTENTION, lambda m: self._put("intention", m))
        self.subscribe(OUTCOME, lambda m: self._put("outcome", m))

    def _put(self, name, msg) -> None:
        run = self.join.run
        done = self.join.put(name, msg)
        if self.join.run != run:  # a new run of the world: drives start over
            self.stage.restart()
        for k, inputs in done:
            out = inputs.get("outcome")
            try:
                fields = self.stage.tick(inputs["world"].fields, inputs["intention"].fields["intention"],
                                         out.fields if out is not None else None)
            except ScenarioError as exc:  # validated fields always encode; stay up regardless
                self.reject(WORLD, str(exc))
                continue
            self.send(self.pub, k, fields, self.join.run)


def main(args=None) -> int:
    return run_node(DrivesNode, args)


if __name__ == "__main__":
    sys.exit(main())

"""The simulated body: NRes (joint heat) and NEng (battery) as drives (Tables 4.1, 4.2).

On Pepper these two come from the joint temperature status and the battery instead.
"""

from __future__ import annotations

from homeo_decision.drives import DriveDynamics
from homeo_decision.scenario import Scenario


class SimBody(DriveDynamics):
    def __init__(self, sc: Scenario):
        super().__init__(sc, "body")

    def readings(self) -> dict[str, float]:
        return {self.sc.drives[i].name: self.values[i] for i in self.idx}

"""The thesis's simulation recognises nothing: the intention is observed directly (oracle)."""

from __future__ import annotations


class OracleStage:
    """The intention node's oracle mode without ROS: ``homeo/observation`` fields in,
    ``homeo/intention`` fields out (the observed intention, with certainty)."""

    mode = "oracle"

    def __init__(self, sc):
        self.names = sc.intention_names

    def restart(self) -> None:
        pass

    def tick(self, obs: dict, outcome: dict | None = None) -> dict:
        name = obs["intention"]
        return {"intention": name, "posterior": {n: (1.0 if n == name else 0.0) for n in self.names},
                "mode": self.mode}

"""The intention node's core without ROS: ``homeo/observation`` (+ the last outcome) in,
``homeo/intention`` out, with either recogniser of ``homeo_intention.model``.

Tick k first learns from tick k-1 (its observation, and the intention the user revealed in
the outcome, if any), then recognises tick k: the in-process runner's order, so the graph
and ``homeo-sim run --intention bayes`` recognise the same intentions.
"""

from __future__ import annotations

from homeo_decision.scenario import OBS_CHANNELS

from .model import make_model
from .observation import UnknownObservation

MODES = ("oracle", "bayes")


class RecogniserStage:
    def __init__(self, sc, mode: str, **settings):
        if mode not in MODES:
            raise ValueError(f"unknown intention mode {mode!r}; known: {', '.join(MODES)}")
        self.sc = sc
        self.mode = mode
        self.model = make_model(mode, sc, **settings)
        self.names = sc.intention_names
        self.prev_obs: dict | None = None

    @property
    def learns(self) -> bool:
        return self.mode != "oracle"

    def restart(self) -> None:
        """A new run of the world: what the model learned about this user stays."""
        self.prev_obs = None

    def check(self, obs: dict) -> None:
        """Raises UnknownObservation for a symbol outside the scenario's alphabets (or, for the
        oracle, a missing intention), before the observation is taken into a tick."""
        self.model.recognise(self._cues(obs))

    def _cues(self, obs: dict) -> dict:
        if self.mode == "oracle":
            if obs.get("intention") is None:
                raise UnknownObservation("oracle mode needs the intention in the observation")
            return obs
        return {ch: obs.get(ch) for ch in OBS_CHANNELS}  # the robot does not see the true intention

    def tick(self, obs: dict, outcome: dict | None) -> dict:
        if self.learns and outcome is not None and self.prev_obs is not None:
            revealed = outcome.get("clarified_intention")
            self.model.learn(self._cues(self.prev_obs), self.names.index(revealed) if revealed else None)
        r = self.model.recognise(self._cues(obs))
        self.prev_obs = obs
        return {"intention": self.names[r.intention], "posterior": dict(zip(self.names, r.posterior)),
                "mode": self.mode}

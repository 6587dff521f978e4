"""The robot's recognition part (``homeo_decision.robot``), as the intention node hosts it.

Tick t first learns from tick t-1 (its cues, and the intention the human revealed in its outcome,
if any), then recognises tick t from its cues alone: the true intention in an observation is
never read. ``make_recognition`` also gives the oracle (the thesis's own simulation).
"""

from __future__ import annotations

from homeo_decision import codec
from homeo_decision.environment import Observation, Outcome
from homeo_decision.robot import OracleRecognition
from homeo_decision.scenario import OBS_CHANNELS, Scenario
from homeo_msgs_py.graph import BAYES, INTENTION_MODES, ORACLE

from .model import IntentionModel, Recognition


class BayesRecognition:
    learns = True

    def __init__(self, sc: Scenario, model: IntentionModel | None = None, **settings):
        self.model = model if model is not None else IntentionModel(sc, **settings)
        self._prev: dict | None = None

    def restart(self) -> None:
        """A new episode: what the model learned about this user stays."""
        self._prev = None

    @staticmethod
    def _cues(obs: Observation) -> dict:
        cues = obs.cues or {}
        return {ch: cues.get(ch) for ch in OBS_CHANNELS}

    def check(self, obs: Observation) -> None:
        """Raises UnknownObservation for a symbol outside the scenario's alphabets."""
        self.model.recognise(self._cues(obs))

    def tick(self, obs: Observation, out: Outcome | None) -> Recognition:
        if out is not None and self._prev is not None:
            self.model.learn(self._prev, out.clarified)
        cues = self._cues(obs)
        r = self.model.recognise(cues)
        self._prev = cues
        return r


def make_recognition(mode: str, sc: Scenario, **settings):
    if mode == ORACLE:
        return OracleRecognition(sc)
    if mode == BAYES:
        return BayesRecognition(sc, **settings)
    raise ValueError(f"unknown intention mode {mode!r}; known: {', '.join(INTENTION_MODES)}")


class RecognitionHost:
    """``homeo_intention`` without ROS: observation(k) (carrying the outcome of k-1) -> intention(k)."""

    def __init__(self, sc: Scenario, mode: str, **settings):
        from homeo_msgs_py.graph import NODES
        from homeo_msgs_py.lockstep import JoinedStage

        self.sc, self.mode = sc, mode
        self.part = make_recognition(mode, sc, **settings)
        self.offsets = NODES["homeo_intention"].join_offsets(self.part.learns)
        self.stage = JoinedStage(self.offsets, self._tick, self.part.restart)

    def check(self, fields: dict) -> None:
        """Raises ValueError for an observation this mode cannot use (before it joins a tick)."""
        self.part.check(codec.observation_from_fields(self.sc, None, fields))

    def _tick(self, k: int, inputs: dict) -> dict:
        sc, seen = self.sc, inputs["observation"]
        out = codec.outcome_from_fields(sc, seen["outcome"]) if self.part.learns and "outcome" in seen else None
        r = self.part.tick(codec.observation_from_fields(sc, None, seen), out)
        names = sc.intention_names
        return {"intention": names[r.intention], "posterior": dict(zip(names, r.posterior)), "mode": self.mode}

"""The thesis's intention recogniser (Section 2.3): ``recognise(cues) -> Recognition``, ``learn(cues, label)``.

A Bayesian network over the user's gesture, movement and spoken keyword, the arg-max of the
posterior (Eq 2.10), and EM when the user reveals what they meant. No rclpy: the robot's
recognition part (``recognition.py``) and the ROS node wrap it.

Cues are dicts with the symbols under ``gesture``, ``movement`` and ``keyword`` (a missing or
None channel is unobserved).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from homeo_decision.scenario import OBS_CHANNELS, Scenario

from .em import Params, run_em
from .network import posterior_table, to_pgmpy
from .observation import ObservationCoder


@dataclass(slots=True)
class Recognition:
    intention: int  # index into Scenario.intention_names (0 = none)
    posterior: list  # P(I | z), in Scenario.intention_names order
    confidence: float  # the largest posterior value


def prior_params(sc: Scenario) -> Params:
    """The network's textbook CPDs from the scenario's ``observations.prior``."""
    spec = sc.observations
    return Params(np.array(spec.prior_intention, float), [np.array(spec.prior[ch], float) for ch in OBS_CHANNELS])


class IntentionModel:
    """Bayesian intention recognition that learns this user by EM.

    Settings (defaults from the scenario's ``open`` block): ``threshold`` -- below this posterior
    the recognised intention is ``none``; ``prior_strength`` -- how many textbook observations
    each prior CPD column is worth (Dirichlet pseudo counts of the MAP-EM); ``max_iter`` and
    ``atol`` -- when one EM run stops.
    """

    def __init__(self, sc: Scenario, threshold: float | None = None, prior_strength: float | None = None,
                 max_iter: int = 100, atol: float = 1e-6):
        self.sc = sc
        self.coder = ObservationCoder(sc)  # raises ScenarioError without an observations block
        self.names = sc.intention_names
        self.K = len(self.names)
        self.threshold = float(sc.open.intention_threshold if threshold is None else threshold)
        self.strength = float(sc.open.intention_prior_strength if prior_strength is None else prior_strength)
        if not 0.0 <= self.threshold <= 1.0:
            raise ValueError(f"threshold must be in [0, 1], got {self.threshold}")
        if not self.strength >= 0.0:
            raise ValueError(f"prior_strength must be >= 0, got {self.strength}")
        self.max_iter, self.atol = int(max_iter), float(atol)
        self.prior = prior_params(sc)
        self.reset()

    # -- state ---------------------------------------------------------------------------
    def reset(self) -> None:
        """Back to the textbook prior, with nothing seen."""
        self.params = self.prior.copy()
        self.labelled = np.zeros((self.K, self.coder.n_cells))
        self.unlabelled = np.zeros(self.coder.n_cells)
        self.em_runs = 0
        self.em_iterations = 0
        self._refresh()

    def _refresh(self) -> None:
        """Recompute the posterior of every cell (Eq 2.10's P(hi | z)) and its recognition."""
        post = posterior_table(self.params.pi, self.params.likes).T  # (n_cells, K)
        best = post.argmax(axis=1)  # ties: the first intention, i.e. `none` before the others
        conf = post[np.arange(len(best)), best]
        best[conf < self.threshold] = 0
        self._post = post
        self._best = best.tolist()
        self._conf = conf.tolist()

    def set_params(self, params: Params) -> None:
        """Replace the CPDs (e.g. loaded from a file) and recompute the posterior table."""
        self.params = params.copy()
        self._refresh()

    # -- the interface -------------------------------------------------------------------
    def recognise(self, obs: dict) -> Recognition:
        """Eq 2.10: hi = argmax_hi P(hi | z); ``none`` when the maximum is below the threshold."""
        c = self.coder.cell(obs)
        return Recognition(self._best[c], self._post[c].tolist(), self._conf[c])

    def learn(self, obs: dict, label: int | None) -> int:
        """Remember ``obs`` with the revealed intention ``label`` (None: not revealed). A label that
        corrects the recognition of ``obs`` is the thesis's clarification: EM then re-estimates the
        network from everything seen so far, started from the current CPDs. Agreeing labels and
        unlabelled observations are only counted; they enter the next EM run. Returns the EM
        iterations run (0 when none ran)."""
        c = self.coder.cell(obs)
        if label is None:
            self.unlabelled[c] += 1.0
            return 0
        if not (isinstance(label, (int, np.integer)) and not isinstance(label, bool) and 0 <= label < self.K):
            raise ValueError(f"label must be an intention index in [0, {self.K - 1}] or None, got {label!r}")
        self.labelled[label, c] += 1.0
        if label == self._best[c]:
            return 0
        return self.fit()

    def fit(self) -> int:
        """Run EM on all counts from the current CPDs; returns its iterations."""
        self.params, n = run_em(self.params, self.labelled, self.unlabelled, self.coder.shape, self.prior,
                                self.strength, self.max_iter, self.atol)
        self.em_runs += 1
        self.em_iterations += n
        self._refresh()
        return n

    # -- views ---------------------------------------------------------------------------
    def cpds(self) -> dict:
        """The CPDs by name: ``{"intention": {name: p}, "revealed": {name: P(revealed | name)},
        channel: {intention: {symbol: p}}}``."""
        out = {"intention": dict(zip(self.names, self.params.pi.tolist())),
               "revealed": dict(zip(self.names, self.params.rho.tolist()))}
        for ch, alpha, L in zip(OBS_CHANNELS, self.coder.alphabets, self.params.likes):
            out[ch] = {n: dict(zip(alpha, row)) for n, row in zip(self.names, L.tolist())}
        return out

    def network(self):
        """The current network as a pgmpy ``DiscreteBayesianNetwork`` (built on request: pgmpy is slow to import)."""
        return to_pgmpy(self.names, self.coder.alphabets, self.params.pi, self.params.likes)

    # -- files -----------------------------------------------------------------------------
    def to_json(self, meta: dict | None = None) -> dict:
        from .model_io import to_dict

        return to_dict(self, meta)

    @classmethod
    def from_json(cls, sc: Scenario, raw, where: str = "<memory>", **settings) -> "IntentionModel":
        from .model_io import from_dict

        m = cls(sc, **settings)
        from_dict(m, raw, where)
        return m

    def save(self, path: str | Path, meta: dict | None = None) -> None:
        from .model_io import save

        save(self, path, meta)

    def load(self, path: str | Path) -> None:
        from .model_io import load

        load(self, path)

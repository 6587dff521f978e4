"""Evaluation metrics of Section 4.1: HSR (4.1), CDA (4.2-4.3), CEDA (4.4-4.5), RSR (4.6-4.7).

A run records, for every iteration t, the drives d(t) after the iteration, whether the
human expressed an intention, and whether the robot's action satisfied it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

INSECURE = 90.0  # Eq 4.7: secure iff every drive < 90


@dataclass
class MetricRecorder:
    drive_names: Sequence[str]
    thresholds: Sequence[float]
    _drives: list = field(default_factory=list)
    _expressed: list = field(default_factory=list)
    _satisfied: list = field(default_factory=list)

    def record(self, drives: Sequence[float], expressed: bool, satisfied: bool) -> None:
        self._drives.extend(drives)
        self._expressed.append(expressed)
        self._satisfied.append(satisfied)

    def follow(self, perception, after_action: bool = False) -> "MetricRecorder":
        """Record from a robot's perception in ``on_tick`` (``robot.run_loop``'s hook): its drives after
        each tick, or right after the action (the open choice ``metrics_sample``)."""
        self._perception, self._after_action = perception, after_action
        return self

    def on_tick(self, t, p, r, a, out) -> None:
        """``run_loop``'s hook: d(t) from the followed perception, the truth from the outcome."""
        per = self._perception
        self._drives.extend(per.after_action if self._after_action else per.drives)
        self._expressed.append(out.true_intention != 0)
        self._satisfied.append(out.satisfied)

    @property
    def n(self) -> int:
        return len(self._expressed)

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        d = np.asarray(self._drives, dtype=float).reshape(-1, len(self.drive_names))
        return d, np.asarray(self._expressed, dtype=bool), np.asarray(self._satisfied, dtype=bool)

    def summary(self) -> dict:
        return summarize(*self.arrays(), self.drive_names, self.thresholds)

    def series(self) -> dict:
        return cumulative_series(*self.arrays(), self.drive_names, self.thresholds)


def summarize(drives: np.ndarray, expressed: np.ndarray, satisfied: np.ndarray, names, thresholds) -> dict:
    """The four metrics at the end of a run, per drive and 'all'."""
    n = len(expressed)
    if n == 0:
        raise ValueError("no iterations recorded")
    thr = np.asarray(thresholds, dtype=float)
    cda = drives.mean(axis=0)  # Eq 4.2
    ceda = np.maximum(drives - thr, 0.0).mean(axis=0)  # Eq 4.4
    n_int = int(expressed.sum())
    hsr = float(satisfied.sum() / n_int) if n_int else float("nan")  # Eq 4.1
    rsr = float((drives < INSECURE).all(axis=1).mean())  # Eq 4.6-4.7
    out_cda = {nm: float(v) for nm, v in zip(names, cda)}
    out_cda["all"] = float(cda.mean())  # Eq 4.3
    out_ceda = {nm: float(v) for nm, v in zip(names, ceda)}
    out_ceda["all"] = float(ceda.mean())  # Eq 4.5
    return {"HSR": hsr, "RSR": rsr, "CDA": out_cda, "CEDA": out_ceda, "intentions": n_int}


def cumulative_series(drives: np.ndarray, expressed: np.ndarray, satisfied: np.ndarray, names, thresholds) -> dict:
    """Each metric as it stands after iterations 1..N (the curves of Figs 4.1-4.2)."""
    t = np.arange(1, len(expressed) + 1, dtype=float)
    thr = np.asarray(thresholds, dtype=float)
    cda = np.cumsum(drives, axis=0) / t[:, None]
    ceda = np.cumsum(np.maximum(drives - thr, 0.0), axis=0) / t[:, None]
    n_int = np.cumsum(expressed)
    with np.errstate(invalid="ignore", divide="ignore"):
        hsr = np.where(n_int > 0, np.cumsum(satisfied) / np.maximum(n_int, 1), np.nan)
    rsr = np.cumsum((drives < INSECURE).all(axis=1)) / t
    return {
        "drives": {nm: drives[:, i] for i, nm in enumerate(names)},
        "CDA": {nm: cda[:, i] for i, nm in enumerate(names)} | {"all": cda.mean(axis=1)},
        "CEDA": {nm: ceda[:, i] for i, nm in enumerate(names)} | {"all": ceda.mean(axis=1)},
        "HSR": hsr,
        "RSR": rsr,
        "expressed": expressed,  # per iteration: an intention was expressed (for moving-window rates)
        "satisfied": satisfied,  # per iteration: the robot's action satisfied it
    }


# -- intention recognition (docs/INTENTION.md) ------------------------------------------------
# Accuracy of a run's recogniser: the fraction of ticks whose recognised intention equals the
# human's true one at that tick (`none` included: recognising "nothing wanted" counts too).

ACCURACY_WINDOW = 500


def accuracy_ends(hits: Sequence[bool], window: int = ACCURACY_WINDOW) -> dict:
    """Accuracy over the first and the last ``window`` ticks (the whole run if it is shorter)."""
    if not hits:
        raise ValueError("no iterations recorded")
    w = min(window, len(hits))
    return {f"first_{window}": sum(hits[:w]) / w, f"last_{window}": sum(hits[-w:]) / w}


def accuracy_curve(hits: Sequence[bool], width: int = 250) -> list[float]:
    """Accuracy per consecutive window of ``width`` ticks (a shorter last window is dropped)."""
    return [sum(hits[i:i + width]) / width for i in range(0, len(hits) - width + 1, width)]

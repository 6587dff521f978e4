"""Evaluation metrics of Section 4.1: HSR (4.1), CDA (4.2-4.3), CEDA (4.4-4.5), RSR (4.6-4.7).

A run records, for every iteration t, the drives d(t) after the iteration, whether the
human expressed an intention, and whether the robot's action satisfied it.
"""

from __future__ import annotations

import math
from collections import deque
from typing import Sequence

import numpy as np

INSECURE = 90.0  # Eq 4.7: secure iff every drive < 90


class MetricRecorder:
    """The metrics of a run, kept incrementally: O(1) per tick and fixed memory, so a run of any
    length costs the same per tick (a node publishes them four times a second). Running sums in
    tick order give bit for bit what ``summarize`` computes over the whole arrays (numpy sums a
    column of a C-ordered array row by row). ``keep=True`` also keeps every tick (``series``)."""

    def __init__(self, drive_names: Sequence[str], thresholds: Sequence[float], keep: bool = False,
                 marks: Sequence[int] = ()):
        self.drive_names = list(drive_names)
        # the running sums after each of these ticks (``stages``: the metrics over part of a run)
        self._marks, self.stages = list(marks)[::-1], []
        self.thresholds = [float(x) for x in thresholds]
        self._n = self._n_int = self._n_sat = self._n_secure = 0
        self._sum = [0.0] * len(self.drive_names)
        self._excess = [0.0] * len(self.drive_names)
        self._keep = keep
        self._drives: list = []
        self._expressed: list = []
        self._satisfied: list = []

    def record(self, drives: Sequence[float], expressed: bool, satisfied: bool) -> None:
        s, e, thr = self._sum, self._excess, self.thresholds
        secure = True
        for i, d in enumerate(drives):
            s[i] += d
            x = d - thr[i]
            e[i] += x if x > 0.0 else 0.0
            if not d < INSECURE:
                secure = False
        self._n += 1
        self._n_secure += secure
        self._n_int += bool(expressed)
        self._n_sat += bool(satisfied)
        if self._marks and self._n == self._marks[-1]:
            self._marks.pop()
            self.stages.append(self.state())
        if self._keep:
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
        self.record(per.after_action if self._after_action else per.drives, out.true_intention != 0, out.satisfied)

    @property
    def n(self) -> int:
        return self._n

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Every tick's record (only with ``keep=True``)."""
        if not self._keep:
            raise ValueError("this recorder keeps no per-tick history (MetricRecorder(keep=True))")
        d = np.asarray(self._drives, dtype=float).reshape(-1, len(self.drive_names))
        return d, np.asarray(self._expressed, dtype=bool), np.asarray(self._satisfied, dtype=bool)

    def summary(self) -> dict:
        """``summarize`` of everything recorded, from the running sums."""
        n = self._n
        if n == 0:
            raise ValueError("no iterations recorded")
        names = self.drive_names
        cda = np.array([x / n for x in self._sum])  # Eq 4.2
        ceda = np.array([x / n for x in self._excess])  # Eq 4.4
        n_int = self._n_int
        hsr = float(self._n_sat / n_int) if n_int else float("nan")  # Eq 4.1
        out_cda = {nm: float(v) for nm, v in zip(names, cda)}
        out_cda["all"] = float(cda.mean())  # Eq 4.3
        out_ceda = {nm: float(v) for nm, v in zip(names, ceda)}
        out_ceda["all"] = float(ceda.mean())  # Eq 4.5
        return {"HSR": hsr, "RSR": float(self._n_secure / n), "CDA": out_cda, "CEDA": out_ceda,
                "intentions": n_int}

    def series(self) -> dict:
        return cumulative_series(*self.arrays(), self.drive_names, self.thresholds)

    def state(self) -> dict:
        """The running sums as JSON-able data (a checkpoint); floats round-trip exactly through JSON."""
        return {"n": self._n, "intentions": self._n_int, "satisfied": self._n_sat, "secure": self._n_secure,
                "sum": list(self._sum), "excess": list(self._excess)}

    def set_state(self, st) -> None:
        """Go on from ``state()``; raises ValueError (one line) for anything else, changing nothing."""
        if self._keep:
            raise ValueError("a recorder that keeps every tick cannot take a running-sums state")
        if not isinstance(st, dict):
            raise ValueError("not a metrics state")
        counts = [st.get(k) for k in ("n", "intentions", "satisfied", "secure")]
        if not all(type(c) is int and c >= 0 for c in counts):
            raise ValueError("metric counts must be integers >= 0")
        n, n_int, n_sat, n_sec = counts
        if n_int > n or n_sat > n_int or n_sec > n:
            raise ValueError(f"inconsistent metric counts {counts}")
        sums = []
        for key in ("sum", "excess"):
            v = st.get(key)
            if not isinstance(v, list) or len(v) != len(self.drive_names) or not all(
                    type(x) in (int, float) and math.isfinite(x) and x >= 0.0 for x in v):
                raise ValueError(f"metric {key} must be {len(self.drive_names)} finite numbers >= 0")
            sums.append([float(x) for x in v])
        self._n, self._n_int, self._n_sat, self._n_secure = counts
        self._sum, self._excess = sums


def stage_marks(n: int) -> tuple:
    """The ticks after which a run keeps its running sums: every 10 up to 100, then every 100, and the last."""
    return tuple(sorted({t for t in (*range(10, 101, 10), *range(200, n, 100)) if t < n} | {n}))


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


class AccuracyEnds:
    """``accuracy_ends`` kept in fixed memory: the first ``window`` hits and a ring of the last."""

    def __init__(self, window: int = ACCURACY_WINDOW):
        self.window = window
        self.first: list[bool] = []
        self.last: deque = deque(maxlen=window)

    def append(self, hit: bool) -> None:
        if len(self.first) < self.window:
            self.first.append(hit)
        self.last.append(hit)

    def __len__(self) -> int:
        return len(self.last)

    def state(self) -> dict:
        bits = lambda xs: "".join("1" if x else "0" for x in xs)  # noqa: E731
        return {"window": self.window, "first": bits(self.first), "last": bits(self.last)}

    def set_state(self, st) -> None:
        """Go on from ``state()``; raises ValueError (one line) for anything else, changing nothing."""
        if not isinstance(st, dict) or st.get("window") != self.window:
            raise ValueError(f"not an accuracy state of window {self.window}")
        first, last = st.get("first"), st.get("last")
        for v in (first, last):
            if not isinstance(v, str) or len(v) > self.window or v.strip("01"):
                raise ValueError(f"accuracy hits must be strings of 0 and 1, at most {self.window} long")
        if len(last) < len(first):
            raise ValueError("accuracy hits: fewer last than first")
        self.first = [c == "1" for c in first]
        self.last = deque((c == "1" for c in last), maxlen=self.window)

    def ends(self) -> dict:
        if not self.last:
            raise ValueError("no iterations recorded")
        w = self.window
        n = min(w, len(self.first))
        return {f"first_{w}": sum(self.first[:n]) / n, f"last_{w}": sum(self.last) / len(self.last)}

"""Drives, motivations and the dominant motivation (Section 3.1, Eq 3.2-3.3, 3.6)."""

from __future__ import annotations

from typing import Sequence


def intensities(drives: Sequence[float], thresholds: Sequence[float], stimulus: Sequence[float]) -> list[float]:
    """Eq 3.2: intensity(m_i) = 0 if d_i < at_i, else d_i + sum of present stimuli effects on m_i.

    ``stimulus[i]`` is already the sum over the present stimuli of their effect on m_i.
    """
    return [0.0 if d < at else d + s for d, at, s in zip(drives, thresholds, stimulus)]


def dominant(intens: Sequence[float], tie_break: str = "first") -> int:
    """Eq 3.3 / 3.6: m_dom = argmax_m intensity(m); ties go to the first (or last) declared."""
    best = 0
    top = intens[0]
    if tie_break == "first":
        for i in range(1, len(intens)):
            if intens[i] > top:
                best, top = i, intens[i]
    else:
        for i in range(1, len(intens)):
            if intens[i] >= top:
                best, top = i, intens[i]
    return best


def motivational_state(drives: Sequence[float], thresholds: Sequence[float], stimulus: Sequence[float],
                       tie_break: str = "first", none_state: int = -1) -> tuple[list[float], int]:
    """Eq 3.2 then Eq 3.3: the intensities and the dominant motivation (the robot's internal state,
    Eq 3.6). The one place both are combined: perception, the pseudo state of Eq 3.23 and the
    baselines all call it."""
    inten = [0.0 if d < at else d + s for d, at, s in zip(drives, thresholds, stimulus)]  # Eq 3.2, inlined: hot path
    if none_state >= 0 and not any(x > 0.0 for x in inten):
        return inten, none_state  # open choice no_activated_motivation: none activated (Definition 6), no m_dom
    return inten, dominant(inten, tie_break)


def dod_weights(dod: float, n_drives: int, serving: int) -> list[float]:
    """Eq 3.27-3.28: w_serving = DoD * |D|; the others share |D| - w_serving equally."""
    if not 0.0 <= dod <= 1.0:
        raise ValueError(f"DoD must be in [0, 1], got {dod}")
    if n_drives == 1:
        return [1.0]
    w_s = dod * n_drives
    w_o = (n_drives - w_s) / (n_drives - 1)
    return [w_s if i == serving else w_o for i in range(n_drives)]


def clamp(x: float) -> float:
    """Drives live in [0, 100] (Definition 1)."""
    return 0.0 if x < 0.0 else 100.0 if x > 100.0 else x

"""The reward (Eq 3.18-3.22) and the pseudo reward of a proposal (Section 3.2.6)."""

from __future__ import annotations

from typing import Sequence

from .motivation import clamp


def drive_reward(before: Sequence[float], after: Sequence[float], weights: Sequence[float], k: int, xi: float) -> float:
    """Eq 3.20 (3.19 with the motivation factor): sum_i (1 + delta_ik xi) w_i (d_i,before - d_i,after).

    ``k`` is the index of the drive of the dominant motivation (Eq 3.21's Kronecker delta).
    """
    r = 0.0
    for i, (w, b, a) in enumerate(zip(weights, before, after)):
        term = w * (b - a)
        r += term * (1.0 + xi) if i == k else term
    return r


def feedback_reward(feedback: int, f: float) -> float:
    """Eq 3.22: +f for positive feedback, -f for negative, 0 for none."""
    return f if feedback > 0 else -f if feedback < 0 else 0.0


def reward(before, after, weights, k, xi, feedback, f) -> float:
    """Eq 3.18: r = r_drives + r_feedback."""
    return drive_reward(before, after, weights, k, xi) + feedback_reward(feedback, f)


def pseudo_drives(before: Sequence[float], serving: int, praise_change: float) -> list[float]:
    """Approximation 1 of Section 3.2.6: only the serving drive moves, as if praised; the rest stay."""
    out = list(before)
    out[serving] = clamp(out[serving] + praise_change)
    return out

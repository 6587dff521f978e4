"""Across-seed summaries: mean and a Student-t 95% interval."""

from __future__ import annotations

import math
from typing import Sequence

from homeo_decision.numeric import left_sum
from homeo_msgs_py.schemas import finite

# two-sided 95% Student-t quantiles t_{0.975, df} for df = 1..30; beyond that 1.96 is close enough
_T975 = [12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160, 2.145, 2.131,
         2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056, 2.052, 2.048, 2.045, 2.042]


def t975(df: int) -> float:
    if df < 1:
        return float("nan")
    if df <= len(_T975):
        return _T975[df - 1]
    return 1.96 + 2.4 / df  # within 0.5% of the exact quantile for df > 30


def describe(values: Sequence[float]) -> dict:
    """``{"mean", "ci95": [lo, hi], "per_seed"}``; one value gives a zero-width interval."""
    xs = [math.nan if v is None else float(v) for v in values]  # null: a metric of no samples (JSON has no NaN)
    n = len(xs)
    if n == 0:
        raise ValueError("no values to describe")
    mean = left_sum(xs) / n
    if n > 1:
        sd = math.sqrt(left_sum((x - mean) ** 2 for x in xs) / (n - 1))
        h = t975(n - 1) * sd / math.sqrt(n)
    else:
        h = 0.0
    return {"mean": mean, "ci95": [mean - h, mean + h], "per_seed": xs}


def aggregate(per_seed: Sequence[dict], drive_names: Sequence[str]) -> dict:
    """Combine per-seed metric summaries into the JSON layout of ``homeo-sim run --json``."""
    keys = list(drive_names) + ["all"]
    return {
        "HSR": describe([m["HSR"] for m in per_seed]),
        "RSR": describe([m["RSR"] for m in per_seed]),
        "CDA": {k: describe([m["CDA"][k] for m in per_seed]) for k in keys},
        "CEDA": {k: describe([m["CEDA"][k] for m in per_seed]) for k in keys},
    }


# NaN/inf (e.g. HSR of a run in which nobody wanted anything) become null: strict JSON, as the
# graph's messages do
json_safe = finite

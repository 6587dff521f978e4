"""Section 4.1 metrics (Eq 4.1-4.7) on hand-made arrays, and the across-seed statistics."""

from __future__ import annotations

import math

import numpy as np
import pytest

from homeo_sim.metrics import MetricRecorder, cumulative_series, summarize
from homeo_sim.stats import aggregate, describe, t975

NAMES = ["NAch", "NSoc", "NRes", "NEng"]
THR = [0, 70, 50, 50]

# three iterations, drives after each
D = np.array([
    [10.0, 80.0, 40.0, 90.0],  # NEng = 90: insecure (secure needs < 90)
    [0.0, 60.0, 55.0, 89.0],   # all < 90: secure
    [5.0, 70.0, 95.0, 20.0],   # NRes 95: insecure
])
EXPRESSED = np.array([True, False, True])
SATISFIED = np.array([True, False, False])


@pytest.fixture
def m():
    return summarize(D, EXPRESSED, SATISFIED, NAMES, THR)


def test_hsr_denominator_is_expressed_intentions(m):
    # Eq 4.1: 1 satisfied / 2 expressed = 0.5 (not 1/3 over iterations)
    assert m["HSR"] == 0.5
    assert m["intentions"] == 2


def test_cda_per_drive(m):
    # Eq 4.2: NAch (10+0+5)/3 = 5; NSoc (80+60+70)/3 = 70; NRes (40+55+95)/3 = 190/3; NEng (90+89+20)/3 = 199/3
    assert m["CDA"]["NAch"] == pytest.approx(5.0)
    assert m["CDA"]["NSoc"] == pytest.approx(70.0)
    assert m["CDA"]["NRes"] == pytest.approx(190 / 3)
    assert m["CDA"]["NEng"] == pytest.approx(199 / 3)


def test_cda_all(m):
    # Eq 4.3: (5 + 70 + 190/3 + 199/3) / 4 = 614/12
    assert m["CDA"]["all"] == pytest.approx(614 / 12)


def test_ceda_per_drive(m):
    # Eq 4.4: NAch (thr 0) = CDA = 5; NSoc max(d-70,0): 10+0+0 -> 10/3
    # NRes max(d-50,0): 0+5+45 -> 50/3; NEng: 40+39+0 -> 79/3
    assert m["CEDA"]["NAch"] == pytest.approx(5.0)
    assert m["CEDA"]["NSoc"] == pytest.approx(10 / 3)
    assert m["CEDA"]["NRes"] == pytest.approx(50 / 3)
    assert m["CEDA"]["NEng"] == pytest.approx(79 / 3)


def test_ceda_all(m):
    # Eq 4.5: (5 + 10/3 + 50/3 + 79/3) / 4 = (15 + 139) / 12 = 154/12
    assert m["CEDA"]["all"] == pytest.approx(154 / 12)


def test_rsr_drive_at_90_is_insecure(m):
    # Eq 4.6-4.7: only iteration 2 has every drive < 90 -> 1/3
    assert m["RSR"] == pytest.approx(1 / 3)


def test_rsr_all_secure_just_below_90():
    d = np.array([[89.99, 0, 0, 0], [0, 89.0, 89.0, 89.0]])
    out = summarize(d, np.array([False, False]), np.array([False, False]), NAMES, THR)
    assert out["RSR"] == 1.0


def test_hsr_without_intentions_is_nan():
    out = summarize(D, np.zeros(3, bool), np.zeros(3, bool), NAMES, THR)
    assert math.isnan(out["HSR"])


def test_empty_run_raises():
    with pytest.raises(ValueError):
        summarize(np.zeros((0, 4)), np.zeros(0, bool), np.zeros(0, bool), NAMES, THR)


def test_cumulative_series(m):
    s = cumulative_series(D, EXPRESSED, SATISFIED, NAMES, THR)
    # HSR after t=1: 1/1; t=2: no new intention, 1/1; t=3: 1/2
    assert list(s["HSR"]) == pytest.approx([1.0, 1.0, 0.5])
    # RSR: 0/1, 1/2, 1/3
    assert list(s["RSR"]) == pytest.approx([0.0, 0.5, 1 / 3])
    # CDA NAch: 10, (10+0)/2 = 5, 15/3 = 5
    assert list(s["CDA"]["NAch"]) == pytest.approx([10.0, 5.0, 5.0])
    # CEDA NEng: 40, 79/2, 79/3
    assert list(s["CEDA"]["NEng"]) == pytest.approx([40.0, 39.5, 79 / 3])
    # the last point is the summary
    assert s["CDA"]["all"][-1] == pytest.approx(m["CDA"]["all"])
    assert s["CEDA"]["all"][-1] == pytest.approx(m["CEDA"]["all"])


def test_cumulative_hsr_nan_before_first_intention():
    s = cumulative_series(D[:2], np.array([False, True]), np.array([False, True]), NAMES, THR)
    assert math.isnan(s["HSR"][0]) and s["HSR"][1] == 1.0


def test_recorder_matches_summarize(m):
    rec = MetricRecorder(NAMES, THR)
    for d, e, s in zip(D, EXPRESSED, SATISFIED):
        rec.record(list(d), bool(e), bool(s))
    assert rec.n == 3
    assert rec.summary() == m


# -- stats ------------------------------------------------------------------------------------

def test_describe_student_t_interval():
    # [1, 2, 3, 6]: mean 3; squared deviations 4 + 1 + 0 + 9 = 14; s = sqrt(14/3)
    # half width = t_{0.975,3} * s / sqrt(4) = 3.182 * sqrt(14/3) / 2 = 3.4369...
    out = describe([1, 2, 3, 6])
    h = 3.182 * math.sqrt(14 / 3) / 2
    assert out["mean"] == 3.0
    assert out["ci95"] == pytest.approx([3 - h, 3 + h])
    assert out["per_seed"] == [1.0, 2.0, 3.0, 6.0]


def test_describe_two_values():
    # [0.8, 0.9]: mean 0.85; s = sqrt(0.005) = 0.0707; h = 12.706 * 0.0707 / sqrt(2) = 0.6353
    out = describe([0.8, 0.9])
    h = 12.706 * math.sqrt(0.005) / math.sqrt(2)
    assert out["ci95"] == pytest.approx([0.85 - h, 0.85 + h])


def test_describe_one_value_zero_width():
    assert describe([4.0]) == {"mean": 4.0, "ci95": [4.0, 4.0], "per_seed": [4.0]}


@pytest.mark.parametrize("df, t", [(1, 12.706), (2, 4.303), (4, 2.776), (10, 2.228), (19, 2.093), (30, 2.042),
                                   (60, 2.000), (120, 1.980)])
def test_t975_against_textbook_table(df, t):
    assert t975(df) == pytest.approx(t, rel=5e-3)


def test_aggregate_layout():
    per_seed = [summarize(D, EXPRESSED, SATISFIED, NAMES, THR), summarize(D[:2], EXPRESSED[:2], SATISFIED[:2], NAMES, THR)]
    out = aggregate(per_seed, NAMES)
    assert set(out) == {"HSR", "RSR", "CDA", "CEDA"}
    assert set(out["CDA"]) == set(NAMES) | {"all"}
    # RSR per seed: 1/3 and 1/2
    assert out["RSR"]["per_seed"] == pytest.approx([1 / 3, 1 / 2])
    assert out["RSR"]["mean"] == pytest.approx(5 / 12)

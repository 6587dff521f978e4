"""Eq 3.2 (intensities), Eq 3.3 (dominant motivation), Table 3.2 (stimuli), Eq 3.27-3.28 (DoD weights)."""

from __future__ import annotations

import math

import pytest

from homeo_decision.agent import DecisionCore
from homeo_decision.motivation import clamp, dod_weights, dominant, intensities

THRESH = [0, 70, 50, 50]  # Table 3.1: NAch, NSoc, NRes, NEng


# -- Eq 3.2 ------------------------------------------------------------------

def test_intensity_below_threshold_is_zero_even_with_stimuli():
    # NSoc 69 < 70, NRes 49 < 50, NEng 10 < 50: all 0 whatever the stimuli add
    out = intensities([5, 69, 49, 10], THRESH, [0, 10, 10, 10])
    assert out[1:] == [0.0, 0.0, 0.0]


def test_intensity_at_threshold_is_drive_plus_stimuli():
    # d = at is not "d < at": NSoc 70 + 10 = 80, NRes 50 + 10 = 60, NEng 50 + 0 = 50
    out = intensities([0, 70, 50, 50], THRESH, [0, 10, 10, 0])
    assert out[1:] == [80.0, 60.0, 50.0]


def test_intensity_nach_threshold_zero_active_at_zero():
    # NAch threshold 0: d = 0 is active; intention recognised -> 0 + 20 = 20
    assert intensities([0, 0, 0, 0], THRESH, [20, 0, 0, 0])[0] == 20.0


def test_intensity_sums_several_stimuli():
    # NEng 60 with two stimuli summing to 10 + 5 = 15 -> 75
    assert intensities([0, 0, 0, 60], THRESH, [0, 0, 0, 15])[3] == 75.0


# -- Eq 3.3 ------------------------------------------------------------------

def test_dominant_is_argmax():
    assert dominant([10.0, 0.0, 85.0, 60.0]) == 2


def test_dominant_tie_first():
    # NSoc and NRes tie at 80: "first" picks the earlier declared (index 1)
    assert dominant([5.0, 80.0, 80.0, 0.0], "first") == 1


def test_dominant_tie_last():
    assert dominant([5.0, 80.0, 80.0, 0.0], "last") == 2


def test_dominant_tie_last_but_not_lower_later_value():
    # a later *smaller* value must not win under "last"
    assert dominant([5.0, 80.0, 80.0, 79.0], "last") == 2


# -- Table 3.2 stimuli through the compiled scenario -----------------------------

def test_stimuli_robot_near_human_with_intention(thesis, enc):
    # robot at H, human present with an intention: Serving +20, Social +10, no Relaxative, no Survival
    code = enc(thesis, "H", intention="light")
    assert thesis.c.stim[code] == (20.0, 10.0, 0.0, 0.0)


def test_stimuli_robot_at_rest_place_human_far(thesis, enc):
    # robot at R, human present (far), no intention: Social +10, Relaxative +10
    assert thesis.c.stim[enc(thesis, "R")] == (0.0, 10.0, 10.0, 0.0)


def test_stimuli_robot_at_charger_human_absent(thesis, enc):
    # robot at C, human absent: only Survival +10 (charger near)
    assert thesis.c.stim[enc(thesis, "C", presence="absent")] == (0.0, 0.0, 0.0, 10.0)


def test_perceive_gives_eq_3_2_and_3_3(thesis, enc):
    # robot at C, human far, intention 'music'; drives NAch 30, NSoc 75, NRes 40, NEng 62
    # Serving 30+20=50; Social 75+10=85; Relaxative 0 (40<50); Survival 62+10=72 -> Social dominant
    core = DecisionCore(thesis, seed=0)
    p = core.perceive([30, 75, 40, 62], enc(thesis, "C", intention="music"))
    assert p.intensities == [50.0, 85.0, 0.0, 72.0]
    assert p.m_dom == 1


# -- Eq 3.27-3.28 ------------------------------------------------------------

def test_dod_quarter_four_drives_all_one():
    # w_NAch = 0.25 * 4 = 1; others (4 - 1) / 3 = 1
    assert dod_weights(0.25, 4, 0) == [1.0, 1.0, 1.0, 1.0]


def test_dod_zero():
    # w_NAch = 0; others 4 / 3
    assert dod_weights(0.0, 4, 0) == pytest.approx([0.0, 4 / 3, 4 / 3, 4 / 3])


def test_dod_one():
    # w_NAch = 4; others (4 - 4) / 3 = 0
    assert dod_weights(1.0, 4, 0) == [4.0, 0.0, 0.0, 0.0]


def test_dod_weight_goes_to_serving_index():
    # serving drive declared third: DoD 0.5 -> w_s = 2, others 2/3
    assert dod_weights(0.5, 4, 2) == pytest.approx([2 / 3, 2 / 3, 2.0, 2 / 3])


@pytest.mark.parametrize("dod", [0.0, 0.1, 0.25, 0.6, 1.0])
def test_dod_weights_sum_to_number_of_drives(dod):
    w = dod_weights(dod, 4, 0)
    assert sum(w) == pytest.approx(4.0)
    assert w[0] / sum(w) == pytest.approx(dod)  # Eq 3.27


@pytest.mark.parametrize("dod", [-0.01, 1.01, 1.5, math.nan])
def test_dod_out_of_range_raises(dod):
    with pytest.raises(ValueError):
        dod_weights(dod, 4, 0)


def test_decision_core_rejects_bad_dod(thesis):
    with pytest.raises(ValueError):
        DecisionCore(thesis, dod=1.5)


def test_clamp_to_0_100():
    assert (clamp(-5.0), clamp(42.0), clamp(130.0)) == (0.0, 42.0, 100.0)

"""Reward, Eq 3.18-3.22, and the pseudo drives of a proposal (Section 3.2.6, approximation 1)."""

from __future__ import annotations

import pytest

from homeo_decision.agent import DecisionCore
from homeo_decision.reward import drive_reward, feedback_reward, pseudo_drives, reward

W1 = [1.0, 1.0, 1.0, 1.0]
NAch, NSoc, NRes, NEng = range(4)


def test_thesis_example_section_4_2_3_with_survival_dominant():
    # NEng 50 -> 30, Survival dominant, xi = 1: 20 (1 + 1) w = 40 w; with w = 1 -> 40
    before = [0, 0, 0, 50]
    after = [0, 0, 0, 30]
    assert drive_reward(before, after, W1, NEng, 1.0) == 40.0


def test_thesis_example_scales_with_weight():
    # the same with w_NEng = 4/3 (DoD 0): 40 * 4/3
    w = [0.0, 4 / 3, 4 / 3, 4 / 3]
    assert drive_reward([0, 0, 0, 50], [0, 0, 0, 30], w, NEng, 1.0) == pytest.approx(160 / 3)


def test_thesis_example_other_motivation_dominant_gets_no_bonus():
    # NEng 50 -> 30 while Social dominant: only 20 w = 20
    assert drive_reward([0, 0, 0, 50], [0, 0, 0, 30], W1, NSoc, 1.0) == 20.0


def test_xi_zero_is_eq_3_19():
    # xi = 0: sum w (before - after) = (10-13) + (70-40) + (20-22) + (50-30) = -3 + 30 - 2 + 20 = 45
    before = [10, 70, 20, 50]
    after = [13, 40, 22, 30]
    assert drive_reward(before, after, W1, NSoc, 0.0) == 45.0


def test_drive_reward_several_drives_with_bonus_and_weights():
    # w = [2, 2/3, 2/3, 2/3] (DoD 0.5), xi = 2, Serving dominant (k = 0)
    # NAch 30->20: (1+2)*2*10 = 60; NSoc 40->43: 2/3*(-3) = -2; NRes 60->40: 2/3*20 = 40/3; NEng unchanged: 0
    # total = 60 - 2 + 40/3 = 71.333...
    w = [2.0, 2 / 3, 2 / 3, 2 / 3]
    r = drive_reward([30, 40, 60, 50], [20, 43, 40, 50], w, NAch, 2.0)
    assert r == pytest.approx(60 - 2 + 40 / 3)


@pytest.mark.parametrize("fb, expected", [(1, 10.0), (-1, -10.0), (0, 0.0)])
def test_feedback_reward(fb, expected):
    # Eq 3.22 with f = 10
    assert feedback_reward(fb, 10.0) == expected


def test_total_reward_is_drives_plus_feedback():
    # Eq 3.18: NEng 50 -> 30 Survival dominant (40) + negative feedback (-10) = 30
    assert reward([0, 0, 0, 50], [0, 0, 0, 30], W1, NEng, 1.0, -1, 10.0) == 30.0


def test_pseudo_drives_only_serving_moves():
    # praise -10 on NAch 25 -> 15; the rest stay
    assert pseudo_drives([25, 70, 55, 80], NAch, -10.0) == [15.0, 70, 55, 80]


def test_pseudo_drives_clamped_at_zero():
    # NAch 4 - 10 = -6 -> 0
    assert pseudo_drives([4, 70, 55, 80], NAch, -10.0) == [0.0, 70, 55, 80]


def test_pseudo_drives_do_not_mutate_input():
    before = [25.0, 70.0, 55.0, 80.0]
    pseudo_drives(before, NAch, -10.0)
    assert before == [25.0, 70.0, 55.0, 80.0]


def test_learn_reports_eq_3_18_reward(thesis, enc):
    # DecisionCore.learn on the thesis scenario with DoD 0 (w = [0, 4/3, 4/3, 4/3]), xi 1, f 10.
    # s: robot at H, human near, intention 'light'; drives [20, 75, 30, 40]
    #   intensities: Serving 40, Social 85, Relaxative 0, Survival 0 -> Social dominant (k = 1)
    # action Chat, after [23, 48, 32, 42] (NSoc 75-30+3), feedback -1:
    #   NAch: 0; NSoc: 2 * 4/3 * 27 = 72; NRes: 4/3 * -2; NEng: 4/3 * -2 -> 72 - 16/3; feedback -10
    core = DecisionCore(thesis, seed=0, dod=0.0, pseudo_update=False)
    code = enc(thesis, "H", intention="light")
    p = core.perceive([20, 75, 30, 40], code)
    assert p.m_dom == 1
    after = (23.0, 48.0, 32.0, 42.0)
    p2 = core.perceive(after, code)
    out = core.learn(p, thesis.action_index("Chat"), after, -1, None, p2, 0)
    assert out.reward == pytest.approx(72 - 16 / 3 - 10)
    assert out.pseudo_reward is None

"""Object Q-learning on the two-object toy scenario: Eq 3.13-3.17 and the pseudo update, Eq 3.23.

Toy (conftest.py): objects ``box`` (at B, status off/on) and ``null``; actions
TurnOn (box, needs the box near), TurnOff (box), Wait, GoB, GoH (null).
"""

from __future__ import annotations

import copy
import math

import pytest

from homeo_decision.agent import DecisionCore
from homeo_decision.objectq import ObjectQ, phase_at, schedule_from
from homeo_decision.scenario import scenario_from_dict


def setq(q: ObjectQ, sc, name: str, states, value: float) -> None:
    a = sc.action_index(name)
    q.q[q.act_obj[a]][states[q.act_obj[a]]][q.act_local[a]] = value


def getq(q: ObjectQ, sc, name: str, states) -> float:
    return q.value(sc.action_index(name), states)


# -- state reduction (Eq 3.11-3.13) --------------------------------------------------

def test_table_shapes_toy(toy):
    # box: |M| 2 x |S_hum| (3 intentions x 3 relations = 9) x |S_box| (2 distances x 2 statuses = 4) = 72 rows of 2
    # null: 2 x 9 x 1 = 18 rows of 3 actions
    q = ObjectQ(toy)
    assert toy.object_names == ["box", "null"]
    assert (len(q.q[0]), len(q.q[0][0])) == (72, 2)
    assert (len(q.q[1]), len(q.q[1][0])) == (18, 3)


def test_table_shapes_thesis(thesis):
    # |M| = 4, |S_hum| = 7 x 3 = 21; charger 4 states, player 2, light 2, null 1
    q = ObjectQ(thesis)
    rows = [len(t) for t in q.q]
    cols = [len(t[0]) for t in q.q]
    assert rows == [4 * 21 * 4, 4 * 21 * 2, 4 * 21 * 2, 4 * 21 * 1]
    assert cols == [4, 2, 2, 4]


def test_initial_q_from_scenario(toy_raw):
    raw = toy_raw()
    raw["open"]["initial_q"] = 1.0
    q = ObjectQ(scenario_from_dict(raw))
    assert {v for t in q.q for row in t for v in row} == {1.0}


def test_states_differ_per_m_dom_and_object_state(toy, enc):
    q = ObjectQ(toy)
    a, b = enc(toy, "B", box="off"), enc(toy, "B", box="on")
    s0, s1 = q.states(0, a), q.states(1, a)
    assert s0[0] != s1[0] and s0[1] != s1[1]  # m_dom is part of every reduced state
    t = q.states(0, b)
    assert t[0] != s0[0] and t[1] == s0[1]  # the box status is in S_box only, not in S_null


# -- Eq 3.14-3.16 ----------------------------------------------------------------------

def test_update_with_collateral_term(toy, enc):
    q = ObjectQ(toy)
    A = enc(toy, "B", box="off")
    B = enc(toy, "B", box="on")
    s, s2 = q.states(0, A), q.states(1, B)
    for name, v in (("TurnOn", 2.0), ("TurnOff", -1.0), ("Wait", 0.5), ("GoB", 3.0), ("GoH", -2.0)):
        setq(q, toy, name, s, v)
    for name, v in (("TurnOn", 1.0), ("TurnOff", 4.0), ("Wait", 5.0), ("GoB", 1.0), ("GoH", 0.0)):
        setq(q, toy, name, s2, v)
    # V^box(s, s') = max Q^box(s') + [max Q^null(s') - max Q^null(s)] = 4 + (5 - 3) = 6
    # Q <- (1 - 0.5) * 2 + 0.5 * (6 + 0.5 * 6) = 1 + 4.5 = 5.5
    new = q.update(toy.action_index("TurnOn"), s, 6.0, s2, 0.5, 0.5, A, B)
    assert new == pytest.approx(5.5)
    assert getq(q, toy, "TurnOn", s) == pytest.approx(5.5)


def test_update_changes_only_the_updated_entry(toy, enc):
    q = ObjectQ(toy)
    A, B = enc(toy, "B", box="off"), enc(toy, "B", box="on")
    s, s2 = q.states(0, A), q.states(1, B)
    setq(q, toy, "GoB", s2, 3.0)
    before = copy.deepcopy(q.q)
    q.update(toy.action_index("TurnOn"), s, 6.0, s2, 0.5, 0.5, A, B)
    o, j = q.act_obj[0], q.act_local[0]
    before[o][s[o]][j] = q.q[o][s[o]][j]
    assert q.q == before


def test_update_no_collateral_when_other_state_unchanged(toy, enc):
    # same m_dom and human: the null state is the same in s and s', so dQmax^null = 0
    q = ObjectQ(toy)
    A, B = enc(toy, "B", box="off"), enc(toy, "B", box="on")
    s, s2 = q.states(0, A), q.states(0, B)
    assert s[1] == s2[1]
    setq(q, toy, "TurnOn", s, 2.0)
    setq(q, toy, "TurnOff", s2, 4.0)
    setq(q, toy, "GoB", s, 3.0)
    # Q <- 0.5 * 2 + 0.5 * (6 + 0.5 * 4) = 1 + 4 = 5
    assert q.update(toy.action_index("TurnOn"), s, 6.0, s2, 0.5, 0.5, A, B) == pytest.approx(5.0)


def test_update_null_action_with_negative_collateral(toy, enc):
    # Wait (null): only m_dom changes, 0 -> 1
    # V^null = max Q^null(s') = 7 + [max Q^box(s') = 0.5 - max Q^box(s) = 2] = 5.5
    # Q <- 0.7 * 0.5 + 0.3 * (-4 + 0.5 * 5.5) = 0.35 + 0.3 * (-1.25) = -0.025
    q = ObjectQ(toy)
    A = enc(toy, "B", box="off")
    s, s2 = q.states(0, A), q.states(1, A)
    setq(q, toy, "Wait", s, 0.5)
    setq(q, toy, "TurnOn", s, 2.0)
    setq(q, toy, "TurnOff", s, -1.0)
    setq(q, toy, "GoH", s2, 7.0)
    setq(q, toy, "TurnOn", s2, 0.5)
    setq(q, toy, "TurnOff", s2, 0.0)
    assert q.update(toy.action_index("Wait"), s, -4.0, s2, 0.3, 0.5, A, A) == pytest.approx(-0.025)


def test_value_max_over_all_actions_of_the_object(toy, enc):
    # Eq 3.15 takes max over A_o: with the robot at H, TurnOn (invalid there) still counts
    # V = max Q^box(s') = 100 + [max Q^null(s') = 2 - max Q^null(s) = 0] = 102
    # Q <- 0.5 * 0 + 0.5 * (0 + 0.5 * 102) = 25.5
    q = ObjectQ(toy)
    A, H = enc(toy, "B"), enc(toy, "H")
    s, s2 = q.states(0, A), q.states(0, H)
    setq(q, toy, "TurnOn", s2, 100.0)
    setq(q, toy, "TurnOff", s2, 1.0)
    setq(q, toy, "GoB", s2, 2.0)
    assert q.update(toy.action_index("TurnOff"), s, 0.0, s2, 0.5, 0.5, A, H) == pytest.approx(25.5)


def test_value_max_over_valid_open_choice(toy_raw, enc):
    # open.value_max_over = "valid": at H only TurnOff is valid for the box -> max = 1
    # V = 1 + [max Q^null(s') = 2 - max Q^null(s) = 0] = 3; Q <- 0.5 * 0 + 0.5 * (0 + 0.5 * 3) = 0.75
    raw = toy_raw()
    raw["open"]["value_max_over"] = "valid"
    sc = scenario_from_dict(raw)
    q = ObjectQ(sc)
    A, H = enc(sc, "B"), enc(sc, "H")
    s, s2 = q.states(0, A), q.states(0, H)
    setq(q, sc, "TurnOn", s2, 100.0)
    setq(q, sc, "TurnOff", s2, 1.0)
    setq(q, sc, "GoB", s2, 2.0)
    assert q.update(sc.action_index("TurnOff"), s, 0.0, s2, 0.5, 0.5, A, H) == pytest.approx(0.75)


# -- Eq 3.17 --------------------------------------------------------------------------------

@pytest.fixture
def soft(toy, enc):
    """Robot at H (box far): valid = TurnOff, Wait, GoB, GoH; Q/tau = 0, ln 2, ln 3, 0 with tau 2."""
    q = ObjectQ(toy)
    H = enc(toy, "H")
    s = q.states(0, H)
    setq(q, toy, "TurnOn", s, 100.0)  # invalid here: would dominate if it leaked in
    setq(q, toy, "TurnOff", s, 0.0)
    setq(q, toy, "Wait", s, 2 * math.log(2))
    setq(q, toy, "GoB", s, 2 * math.log(3))
    setq(q, toy, "GoH", s, 0.0)
    return q, s, toy.c.valid[H]


def test_valid_actions_exclude_turnon_when_box_far(toy, soft):
    _, _, valid = soft
    assert [toy.action_names[a] for a in valid] == ["TurnOff", "Wait", "GoB", "GoH"]


def test_softmax_probabilities(soft):
    # exp(Q / 2) = 1, 2, 3, 1 -> sum 7
    q, s, valid = soft
    assert q.probabilities(s, valid, 2.0) == pytest.approx([1 / 7, 2 / 7, 3 / 7, 1 / 7])


def test_softmax_temperature(soft):
    # tau = 1: exp(Q) = 1, 4, 9, 1 -> sum 15
    q, s, valid = soft
    assert q.probabilities(s, valid, 1.0) == pytest.approx([1 / 15, 4 / 15, 9 / 15, 1 / 15])


def test_softmax_uses_each_objects_own_state(toy, enc):
    # Q^box at state s[0] and Q^null at s[1]; values written under another m_dom do not count
    q = ObjectQ(toy)
    B = enc(toy, "B")
    s, other = q.states(0, B), q.states(1, B)
    setq(q, toy, "TurnOn", s, 2 * math.log(4))  # exp(Q/2) = 4
    setq(q, toy, "Wait", other, 50.0)  # another reduced state: ignored
    p = q.probabilities(s, toy.c.valid[B], 2.0)
    # all 5 valid at B: 4, 1, 1, 1, 1 -> sum 8
    assert p == pytest.approx([4 / 8, 1 / 8, 1 / 8, 1 / 8, 1 / 8])


@pytest.mark.parametrize("u, name", [(0.0, "TurnOff"), (0.14, "TurnOff"), (0.15, "Wait"), (0.42, "Wait"),
                                     (0.43, "GoB"), (0.85, "GoB"), (0.86, "GoH"), (0.999, "GoH")])
def test_select_cumulative(toy, soft, u, name):
    # cumulative: TurnOff < 1/7 = .1429 <= Wait < 3/7 = .4286 <= GoB < 6/7 = .8571 <= GoH
    q, s, valid = soft
    assert toy.action_names[q.select(s, valid, 2.0, u)] == name


def test_select_never_invalid(toy, soft):
    q, s, valid = soft
    picked = {q.select(s, valid, 2.0, i / 1000) for i in range(1000)}
    assert picked == set(valid)


# -- the alpha / tau schedule (Section 4.2.1) ---------------------------------------------

def test_schedule_thesis(thesis):
    sch = schedule_from(thesis.learning)
    assert (phase_at(sch, 0).alpha, phase_at(sch, 0).tau) == (0.3, 4.0)
    assert (phase_at(sch, 999).alpha, phase_at(sch, 999).tau) == (0.3, 4.0)
    assert (phase_at(sch, 1000).alpha, phase_at(sch, 1000).tau) == (0.1, 2.0)


# -- Eq 3.23 through DecisionCore.learn -------------------------------------------------------

@pytest.fixture
def pseudo_case(toy, enc):
    """Intention 'on', robot at B (human far); drives NAch 45, NEng 58.

    Intensities: Serving 45 + 20 = 65, Survival 58 -> m_dom = Serving (0).
    Pseudo drives (praise -10): NAch 35 -> Serving 55 < Survival 58 -> m_dag = Survival (1).
    """
    core = DecisionCore(toy, seed=0)
    X = enc(toy, "B", intention="on")
    p = core.perceive([45, 58], X)
    assert p.m_dom == 0
    s, s_dag = p.states, core.q.states(1, X)
    q = core.q
    setq(q, toy, "GoH", s, 2.0)  # max Q^null(s) = 2
    setq(q, toy, "TurnOn", s, 1.0)
    setq(q, toy, "TurnOn", s_dag, 3.0)  # max Q^box(s+) = 3
    setq(q, toy, "GoH", s_dag, 6.0)  # max Q^null(s+) = 6
    after = (48.0, 60.0)  # time growth: NAch +3, NEng +2
    p_next = core.perceive(after, X)  # Serving 68 > Survival 60: same reduced states as s
    assert p_next.states == s
    return core, p, after, p_next, s


def test_pseudo_update_moves_proposed_action(toy, pseudo_case):
    core, p, after, p_next, s = pseudo_case
    out = core.learn(p, toy.action_index("Wait"), after, -1, toy.action_index("TurnOn"), p_next, 0)
    # executed Wait: r = 2*(45-48) + (58-60) - 10 = -18; V = max Q^null(s) = 2; Q = 0.5*0 + 0.5*(-18 + 1) = -8.5
    assert out.reward == pytest.approx(-18.0)
    assert getq(core.q, toy, "Wait", s) == pytest.approx(-8.5)
    # pseudo: r+ = (1+1)*1*(45-35) = 20, + f = 30
    # V^box(s, s+) = max Q^box(s+) + [max Q^null(s+) - max Q^null(s)] = 3 + (6 - 2) = 7
    # Q(s, TurnOn) = 0.5 * 1 + 0.5 * (30 + 0.5 * 7) = 0.5 + 16.75 = 17.25
    assert out.pseudo_reward == pytest.approx(30.0)
    assert getq(core.q, toy, "TurnOn", s) == pytest.approx(17.25)


def test_no_pseudo_update_without_proposal(toy, pseudo_case):
    core, p, after, p_next, s = pseudo_case
    out = core.learn(p, toy.action_index("Wait"), after, -1, None, p_next, 0)
    assert out.pseudo_reward is None
    assert getq(core.q, toy, "TurnOn", s) == 1.0


def test_no_pseudo_update_when_switched_off(toy, pseudo_case):
    core, p, after, p_next, s = pseudo_case
    core.set_params(pseudo_update=False)
    core.learn(p, toy.action_index("Wait"), after, -1, toy.action_index("TurnOn"), p_next, 0)
    assert getq(core.q, toy, "TurnOn", s) == 1.0

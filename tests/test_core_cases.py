"""Small cases of the core computed by hand, written for the mutants ``make mutation`` found alive
(tools/mutation.py): each assertion fails under one of them (a boundary moved, a term dropped, a check skipped)."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from homeo_sim.metrics import (AccuracyEnds, MetricRecorder, accuracy_curve, accuracy_ends, cumulative_series,
                               summarize)

def refused(message: str):
    """The whole one-line message: a part of it would let a message with anything added pass."""
    return pytest.raises(ValueError, match=f"^{re.escape(message)}$")


# -- metrics (Section 4.1) ---------------------------------------------------------------------------
# three ticks, two drives with thresholds 0 and 50
DRIVES = np.array([[10.0, 60.0], [20.0, 95.0], [0.0, 40.0]])
EXPRESSED = np.array([True, False, True])
SATISFIED = np.array([True, False, False])
NAMES, THR = ["A", "B"], [0.0, 50.0]


def test_cumulative_series_by_hand():
    s = cumulative_series(DRIVES, EXPRESSED, SATISFIED, NAMES, THR)
    # Eq 4.2 after 1, 2, 3 ticks: A 10, 15, 10; B 60, 77.5, 65; all their mean (Eq 4.3)
    assert s["CDA"]["A"].tolist() == [10.0, 15.0, 10.0] and s["CDA"]["B"].tolist() == [60.0, 77.5, 65.0]
    assert s["CDA"]["all"].tolist() == [35.0, 46.25, 37.5]
    # Eq 4.4: excess over the threshold, A 10 20 0, B 10 45 0 (40 < 50 counts 0, not -10)
    assert s["CEDA"]["A"].tolist() == [10.0, 15.0, 10.0]
    assert s["CEDA"]["B"].tolist() == pytest.approx([10.0, 27.5, 55.0 / 3])
    assert s["CEDA"]["all"].tolist() == pytest.approx([10.0, 21.25, (10.0 + 55.0 / 3) / 2])
    # Eq 4.1 over the ticks with an intention: 1/1, 1/1, 1/2; Eq 4.6-4.7: tick 2 insecure (95 >= 90)
    assert s["HSR"].tolist() == [1.0, 1.0, 0.5]
    assert s["RSR"].tolist() == pytest.approx([1.0, 0.5, 2.0 / 3])
    assert s["drives"]["B"].tolist() == [60.0, 95.0, 40.0]
    assert s["expressed"] is EXPRESSED and s["satisfied"] is SATISFIED
    later = cumulative_series(DRIVES, ~EXPRESSED, SATISFIED & False, NAMES, THR)  # no intention until tick 2
    assert math.isnan(later["HSR"][0]) and later["HSR"][1:].tolist() == [0.0, 0.0]


def _flat(d: dict) -> dict:
    return {f"{k}.{j}": w for k, v in d.items() for j, w in (v.items() if isinstance(v, dict) else [("", v)])}


def test_summary_by_hand_and_the_recorder_agrees():
    want = {"HSR": 0.5, "RSR": 2.0 / 3, "CDA": {"A": 10.0, "B": 65.0, "all": 37.5},
            "CEDA": {"A": 10.0, "B": 55.0 / 3, "all": (10.0 + 55.0 / 3) / 2}, "intentions": 2}
    assert _flat(summarize(DRIVES, EXPRESSED, SATISFIED, NAMES, THR)) == pytest.approx(_flat(want))
    rec = MetricRecorder(NAMES, THR, keep=True)
    for d, e, s in zip(DRIVES.tolist(), EXPRESSED, SATISFIED):
        rec.record(d, e, s)
    assert rec.n == 3 and _flat(rec.summary()) == pytest.approx(_flat(want))
    d, e, s = rec.arrays()
    assert d.tolist() == DRIVES.tolist() and e.tolist() == EXPRESSED.tolist() and s.tolist() == SATISFIED.tolist()
    assert rec.series()["CDA"]["all"].tolist() == [35.0, 46.25, 37.5]
    assert rec.series()["CEDA"]["B"].tolist() == pytest.approx([10.0, 27.5, 55.0 / 3])  # its thresholds


def test_the_boundaries_of_secure_and_of_excess():
    rec = MetricRecorder(NAMES, THR)
    rec.record([90.0, 50.0], False, False)  # 90 is not secure (Eq 4.7: every drive < 90); 50 is no excess
    rec.record([89.5, 49.0], True, True)
    out = rec.summary()
    assert out["RSR"] == 0.5 and out["CEDA"]["B"] == 0.0 and out["CEDA"]["A"] == pytest.approx(89.75)
    assert out["HSR"] == 1.0 and out["intentions"] == 1
    assert math.isnan(summarize(DRIVES[:1], np.array([False]), np.array([False]), NAMES, THR)["HSR"])
    empty = MetricRecorder(NAMES, THR)
    with refused("no iterations recorded"):
        empty.summary()
    with refused("no iterations recorded"):
        summarize(DRIVES[:0], EXPRESSED[:0], SATISFIED[:0], NAMES, THR)
    with refused("this recorder keeps no per-tick history (MetricRecorder(keep=True))"):
        empty.arrays()
    rec = MetricRecorder(NAMES, THR, keep=True)
    rec.record([50, 50], 0, 0)  # integers, as a caller may give them: the arrays are numbers and truths
    rec.record([50.5, 49.0], 1, 1)  # 0.5 above the threshold counts 0.5 (Eq 4.4)
    d, e, s = rec.arrays()
    assert (d.dtype, e.dtype, s.dtype) == (np.float64, np.bool_, np.bool_) and d.shape == (2, 2)
    assert rec.summary()["CEDA"]["A"] == 50.25 and rec.summary()["CEDA"]["B"] == 0.0
    silent = MetricRecorder(NAMES, THR)
    silent.record([1.0, 1.0], False, False)
    assert math.isnan(silent.summary()["HSR"]) and silent.summary()["RSR"] == 1.0  # no intention: HSR undefined


GOOD = {"n": 3, "intentions": 2, "satisfied": 1, "secure": 2, "sum": [30.0, 195.0], "excess": [30.0, 55.0]}


COUNTS, SUMS = "metric counts must be integers >= 0", "metric sum must be 2 finite numbers >= 0"


@pytest.mark.parametrize("bad,words", [
    ("x", "not a metrics state"),
    (dict(GOOD, n=-1), COUNTS), (dict(GOOD, n=3.0), COUNTS), (dict(GOOD, secure=True), COUNTS),
    (dict(GOOD, intentions=4), "inconsistent metric counts [3, 4, 1, 2]"),
    (dict(GOOD, satisfied=3), "inconsistent metric counts [3, 2, 3, 2]"),
    (dict(GOOD, secure=4), "inconsistent metric counts [3, 2, 1, 4]"),
    (dict(GOOD, sum=[1.0]), SUMS), (dict(GOOD, sum=[1.0, -1.0]), SUMS), (dict(GOOD, sum=[1.0, float("nan")]), SUMS),
    (dict(GOOD, sum=[1.0, "2"]), SUMS), (dict(GOOD, excess=None), "metric excess must be 2 finite numbers >= 0"),
    (dict(GOOD, excess=[0.0, float("inf")]), "metric excess must be 2 finite numbers >= 0"),
])
def test_a_metrics_state_is_refused_whole(bad, words):
    rec = MetricRecorder(NAMES, THR)
    rec.record([1.0, 2.0], True, False)
    before = rec.state()
    with refused(words):
        rec.set_state(bad)
    assert rec.state() == before  # nothing changed


def test_a_metrics_state_at_its_bounds_is_taken():
    rec = MetricRecorder(NAMES, THR)
    zero = {"n": 0, "intentions": 0, "satisfied": 0, "secure": 0, "sum": [0.0, 0], "excess": [0, 0.0]}
    rec.set_state(zero)  # nothing recorded yet: zeros, integer or not
    assert rec.state() == dict(zero, sum=[0.0, 0.0], excess=[0.0, 0.0]) and rec.n == 0
    full = {"n": 2, "intentions": 2, "satisfied": 2, "secure": 2, "sum": [0.5, 3], "excess": [0.5, 0.25]}
    rec.set_state(full)  # every tick with an intention, each satisfied, each secure
    assert rec.summary()["HSR"] == 1.0 and rec.summary()["RSR"] == 1.0 and rec.summary()["CDA"]["A"] == 0.25


def test_a_metrics_state_goes_on_as_the_uninterrupted_run():
    whole, first = MetricRecorder(NAMES, THR), MetricRecorder(NAMES, THR)
    for d, e, s in zip(DRIVES.tolist()[:2], EXPRESSED, SATISFIED):
        whole.record(d, e, s)
        first.record(d, e, s)
    st = first.state()
    assert st == {"n": 2, "intentions": 1, "satisfied": 1, "secure": 1, "sum": [30.0, 155.0], "excess": [30.0, 55.0]}
    later = MetricRecorder(NAMES, THR)
    later.set_state(st)
    for rec in (whole, later):
        rec.record(DRIVES[2].tolist(), True, False)
    assert later.state() == whole.state() == GOOD
    assert later.summary() == whole.summary()
    with refused("a recorder that keeps every tick cannot take a running-sums state"):
        MetricRecorder(NAMES, THR, keep=True).set_state(GOOD)


def test_the_recorder_follows_the_robot_tick_by_tick(thesis):
    """``follow`` and ``on_tick`` as the runner uses them: d(t) after each tick, the human's truth from the outcome."""
    from homeo_decision.agent import DecisionCore
    from homeo_decision.robot import OracleRecognition, Robot, run_loop
    from homeo_sim.environment import SimEnvironment

    robot = Robot(thesis, DecisionCore(thesis, 2), OracleRecognition(thesis))
    rec = MetricRecorder(thesis.drive_names, [d.threshold for d in thesis.drives], keep=True).follow(robot.perception)
    seen = []

    def hook(t, p, r, a, out):
        rec.on_tick(t, p, r, a, out)
        seen.append((list(robot.perception.drives), out.true_intention != 0, out.satisfied))

    run_loop(SimEnvironment(thesis, 2), robot, 200, on_tick=hook)
    d, e, s = rec.arrays()
    assert d.tolist() == [x[0] for x in seen] and e.tolist() == [x[1] for x in seen] and s.tolist() == [x[2] for x in seen]
    assert 0 < e.sum() < 200 and 0 < s.sum() < e.sum()  # both kinds of tick, both kinds of answer


def test_accuracy_at_both_ends_and_per_window():
    hits = [True, False, True, True, False]
    assert accuracy_ends(hits, 2) == {"first_2": 0.5, "last_2": 0.5}
    assert accuracy_ends(hits[:4], 2) == {"first_2": 0.5, "last_2": 1.0}
    assert accuracy_ends(hits, 10) == {"first_10": 0.6, "last_10": 0.6}  # a shorter run: the whole of it
    assert accuracy_ends(hits) == {"first_500": 0.6, "last_500": 0.6}  # the window of docs/INTENTION.md: 500
    with refused("no iterations recorded"):
        accuracy_ends([])
    assert accuracy_curve(hits, 2) == [0.5, 1.0]  # the fifth tick's window of one is dropped
    assert accuracy_curve(hits, 5) == [0.6] and accuracy_curve(hits, 6) == []
    assert accuracy_curve(hits * 50) == [0.6]  # 250 ticks a window by default
    ends = AccuracyEnds(2)
    with refused("no iterations recorded"):
        ends.ends()
    ends.append(True)
    assert len(ends) == 1 and ends.ends() == {"first_2": 1.0, "last_2": 1.0}
    for h in (False, False):
        ends.append(h)
    assert len(ends) == 2 and ends.ends() == {"first_2": 0.5, "last_2": 0.0}
    assert ends.state() == {"window": 2, "first": "10", "last": "00"}
    again = AccuracyEnds(2)
    again.set_state(ends.state())
    again.append(True)
    assert again.state() == {"window": 2, "first": "10", "last": "01"} and again.ends() == {"first_2": 0.5, "last_2": 0.5}
    again.set_state({"window": 2, "first": "1", "last": "11"})
    assert again.ends() == {"first_2": 1.0, "last_2": 1.0}


HITS = "accuracy hits must be strings of 0 and 1, at most 2 long"


@pytest.mark.parametrize("bad,words", [
    ([], "not an accuracy state of window 2"), ({"window": 3, "first": "", "last": ""}, "not an accuracy state of window 2"),
    ({"window": 2, "first": 1, "last": "1"}, HITS), ({"window": 2, "first": "1", "last": "012"}, HITS),
    ({"window": 2, "first": "1", "last": "1x"}, HITS), ({"window": 2, "first": "X", "last": "1X"}, HITS),
    ({"window": 2, "first": "11", "last": "1"}, "accuracy hits: fewer last than first"),
])
def test_an_accuracy_state_is_refused_whole(bad, words):
    ends = AccuracyEnds(2)
    ends.append(True)
    with refused(words):
        ends.set_state(bad)
    assert ends.state() == {"window": 2, "first": "1", "last": "1"}


# -- the decision core (Algorithm 1's parameters, Table 4.4's schedule) ---------------------------------
def test_the_schedule_goes_on_from_the_tick_offset(thesis):
    from homeo_decision.agent import DecisionCore

    core = DecisionCore(thesis, 0)
    first, later = core.schedule  # Table 4.4: alpha 0.3, tau 4 for the first 1000 iterations, then 0.1 and 2
    assert (first.start, first.alpha, first.tau, later.start, later.alpha, later.tau) == (0, 0.3, 4.0, 1000, 0.1, 2.0)
    assert core.phase(5) is first and core.phase(999) is first and core.phase(1000) is later
    core.set_tick_offset(995)  # a robot that had learned 995 ticks: its tick 5 is the schedule's 1000
    assert core.tick_offset == 995 and core.phase(4) is first and core.phase(5) is later
    core.set_tick_offset(0)  # the phase cached for tick 5 was the later one: forgotten
    assert core.tick_offset == 0 and core.phase(0) is first and core.phase(1) is first and core.phase(5) is first
    with pytest.raises(ValueError, match="tick offset must be >= 0, got -1"):
        core.set_tick_offset(-1)
    assert core.tick_offset == 0


def test_the_parameters_in_force_by_name(thesis):
    from homeo_decision.agent import DecisionCore

    core = DecisionCore(thesis, 0, dod=0.4, xi=2.0)
    # the scenario's gamma 0.5 (Table 4.4) and the two switches on; dod and xi as given
    assert list(core.params().items()) == [("dod", 0.4), ("xi", 2.0), ("gamma", 0.5), ("feedback", True),
                                           ("pseudo_update", True)]


def test_reset_forgets_the_table_and_starts_the_stream_again(thesis):
    from homeo_decision.agent import DecisionCore
    from homeo_decision.rng import UniformStream

    core = DecisionCore(thesis, 3)
    drawn = [core.rng.random() for _ in range(3)]
    assert drawn[0] == UniformStream(3, "decision").random()  # the stream of the seed, named for its component
    core.q.q[0][0][0] = 99.0
    core.reset()
    assert core.q.q[0][0][0] == thesis.open.initial_q and core.seed == 3
    assert [core.rng.random() for _ in range(3)] == drawn
    core.reset(7)
    seven = UniformStream(7, "decision")
    assert core.seed == 7 and [core.rng.random() for _ in range(3)] == [seven.random() for _ in range(3)]


# -- the simulated human's checkpoint (homeo_sim.human) -----------------------------------------------------
def _human(thesis, seed=5, ticks=7):
    from homeo_sim.human import SimHuman

    h = SimHuman(thesis, seed)
    for t in range(ticks):
        h.advance(0)
        h.respond(t % 5)
        h.observe()
    return h


def test_a_human_state_goes_on_with_the_same_draws(thesis):
    from homeo_sim.human import SimHuman

    h = _human(thesis)
    st = h.state()
    assert set(st) == {"seed", "intention", "present", "satisfied", "rng", "obs_rng"} and st["seed"] == 5
    other = SimHuman(thesis, 0)
    other.set_state(st)
    assert other.state() == st
    for t in range(20):
        for x in (h, other):
            x.advance(0)
        assert (h.intention, h.present) == (other.intention, other.present)
        assert h.respond(t % 5) == other.respond(t % 5) and h.observe() == other.observe()
    h.reset()  # the same seed, a fresh start (Algorithm 2 line 1: no intention)
    assert (h.seed, h.intention, h.present, h.satisfied) == (5, 0, True, False)
    assert h.state()["rng"] == SimHuman(thesis, 5).state()["rng"]
    h.reset(9)
    assert h.seed == 9 and h.state()["obs_rng"] == SimHuman(thesis, 9).state()["obs_rng"]


SEED, IT, BOOLS = ("human seed must be an integer in 0..2^31-1, got {}",
                    "human intention must be an index of the scenario's intentions, got {}",
                    "human present and satisfied must be true or false")


@pytest.mark.parametrize("change,words", [
    (None, "not a human state"),
    ({"seed": -1}, SEED.format(-1)), ({"seed": 2**31}, SEED.format(2**31)), ({"seed": True}, SEED.format(True)),
    ({"seed": 5.0}, SEED.format(5.0)), ({"intention": -1}, IT.format(-1)), ({"intention": 7}, IT.format(7)),
    ({"intention": False}, IT.format(False)), ({"present": 1}, BOOLS), ({"satisfied": "no"}, BOOLS),
    ({"rng": None}, "human stream: not a random-stream state"),
    ({"rng": {"block": 0, "drawn": 1.0}}, "human stream: not a random-stream state"),
    ({"obs_rng": {"block": "0", "drawn": 0}}, "observation stream: not a random-stream state"),
    ({"rng": {"block": 0, "drawn": -1}}, "human stream: not a random-stream state (block 0, drawn -1)"),
])
def test_a_human_state_is_refused_whole(thesis, change, words):
    h = _human(thesis)
    before = h.state()
    with refused(words):
        h.set_state("x" if change is None else dict(before, **change))
    assert h.state() == before


def test_a_human_state_at_its_bounds_is_taken(thesis):
    h = _human(thesis)
    h.set_state(dict(h.state(), seed=0, intention=0))  # the lowest seed and no intention
    assert (h.seed, h.intention) == (0, 0)
    st = dict(h.state(), seed=2**31 - 1, intention=len(thesis.intention_names) - 1, present=False, satisfied=True)
    st["rng"] = dict(st["rng"])  # a stream state is the seed's: it goes on under the new seed's generator
    h.set_state(st)
    assert (h.seed, h.intention, h.present, h.satisfied) == (2**31 - 1, 6, False, True)


def test_the_human_reveals_by_its_scenario_s_rule(toy_raw):
    from homeo_decision.scenario import scenario_from_dict
    from homeo_sim.human import SimHuman

    raw = toy_raw()
    raw["open"]["intention_reveal"] = "feedback"
    sc = scenario_from_dict(raw)
    h = SimHuman(sc)
    assert h.seed == 0 and h.reveal == "feedback"  # the default seed; the open choice as the scenario says
    h.intention = sc.intention_names.index("on")
    assert h.respond(sc.action_index("TurnOn")).clarified == h.intention  # praise reveals the intention


def test_the_human_answers_as_algorithm_2_says(thesis):
    """Lines 8-19 with each reveal rule (the open choice intention_reveal) and a proposal always / never made."""
    from homeo_decision.environment import Outcome
    from homeo_sim.human import SimHuman

    h = SimHuman(thesis, 0)
    light, on, play = thesis.intention_names.index("light"), thesis.action_index("LightOn"), thesis.action_index("Play")
    assert h.respond(play) == Outcome(play, 0, None, None, None, 0, False)  # no intention: no answer
    h.intention, h.reveal = light, "feedback"
    assert h.respond(on) == Outcome(on, 1, None, light, None, light, True) and h.satisfied  # praise reveals it
    h.satisfied, h.reveal, h.p_propose = False, "proposal", 1.0
    assert h.respond(on) == Outcome(on, 1, None, None, None, light, True)  # praise alone does not
    assert h.respond(play) == Outcome(play, -1, on, light, None, light, False)  # a scolding with the proposal does
    h.reveal = "never"
    assert h.respond(play) == Outcome(play, -1, on, None, None, light, False)
    h.reveal, h.p_propose = "proposal", 0.0
    assert h.respond(play) == Outcome(play, -1, None, None, None, light, False)  # no proposal: nothing revealed


def test_the_proposal_names_the_rule_s_desired_action(thesis):
    from homeo_sim.human import SimHuman

    h = SimHuman(thesis, 0)
    leave, light = thesis.intention_names.index("leave"), thesis.intention_names.index("light")
    to_r, to_c = thesis.action_index("MoveToR"), thesis.action_index("MoveToC")
    h.p_propose = 1.0
    h.proposal_choice = "first"
    assert h.proposal(leave) == to_r and h.proposal(light) == thesis.action_index("LightOn")
    h.proposal_choice = "MoveToC"
    assert h.proposal(leave) == to_c
    h.proposal_choice = "Play"  # not one of leave's desired actions: the first
    assert h.proposal(leave) == to_r
    h.proposal_choice = "random"
    assert {h.proposal(leave) for _ in range(40)} == {to_r, to_c}
    h.p_propose = 0.0
    assert h.proposal(leave) is None


def test_the_human_is_observed_by_its_habits(thesis):
    """Each channel drawn from the intention's habit row (its inverse CDF), or uniformly with the channel's noise."""
    from homeo_sim.human import SimHuman

    h, n = SimHuman(thesis, 4), 4000
    spec = thesis.observations
    for name in ("light", "leave", "none"):
        h.intention = thesis.intention_names.index(name)
        draws = [h.observe() for _ in range(n)]
        for ch in ("gesture", "movement", "keyword"):
            row = spec.habits[ch][h.intention]
            got = [sum(d[ch] == sym for d in draws) / n for sym in spec.alphabets[ch]]
            assert got == pytest.approx(row, abs=0.03), (name, ch)
    assert h.observe(with_intention=True)["intention"] == "none"
    ch, symbols, _, cum = h._habits[0]  # the gesture channel, all noise now
    h._habits = ((ch, symbols, 1.0, cum), *h._habits[1:])
    gestures = [h.observe()["gesture"] for _ in range(n)]
    assert [gestures.count(s) / n for s in symbols] == pytest.approx([1 / len(symbols)] * len(symbols), abs=0.03)


def test_perception_breaks_a_tie_by_the_scenario_s_rule(toy_raw, enc):
    """Eq 3.3 with equal intensities: the open choice tie_break ('first' in the toy, 'last' declared)."""
    from homeo_decision.agent import DecisionCore
    from homeo_decision.scenario import scenario_from_dict

    for rule, m_dom in (("first", 0), ("last", 1)):
        raw = toy_raw()
        raw["open"]["tie_break"] = rule
        sc = scenario_from_dict(raw)
        core = DecisionCore(sc, 0)
        code = enc(sc, "H")  # no intention: no stimulus; NAch 60 (threshold 0) and NEng 60 (threshold 50)
        p = core.perceive([60.0, 60.0], code)
        assert (p.intensities, p.m_dom) == ([60.0, 60.0], m_dom), rule
        q = core.percept(code, (60.0, 60.0), [60.0, 60.0], m_dom)
        assert (q.intensities, q.m_dom, q.states) == (p.intensities, p.m_dom, p.states)
        from homeo_decision.baselines import FlatQ  # a baseline perceives through the shared Perceiving

        f = FlatQ(sc).percept(code, (60.0, 60.0), [60.0, 60.0], m_dom)
        assert (f.intensities, f.m_dom) == ([60.0, 60.0], m_dom)


def test_the_parameters_given_win_over_the_scenario_s(thesis):
    from homeo_decision.agent import DecisionCore

    core = DecisionCore(thesis, 0, gamma=0.9, pseudo_update=False, feedback=False, feedback_value=0.0)
    assert (core.gamma, core.pseudo_update, core.feedback, core.f) == (0.9, False, False, 0.0)  # f = 0 is allowed
    assert DecisionCore(thesis, 0).f == 10.0  # Table 4.4's f
    with refused("feedback value must be >= 0, got -1"):
        core.set_params(feedback_value=-1)
    assert core.f == 0.0


# -- drives (Tables 4.1-4.2, Definition 1: every drive in [0, 100]) ---------------------------------------------
def test_drives_are_clamped_at_both_ends_and_nowhere_else(toy_raw, enc):
    from homeo_decision.drives import DriveDynamics, DriveModel
    from homeo_decision.scenario import scenario_from_dict

    raw = toy_raw()
    raw["drives"][1]["rate"] = 0.5  # NEng (body) grows 0.5 a tick
    raw["actions"][3]["effects"] = [{"set": {"robot.location": "B"}, "drives": {"NEng": -0.5}}]  # GoB lowers it
    sc = scenario_from_dict(raw)
    body = DriveDynamics(sc, "body")
    go_b = sc.action_index("GoB")
    for start, after_time, after_action in ((99.75, 100.0, 99.5), (100.0, 100.0, 99.5), (0.25, 0.75, 0.25),
                                            (0.0, 0.5, 0.0), (99.6, 100.0, 99.5)):
        body.values[1] = start
        body.apply_time()
        assert body.values[1] == after_time, start  # 100.25 -> 100, nothing else moved
        body.values[1] = after_time
        body.apply_action(enc(sc, "H"), go_b)
        assert body.values[1] == after_action, start
    body.values[1] = 0.25
    body.apply_action(enc(sc, "H"), go_b)
    assert body.values[1] == 0.0  # -0.25 -> 0
    m = DriveModel(sc)
    assert m.values == [float(v) for v in sc.open.initial_drives]  # the body drive too, before any reading
    for given, kept in (([5.0, -3.0], 0.0), ([5.0, 0.5], 0.5), ([5.0, 100.5], 100.0), ([5.0, 99.5], 99.5), ([5.0, 100], 100.0)):
        m.set_body(given)
        assert m.values[1] == kept and m.values[0] == sc.open.initial_drives[0]  # the internal drive is its own


def test_feedback_moves_the_serving_drive_only_when_given(toy_raw):
    from homeo_decision.drives import DriveModel
    from homeo_decision.scenario import scenario_from_dict

    raw = toy_raw()
    raw["open"]["scold_drive_change"] = 5.0
    raw["open"]["initial_drives"] = {"NAch": 50.0, "NEng": 0.0}
    m = DriveModel(scenario_from_dict(raw))
    m.apply_feedback(0)
    assert m.values[0] == 50.0  # no answer: nothing
    m.apply_feedback(-1)
    assert m.values[0] == 55.0  # a scolding: the open choice's +5
    m.apply_feedback(1)
    assert m.values[0] == 45.0  # praise: -10 (Section 4.2.1)
    m.apply_time()  # the defaults: an intention expressed, not satisfied; serving_growth always: +3 and +2
    assert m.values == [48.0, 0.0]  # the body drive is the body's: it does not grow here


def test_a_drive_growing_always_is_never_still(toy_raw, enc):
    from homeo_decision.drives import DriveDynamics
    from homeo_decision.scenario import scenario_from_dict

    raw = toy_raw()
    raw["open"]["drive_growth"] = {"NEng": "always"}
    sc = scenario_from_dict(raw)
    assert DriveDynamics(sc, "body").still(enc(sc, "H"), sc.action_index("GoB")) == ()


# -- motivation (Eq 3.2-3.3, 3.27-3.28; Definition 1) ---------------------------------------------------------
def test_a_drive_at_its_threshold_is_activated():
    from homeo_decision.motivation import motivational_state

    # Eq 3.2: intensity 0 only when d < at; NAch 30 at its threshold 30 is activated: 30 + stimulus 5 = 35;
    # NEng 10 < 50 is not: 0
    assert motivational_state([30.0, 10.0], [30.0, 50.0], [5.0, 0.0]) == ([35.0, 0.0], 0)


def test_a_tie_goes_to_the_first_declared_by_default():
    from homeo_decision.motivation import dominant, motivational_state

    # Eq 3.3 with intensities 40 and 40 and no tie_break given: the first (index 0), not the last (1)
    assert dominant([40.0, 40.0]) == 0
    # both drives 40 over thresholds 0, no stimulus: intensities 40, 40; m_dom 0 by the default rule
    assert motivational_state([40.0, 40.0], [0.0, 0.0], [0.0, 0.0]) == ([40.0, 40.0], 0)


def test_the_none_state_is_taken_only_when_no_motivation_is_activated():
    from homeo_decision.motivation import motivational_state

    # open choice no_activated_motivation: any none_state >= 0 names the state of "none activated" (Definition 6).
    # Drives 10 and 20 under thresholds 50: intensities 0, 0; the none state given is 0, so m_dom is 0, where
    # Eq 3.3's argmax with ties to the last would give 1
    assert motivational_state([10.0, 20.0], [50.0, 50.0], [0.0, 0.0], "last", 0) == ([0.0, 0.0], 0)
    # an intensity of 0.5 (drive 0.5 over threshold 0) is activated, however small: m_dom 0, not the none state 1
    assert motivational_state([0.5], [0.0], [0.0], "first", 1) == ([0.5], 0)


def test_dod_weights_of_one_drive_and_a_dod_out_of_range():
    from homeo_decision.motivation import dod_weights

    # Eq 3.27-3.28 with |D| = 1: the weights sum to |D| = 1, so the one drive weighs 1 whatever the DoD
    assert dod_weights(0.3, 1, 0) == [1.0]
    with refused("DoD must be in [0, 1], got 1.5"):  # the refusal says what was given
        dod_weights(1.5, 2, 0)


def test_clamp_keeps_a_drive_inside_0_100_and_moves_nothing_else():
    from homeo_decision.motivation import clamp

    # Definition 1: -0.5 -> 0; 0.5 and 99.5 stay (inside, however close to a bound); 100.5 -> 100
    assert [clamp(x) for x in (-0.5, 0.5, 99.5, 100.5)] == [0.0, 0.5, 99.5, 100.0]


# -- Object Q-learning (Eq 3.11-3.17) -------------------------------------------------------------------------
def test_a_tick_before_the_first_phase_has_the_first_phase():
    from homeo_decision.objectq import Phase, phase_at

    sched = (Phase(10, 0.3, 4.0), Phase(20, 0.1, 2.0))
    # tick 5 precedes every start: the first phase; tick 10 starts it; tick 25 is past 20: the second
    assert phase_at(sched, 5) is sched[0] and phase_at(sched, 10) is sched[0] and phase_at(sched, 25) is sched[1]


def test_softmax_of_large_values_does_not_overflow():
    from homeo_decision.objectq import softmax_pick, softmax_probs

    # Eq 3.17 with Q = 1000 and 999 at tau 1: exp(1000) overflows a float, exp(Q - max) = exp(0), exp(-1) does not:
    # P = 1 / (1 + e^-1) = e / (e + 1) = 0.731, 1 / (e + 1) = 0.269
    e = math.e
    assert softmax_probs([1000.0, 999.0], 1.0) == pytest.approx([e / (e + 1), 1 / (e + 1)])
    # cumulative weights 1, 1 + 1/e = 1.368; u = 0.5 -> 0.684 < 1: the first action; u = 0.75 -> 1.026 >= 1: the second
    assert softmax_pick([1000.0, 999.0], [7, 8], 1.0, 0.5) == 7 and softmax_pick([1000.0, 999.0], [7, 8], 1.0, 0.75) == 8


def test_a_draw_at_the_top_of_the_range_picks_the_last_action():
    from homeo_decision.objectq import softmax_pick

    # equal values: cumulative weights 1, 2, 3; u = 1 (the closed end of a draw) -> 3, which no weight exceeds:
    # the last action (6), not the second (5) nor past the end
    assert softmax_pick([0.0, 0.0, 0.0], [4, 5, 6], 1.0, 1.0) == 6


def test_an_initial_q_given_wins_over_the_scenario_s(toy):
    from homeo_decision.objectq import ObjectQ

    assert toy.open.initial_q == 0.0
    q = ObjectQ(toy, initial_q=2.5)  # every entry of every table starts at the value given
    assert q.initial_q == 2.5 and {v for t in q.q for row in t for v in row} == {2.5}


def test_the_reduced_state_is_the_documented_number(toy, enc):
    from homeo_decision.objectq import ObjectQ

    q = ObjectQ(toy)
    code = enc(toy, "B", intention="on", box="on")
    # Eq 3.11-3.13: (m_dom * n_hum + hum) * n_states_o + object_state. Toy: S_hum = 3 intentions (none, on, come)
    # x 3 relations (near, far, absent): n_hum 9; intention "on" 1, the human at H and the robot at B: far 1 ->
    # hum = 1 * 3 + 1 = 4. box: distance (near, far) x status (off, on): 4 states; near 0, on 1 -> 0 * 2 + 1 = 1.
    # null: 1 state (0). m_dom 1: box (1 * 9 + 4) * 4 + 1 = 53; null (1 * 9 + 4) * 1 + 0 = 13
    assert q.states(1, code) == (53, 13)
    assert q.states(0, code) == (4 * 4 + 1, 4)  # m_dom 0: (0 + 4) * 4 + 1 = 17; null 4


def test_value_max_over_valid_subtracts_the_other_object_s_max(toy_raw, enc):
    from homeo_decision.objectq import ObjectQ
    from homeo_decision.scenario import scenario_from_dict

    raw = toy_raw()
    raw["open"]["value_max_over"] = "valid"
    sc = scenario_from_dict(raw)
    q = ObjectQ(sc)
    A, H = enc(sc, "B"), enc(sc, "H")
    s, s2 = q.states(0, A), q.states(0, H)  # the human's relation changes (far -> near): both objects' states change
    box, null = 0, 1
    turn_on, turn_off = q.act_local[sc.action_index("TurnOn")], q.act_local[sc.action_index("TurnOff")]
    q.q[box][s2[box]][turn_on] = 100.0  # invalid at H
    q.q[box][s2[box]][turn_off] = 1.0
    q.q[null][s2[null]][q.act_local[sc.action_index("GoB")]] = 2.0
    q.q[null][s[null]][q.act_local[sc.action_index("GoH")]] = 1.0
    # Eq 3.15-3.16 over the valid actions: V = max_valid Q^box(s') = 1 + [max Q^null(s') = 2 - max Q^null(s) = 1] = 2
    # Eq 3.14: Q <- 0.5 * 0 + 0.5 * (0 + 0.5 * 2) = 0.5
    assert q.update(sc.action_index("TurnOff"), s, 0.0, s2, 0.5, 0.5, A, H) == pytest.approx(0.5)


def test_value_max_over_valid_with_no_valid_action_takes_them_all(toy_raw, enc):
    from homeo_decision.objectq import ObjectQ
    from homeo_decision.scenario import scenario_from_dict

    raw = toy_raw()
    raw["open"]["value_max_over"] = "valid"
    raw["actions"][1]["requires"] = {"box.distance": ["near"]}  # TurnOff too needs the box near: none valid at H
    sc = scenario_from_dict(raw)
    q = ObjectQ(sc)
    A, H = enc(sc, "B"), enc(sc, "H")
    assert q.valid_local[H][0] == ()
    s, s2 = q.states(0, A), q.states(0, H)
    q.q[0][s2[0]][q.act_local[sc.action_index("TurnOn")]] = 100.0
    q.q[0][s2[0]][q.act_local[sc.action_index("TurnOff")]] = 1.0
    q.q[1][s2[1]][q.act_local[sc.action_index("GoB")]] = 2.0
    # no valid box action at H: the max over all of A_box, 100; V = 100 + [2 - 0] = 102
    # Q <- 0.5 * 0 + 0.5 * (0 + 0.5 * 102) = 25.5
    assert q.update(sc.action_index("TurnOff"), s, 0.0, s2, 0.5, 0.5, A, H) == pytest.approx(25.5)


# -- Algorithm 1's open choices on the motivation factor and the pseudo update (Eq 3.20-3.21, 3.23) --------------
def _core(toy_raw, **open_choices):
    from homeo_decision.agent import DecisionCore
    from homeo_decision.scenario import scenario_from_dict

    raw = toy_raw()
    raw["open"].update(open_choices)
    sc = scenario_from_dict(raw)
    return sc, DecisionCore(sc, 0)


def _set(core, sc, name, states, value):
    a = sc.action_index(name)
    core.q.q[core.q.act_obj[a]][states[core.q.act_obj[a]]][core.q.act_local[a]] = value


def _get(core, sc, name, states):
    return core.q.value(sc.action_index(name), states)


def test_the_motivation_bonus_goes_to_m_dom_or_only_to_an_activated_one(toy_raw, enc):
    from homeo_decision.agent import Percept

    sc, core = _core(toy_raw)  # the default, motivation_bonus = dominant: k = m_dom whatever its intensity
    X = enc(sc, "B")
    assert core.bonus_drive(Percept(X, (0.0, 58.0), [0.0, 58.0], 0, ())) == 0
    sc, core = _core(toy_raw, motivation_bonus="activated")  # Definition 6: only while intensity(m_dom) > 0
    assert core.bonus_drive(Percept(X, (0.0, 58.0), [0.0, 58.0], 0, ())) == -1  # intensity 0: no bonus (k = -1)
    assert core.bonus_drive(Percept(X, (0.5, 0.0), [0.5, 0.0], 0, ())) == 0  # 0.5 > 0: activated, however little
    assert core.bonus_drive(Percept(X, (0.0, 0.0), [0.0, 0.0], 2, ())) == -1  # m_dom 'none' (index 2): no drive


def test_perception_takes_the_none_state_when_nothing_is_activated(toy_raw, enc):
    sc, core = _core(toy_raw, no_activated_motivation="none")
    # NAch 0 (threshold 0, no intention: no stimulus): intensity 0 + 0 = 0; NEng 10 < 50: 0. None activated:
    # m_dom is 'none', the state after the 2 motivations: 2
    p = core.perceive([0.0, 10.0], enc(sc, "H"))
    assert (p.intensities, p.m_dom) == ([0.0, 0.0], 2)


def test_the_default_seed_is_0(toy):
    from homeo_decision.agent import DecisionCore

    a, b = DecisionCore(toy), DecisionCore(toy, 0)
    assert a.seed == 0 and [a.rng.random() for _ in range(3)] == [b.rng.random() for _ in range(3)]


def _pseudo_setup(core, sc, X, s, s_dag, extra=()):
    """Q(s, TurnOn) = 1, Q(s, GoH) = 2; Q(s+, TurnOn) = 3, Q(s+, GoH) = 6 (and what ``extra`` sets)."""
    _set(core, sc, "TurnOn", s, 1.0)
    _set(core, sc, "GoH", s, 2.0)
    _set(core, sc, "TurnOn", s_dag, 3.0)
    _set(core, sc, "GoH", s_dag, 6.0)
    for name, states, v in extra:
        _set(core, sc, name, states, v)


def test_the_pseudo_update_with_max_over_valid_reads_both_worlds(toy_raw, enc):
    # test_objectq.py's pseudo case with value_max_over = valid: at B every action is valid, so the same numbers
    sc, core = _core(toy_raw, value_max_over="valid")
    X = enc(sc, "B", intention="on")
    p = core.perceive([45.0, 58.0], X)  # Serving 45 + 20 = 65 > Survival 58: m_dom 0
    s, s_dag = p.states, core.q.states(1, X)  # praise -10: Serving 35 + 20 = 55 < 58: m+ = Survival (1)
    _pseudo_setup(core, sc, X, s, s_dag)
    p_next = core.perceive([48.0, 60.0], X)
    out = core.learn(p, sc.action_index("Wait"), (48.0, 60.0), -1, sc.action_index("TurnOn"), p_next, 0)
    # Wait: r = 2*(45-48) + (58-60) - 10 = -18; V = max_valid Q^null(s) = 2 + 0; Q = 0.5*0 + 0.5*(-18 + 0.5*2) = -8.5
    assert out.reward == -18.0 and _get(core, sc, "Wait", s) == pytest.approx(-8.5)
    # TurnOn: r+ = 2*1*(45-35) + 10 = 30; V = 3 + (6 - 2) = 7; Q = 0.5*1 + 0.5*(30 + 0.5*7) = 17.25
    assert out.pseudo_reward == 30.0 and _get(core, sc, "TurnOn", s) == pytest.approx(17.25)


def test_the_pseudo_state_breaks_a_tie_by_the_scenario_s_rule(toy_raw, enc):
    sc, core = _core(toy_raw)  # tie_break first
    X = enc(sc, "B", intention="on")
    p = core.perceive([48.0, 58.0], X)  # Serving 48 + 20 = 68 > 58: m_dom 0
    s, other = p.states, core.q.states(1, X)
    # praise -10: Serving 38 + 20 = 58 = Survival 58, a tie: the first, Serving (0): s+ = s
    _pseudo_setup(core, sc, X, s, other)
    p_next = core.perceive([51.0, 60.0], X)
    out = core.learn(p, sc.action_index("Wait"), (51.0, 60.0), -1, sc.action_index("TurnOn"), p_next, 0)
    # Wait: r = 2*(48-51) + (58-60) - 10 = -18; Q(s, Wait) = 0.5*(-18 + 0.5*2) = -8.5 (max Q^null(s) stays 2)
    # TurnOn: r+ = 2*(48-38) + 10 = 30; V^box(s, s) = max Q^box(s) = 1 + (2 - 2); Q = 0.5*1 + 0.5*(30 + 0.5) = 15.75
    # (with m+ = Survival it would read V = 3 + (6 - 2) = 7: 17.25)
    assert out.pseudo_reward == 30.0 and _get(core, sc, "TurnOn", s) == pytest.approx(15.75)


def test_the_pseudo_state_can_be_none_activated(toy_raw, enc):
    sc, core = _core(toy_raw, no_activated_motivation="none")
    H = enc(sc, "H")  # no intention: no stimulus
    p = core.perceive([5.0, 30.0], H)  # Serving 5, Survival 0 (30 < 50): m_dom 0
    s = p.states
    # praise -10: NAch 0, intensity 0; Survival 0: none activated, m+ = none (2)
    none, survival = core.q.states(2, H), core.q.states(1, H)
    _pseudo_setup(core, sc, H, s, none, extra=(("TurnOn", survival, 5.0), ("GoH", survival, 9.0)))
    p_next = core.perceive([8.0, 32.0], H)
    out = core.learn(p, sc.action_index("Wait"), (8.0, 32.0), -1, sc.action_index("TurnOn"), p_next, 0)
    # Wait: r = 2*(5-8) + (30-32) - 10 = -18. TurnOn: r+ = 2*1*(5-0) + 10 = 20; V = 3 + (6 - 2) = 7;
    # Q = 0.5*1 + 0.5*(20 + 0.5*7) = 12.25 (s+ = s would give 10.75, s+ with Survival 13.5)
    assert out.reward == -18.0 and out.pseudo_reward == 20.0
    assert _get(core, sc, "TurnOn", s) == pytest.approx(12.25)


def test_the_pseudo_serving_drive_satisfied_and_the_pseudo_reward_without_the_bonus(toy_raw, enc):
    for choices, want in ((dict(pseudo_serving="satisfied"), 2 * 45.0 + 10),  # NAch 45 -> 0: r+ = 2*1*45, + f
                          (dict(pseudo_reward="eq_3_19"), 1 * 10.0 + 10)):  # Eq 3.19: no (1 + xi): 1*(45 - 35), + f
        sc, core = _core(toy_raw, **choices)
        X = enc(sc, "B", intention="on")
        p = core.perceive([45.0, 58.0], X)
        out = core.learn(p, sc.action_index("Wait"), (48.0, 60.0), -1, sc.action_index("TurnOn"),
                         core.perceive([48.0, 60.0], X), 0)
        assert out.pseudo_reward == want, choices
    raw = toy_raw()
    raw["drives"].reverse()  # NEng first: the serving drive NAch is drive 1
    raw["open"]["pseudo_reward"] = "eq_3_19"
    from homeo_decision.agent import DecisionCore
    from homeo_decision.scenario import scenario_from_dict

    sc = scenario_from_dict(raw)
    core = DecisionCore(sc, 0)
    X = enc(sc, "B", intention="on")
    p = core.perceive([58.0, 45.0], X)  # Serving 65 > Survival 58: m_dom 1, the serving drive's
    assert sc.serving == 1 and p.m_dom == 1
    out = core.learn(p, sc.action_index("Wait"), (60.0, 48.0), -1, sc.action_index("TurnOn"),
                     core.perceive([60.0, 48.0], X), 0)
    assert out.pseudo_reward == 1 * 10.0 + 10  # Eq 3.19: no bonus on drive 1 either


# -- metrics: the stages of a run and the excess below 1 (Eq 4.4) ------------------------------------------------
def test_stage_marks_by_hand():
    from homeo_sim.metrics import stage_marks

    # every 10 up to 100, then every 100, each below n, and n itself
    assert stage_marks(5) == (5,)
    assert stage_marks(35) == (10, 20, 30, 35)
    assert stage_marks(450) == (10, 20, 30, 40, 50, 60, 70, 80, 90, 100, 200, 300, 400, 450)


def test_a_recorder_keeps_its_sums_at_each_mark():
    rec = MetricRecorder(NAMES, THR, marks=(1, 2, 3))
    for d, e, s in zip(DRIVES.tolist(), EXPRESSED, SATISFIED):
        rec.record(d, e, s)
    # after tick 1: sums 10, 60; tick 2: 30, 155; tick 3: 30, 195 (the excess of B: 10, 10 + 45, 55)
    assert [st["n"] for st in rec.stages] == [1, 2, 3]
    assert [st["sum"] for st in rec.stages] == [[10.0, 60.0], [30.0, 155.0], [30.0, 195.0]]
    assert rec.stages[-1] == GOOD


def test_an_excess_below_one_counts_and_integer_drives_make_floats():
    rec = MetricRecorder(NAMES, THR, keep=True)
    rec.record([1, 50], 0, 0)  # integers only
    rec.record([0, 51], 0, 0)
    assert rec.arrays()[0].dtype == np.float64  # the drives as floats, whatever numbers the caller gave
    rec = MetricRecorder(NAMES, THR)
    rec.record([0.0, 50.5], False, False)  # B 0.5 over its threshold 50: excess 0.5 (Eq 4.4), not 0
    assert rec.summary()["CEDA"]["B"] == 0.5


def test_an_action_raising_a_drive_and_a_decaying_drive_stay_in_0_100(toy_raw, enc):
    from homeo_decision.drives import DriveDynamics
    from homeo_decision.scenario import scenario_from_dict

    raw = toy_raw()
    raw["drives"][1]["rate"] = -0.5  # NEng (body) decays 0.5 a tick (a rate may be negative)
    raw["actions"][3]["effects"] = [{"set": {"robot.location": "B"}, "drives": {"NEng": 0.5}}]  # GoB raises it
    sc = scenario_from_dict(raw)
    body = DriveDynamics(sc, "body")
    for start, after in ((99.75, 100.0), (100.0, 100.0), (99.0, 99.5)):  # Table 4.1 then clamp: 100.25 -> 100
        body.values[1] = start
        body.apply_action(enc(sc, "H"), sc.action_index("GoB"))
        assert body.values[1] == after, start
    for start, after in ((0.25, 0.0), (0.0, 0.0), (1.0, 0.5)):  # Table 4.2 then clamp: -0.25 -> 0
        body.values[1] = start
        body.apply_time()
        assert body.values[1] == after, start


def test_the_serving_drive_grows_by_default_as_on_a_tick_expressed_and_unsatisfied(toy_raw):
    from homeo_decision.drives import DriveModel
    from homeo_decision.scenario import scenario_from_dict

    for growth in ("expressed", "unsatisfied"):
        raw = toy_raw()
        raw["open"]["serving_growth"] = growth
        raw["open"]["initial_drives"] = {"NAch": 50.0, "NEng": 0.0}
        m = DriveModel(scenario_from_dict(raw))
        m.apply_time()  # the defaults: an intention expressed, not satisfied: NAch grows by its rate, 50 + 3
        assert m.values[0] == 53.0, growth
        m.apply_time(expressed=True, satisfied=True)  # satisfied: it grows only under 'expressed'
        assert m.values[0] == (56.0 if growth == "expressed" else 53.0), growth


# -- the simulated human (Algorithm 2): no reasonable intention, what it shows, a habit ending below 1 --------------
def test_the_human_wants_nothing_where_no_intention_is_reasonable(toy, enc):
    from homeo_sim.human import SimHuman

    # toy: 'on' is reasonable while the box is off, 'come' while the human is far; P(no intention) = 0
    h = SimHuman(toy, 0)
    h.advance(enc(toy, "H", box="on"))  # box on, robot beside the human (near): none reasonable
    assert h.intention == 0
    h.advance(enc(toy, "H", box="off"))  # box off: 'on' (1) is the only reasonable one
    assert h.intention == 1


def test_what_the_human_shows_and_a_habit_that_sums_below_1(thesis, toy):
    from homeo_decision.scenario import ScenarioError
    from homeo_sim.human import SimHuman

    h = SimHuman(thesis, 3)
    assert set(h.observe()) == {"gesture", "movement", "keyword"}  # the intention's name only when asked for
    assert set(h.observe(with_intention=True)) == {"gesture", "movement", "keyword", "intention"}
    with refused(f"{toy.source}: the scenario has no 'observations' block: the simulated human cannot be observed"):
        SimHuman(toy, 0).observe()
    ch, symbols, _, cum = h._habits[0]
    it = h.intention
    # a cumulative habit ending at 0.9, not 1 (as rounding may leave it, only further): the first symbol 0.5, the
    # second 0.2, those between nothing, the last what is left
    row = [0.5] + [0.7] * (len(symbols) - 2) + [0.9]
    h._habits = ((ch, symbols, 0.0, [row if i == it else c for i, c in enumerate(cum)]), *h._habits[1:])
    n = 2000
    seen = [h.observe()["gesture"] for _ in range(n)]
    # inverse CDF: [0, 0.5) the first, [0.5, 0.7) the second, and every draw >= 0.7 stops at the last symbol
    # (the draws in [0.9, 1) too, not past the end): shares 0.5, 0.2, 0.3
    assert [seen.count(symbols[0]) / n, seen.count(symbols[1]) / n, seen.count(symbols[-1]) / n] == pytest.approx(
        [0.5, 0.2, 0.3], abs=0.04)

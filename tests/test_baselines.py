"""Baseline policies (random, threshold rules, flat Q-learning, no feedback) and the adaptive DoD."""

from __future__ import annotations

import subprocess
import sys
from collections import Counter

import pytest

from homeo_decision.adaptive_dod import AdaptiveDoD, AdaptiveDoDRobot, AdaptiveDoDSettings
from homeo_decision.agent import DecisionCore
from homeo_decision.baselines import POLICIES, FlatQ, RandomPolicy, RulePolicy, make_policy
from homeo_decision.qtable_io import QTableError
from homeo_sim.runner import RunConfig, make_decision, run_episode

NAch, NSoc, NRes, NEng = range(4)


def drives(nach=0, nsoc=0, nres=0, neng=0):
    return [float(nach), float(nsoc), float(nres), float(neng)]


# -- random --------------------------------------------------------------------------------

def test_random_picks_only_valid_actions_roughly_uniformly(thesis, enc):
    code = enc(thesis, "H")  # human near: Chat valid, Rest / Attach / Stay not
    valid = thesis.c.valid[code]
    names = {thesis.action_names[a] for a in valid}
    assert "Chat" in names and "Rest" not in names and "Attach" not in names
    pol = RandomPolicy(thesis, seed=3)
    p = pol.perceive(drives(), code)
    n = 9000
    counts = Counter(pol.select(p, t) for t in range(n))
    assert set(counts) == set(valid)
    expected = n / len(valid)
    for a in valid:
        assert abs(counts[a] - expected) < 0.15 * expected, (thesis.action_names[a], counts[a], expected)


def test_random_same_seed_same_choices(thesis, enc):
    code = enc(thesis, "C")
    a, b = RandomPolicy(thesis, seed=5), RandomPolicy(thesis, seed=5)
    p = a.perceive(drives(), code)
    assert [a.select(p, t) for t in range(200)] == [b.select(p, t) for t in range(200)]
    c = RandomPolicy(thesis, seed=6)
    assert [c.select(p, t) for t in range(200)] != [RandomPolicy(thesis, seed=5).select(p, t) for t in range(200)]


# -- rules ---------------------------------------------------------------------------------

@pytest.mark.parametrize("where, kw, d, expected", [
    # 1. battery at its threshold (50) wins over everything, even a pending intention
    ("R", {"intention": "light"}, drives(neng=50), "MoveToC"),
    ("C", {}, drives(neng=60), "Attach"),
    # attached: keep charging while NEng > 10 ...
    ("C", {"charger": "charging"}, drives(neng=30), "Stay"),
    # ... and stop at 10 or below: then the intention is served
    ("C", {"charger": "charging", "intention": "light"}, drives(neng=10), "LightOn"),
    # 2. serve: the first valid desired action (leave -> MoveToR)
    ("H", {"intention": "leave"}, drives(nres=80, nsoc=90), "MoveToR"),
    ("R", {"intention": "come"}, drives(), "MoveToH"),
    ("R", {"intention": "no_music", "player": "playing"}, drives(), "Stop"),
    # 3. rest at NRes >= 50: away from the human first
    ("H", {}, drives(nres=50), "MoveToR"),
    ("R", {}, drives(nres=50, nsoc=95), "Rest"),
    # 4. socialise at NSoc >= 70 when the human is there
    ("R", {}, drives(nsoc=70), "MoveToH"),
    ("H", {}, drives(nsoc=70), "Chat"),
    ("R", {"presence": "absent"}, drives(nsoc=90), "Rest"),  # nobody to chat with: idle
    # 5. idle: Rest where allowed, else Chat
    ("C", {}, drives(), "Rest"),
    ("H", {}, drives(nsoc=69, nres=49, neng=49), "Chat"),
])
def test_rule_hand_checked_choices(thesis, where, kw, d, expected):
    values = {"robot.location": where, "human.presence": kw.get("presence", "present"),
              "intention": kw.get("intention", "none"), "charger.status": kw.get("charger", "idle"),
              "player.status": kw.get("player", "idle"), "light.status": kw.get("light", "off")}
    code = thesis.encode(values)
    pol = RulePolicy(thesis)
    a = pol.select(pol.perceive(d, code), 0)
    assert thesis.action_names[a] == expected
    assert a in thesis.c.valid[code]


def test_rule_needs_the_scenarios_rule_policy_block(toy):
    with pytest.raises(ValueError, match="no 'rule_policy' block"):
        RulePolicy(toy)


# -- flat Q-learning (Eq 2.9) ------------------------------------------------------------------

def test_flatq_state_is_the_full_cartesian_product(toy, enc):
    fq = FlatQ(toy)
    # |M| x |S_hum| x |S_box| = 2 x (3 intentions x 3 relations) x (2 distances x 2 statuses) = 72
    assert fq.n_states == 72 and len(fq.q) == 72 and len(fq.q[0]) == len(toy.actions)
    # no state reduction: the box status changes the state even for the null object's actions
    s_off = fq.perceive(drives()[:2], enc(toy, "H", box="off")).states
    s_on = fq.perceive(drives()[:2], enc(toy, "H", box="on")).states
    assert s_off != s_on


def test_flatq_update_hand_computed(toy, enc):
    # toy: weights [1, 1] (DoD 0.5), xi 1, alpha 0.5 (one phase), gamma 0.5, f 10
    fq = FlatQ(toy)
    code = enc(toy, "H")
    p = fq.perceive([10.0, 60.0], code)  # intensities NAch 10, NEng 60 -> m_dom = NEng (k = 1)
    assert p.m_dom == 1
    code2 = enc(toy, "H", box="off")
    p2 = fq.perceive([13.0, 42.0], code2)
    a = toy.action_index("TurnOff")
    fq.q[p.states[0]][a] = 2.0
    fq.q[p2.states[0]][toy.action_index("GoB")] = 4.0  # max_a' Q(s', a') = 4
    before = [row[:] for row in fq.q]
    out = fq.learn(p, a, p2.drives, +1, None, p2, t=0)
    # r = (10 - 13) * 1 + (60 - 42) * (1 + 1) * 1 + f = -3 + 36 + 10 = 43
    assert out.reward == pytest.approx(43.0)
    # Eq 2.9: (1 - 0.5) * 2 + 0.5 * (43 + 0.5 * 4) = 1 + 22.5 = 23.5
    assert fq.q[p.states[0]][a] == pytest.approx(23.5)
    # nothing else moved: no collateral term, no pseudo update
    changed = [(s, j) for s in range(fq.n_states) for j in range(len(toy.actions)) if fq.q[s][j] != before[s][j]]
    assert changed == [(p.states[0], a)]


def test_flatq_ignores_proposals(toy, enc):
    fq = FlatQ(toy)
    code = enc(toy, "H", intention="come")
    p = fq.perceive([10.0, 0.0], code)
    out = fq.learn(p, toy.action_index("TurnOff"), [13.0, 2.0], -1, toy.action_index("GoH"), p, t=0)
    # it learns (m_dom Serving: 30 against 0): r = 2 * (10 - 13) + (0 - 2) - 10 = -18, Q = 0.5 * (-18 + 0.5 * 0) = -9
    assert out.reward == pytest.approx(-18.0)
    assert fq.q[p.states[0]][toy.action_index("TurnOff")] == pytest.approx(-9.0)
    assert fq.q[p.states[0]][toy.action_index("GoH")] == 0.0  # and the proposal teaches nothing


# -- no feedback ------------------------------------------------------------------------------

def test_nofeedback_ignores_feedback_and_proposals(toy, enc):
    code = enc(toy, "H", intention="come")
    qs = []
    for fb, prop in ((+1, None), (0, None), (-1, toy.action_index("GoH"))):
        core = make_policy("nofeedback", toy)
        p = core.perceive([10.0, 0.0], code)
        out = core.learn(p, toy.action_index("TurnOff"), [13.0, 2.0], fb, prop, p, t=0)
        # the drives alone (m_dom Serving): r = 2 * (10 - 13) + (0 - 2) = -8, Q = 0.5 * (-8 + 0.5 * 0) = -4
        assert out.reward == pytest.approx(-8.0)
        assert core.q.q[0][p.states[0]][toy.action_index("TurnOff")] == pytest.approx(-4.0)
        qs.append([row[:] for o in core.q.q for row in o])
    assert qs[0] == qs[1] == qs[2]


# -- the runner hook --------------------------------------------------------------------------

@pytest.mark.parametrize("policy", POLICIES)
def test_every_policy_runs_and_repeats_with_its_seed(thesis, policy):
    cfg = RunConfig(iterations=300, seed=4, policy=policy)
    a = run_episode(cfg, thesis, keep_actions=True)
    b = run_episode(cfg, thesis, keep_actions=True)
    assert a.actions == b.actions and a.metrics == b.metrics
    assert all(0 <= x < len(thesis.actions) for x in a.actions)


def test_make_decision_unknown_policy(thesis):
    with pytest.raises(ValueError, match="unknown policy"):
        make_decision(thesis, RunConfig(policy="oracle"))


@pytest.mark.parametrize("policy", ["random", "rule", "flatq"])
def test_save_q_without_object_q_table_fails_before_running(thesis, tmp_path, policy):
    target = tmp_path / "q.json"
    with pytest.raises(QTableError, match=policy):
        run_episode(RunConfig(iterations=50, policy=policy, save_q=str(target)), thesis)
    assert not target.exists()


def test_cli_save_q_with_random_policy_is_one_line_error(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "homeo_sim.cli", "run", "--policy", "random", "--iterations", "10",
                           "--save-q", str(tmp_path / "q.json")], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2
    assert proc.stderr.startswith("homeo-sim: error:") and len(proc.stderr.splitlines()) == 1
    assert "random" in proc.stderr and "Traceback" not in proc.stderr


def test_cli_adaptive_dod_needs_object_q():
    proc = subprocess.run([sys.executable, "-m", "homeo_sim.cli", "run", "--policy", "rule", "--adaptive-dod",
                           "--iterations", "10"], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2 and proc.stderr.startswith("homeo-sim: error:") and "adaptive" in proc.stderr


def test_cli_runs_a_baseline_as_json():
    import json

    proc = subprocess.run([sys.executable, "-m", "homeo_sim.cli", "run", "--policy", "flatq", "--iterations", "200",
                           "--json", "--quiet"], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert set(json.loads(proc.stdout)["metrics"]) == {"HSR", "RSR", "CDA", "CEDA"}


# -- adaptive DoD -----------------------------------------------------------------------------

SECURE = [10.0, 10.0, 10.0, 10.0]
INSECURE = [10.0, 95.0, 10.0, 10.0]


def run_controller(dod, feedback, drives_, ticks=100, **kw):
    ctl = AdaptiveDoD(dod, AdaptiveDoDSettings(**kw))
    for t in range(ticks):
        ctl.observe(feedback, drives_)
        ctl.adjust(t)
    return ctl


def test_adaptive_dod_rises_when_user_unsatisfied_and_robot_secure():
    # user satisfaction 0 (target 0.8), robot secure: shortfall 0.8 - 0 -> step min(0.5 * 0.8, 0.05) per 50 ticks
    ctl = run_controller(0.25, -1, SECURE, ticks=100)
    assert ctl.dod == pytest.approx(0.35)
    assert ctl.history == [(0, 0.25), (50, pytest.approx(0.30)), (100, pytest.approx(0.35))]


def test_adaptive_dod_falls_when_robot_insecure_and_user_satisfied():
    ctl = run_controller(0.25, +1, INSECURE, ticks=100)
    assert ctl.dod == pytest.approx(0.15)


def test_adaptive_dod_holds_when_both_satisfied():
    ctl = run_controller(0.25, +1, SECURE, ticks=500)
    assert ctl.dod == 0.25 and ctl.history == [(0, 0.25)]


def test_adaptive_dod_both_short_larger_shortfall_wins_and_step_is_proportional():
    # user 0.5 of feedback positive (shortfall 0.3), robot always insecure (shortfall 0.9): falls by 0.5 * 0.6 = 0.3,
    # capped at max_step 1.0 here
    ctl = AdaptiveDoD(0.5, AdaptiveDoDSettings(max_step=1.0, period=50))
    for t in range(50):
        ctl.observe(+1 if t % 2 else -1, INSECURE)
        ctl.adjust(t)
    su, sr = ctl.shortfalls()
    assert sr == pytest.approx(0.9)
    assert ctl.dod == pytest.approx(0.5 + 0.5 * (su - sr))
    assert ctl.dod < 0.5


def test_adaptive_dod_stays_in_bounds_and_respects_warmup():
    assert run_controller(0.95, -1, SECURE, ticks=1000).dod == 1.0
    assert run_controller(0.05, +1, INSECURE, ticks=1000, dod_min=0.1).dod == pytest.approx(0.1)
    assert run_controller(0.25, -1, SECURE, ticks=100, warmup=200).dod == 0.25


def test_adaptive_robot_sets_the_core_weights(toy, enc):
    core = DecisionCore(toy, 0, dod=0.5)
    robot = AdaptiveDoDRobot(core, AdaptiveDoDSettings(period=1))
    code = enc(toy, "H", intention="come")
    p = robot.perceive([10.0, 0.0], code)
    robot.learn(p, toy.action_index("TurnOff"), [13.0, 2.0], -1, None, p, t=0)
    assert robot.dod == pytest.approx(0.55) and core.dod == pytest.approx(0.55)
    assert core.weights == pytest.approx([1.1, 0.9])  # Eq 3.27-3.28 with |D| = 2


def test_adaptive_dod_run_is_deterministic(thesis):
    cfg = RunConfig(iterations=400, seed=2, adaptive_dod=True)
    a, b = run_episode(cfg, thesis, keep_actions=True), run_episode(cfg, thesis, keep_actions=True)
    assert a.actions == b.actions and a.metrics == b.metrics


def test_adaptive_settings_validate():
    with pytest.raises(ValueError):
        AdaptiveDoDSettings(target_hsr=1.5)
    with pytest.raises(ValueError):
        AdaptiveDoDSettings(period=0)


# -- the rule baseline as scenario data: the thesis's rules give exactly the old hand-coded choices ---

class OldThesisRule:
    """The hand-coded rule of the thesis scenario as it was before the rules became data (the oracle)."""

    def __init__(self, sc):
        thr = {d.name: d.threshold for d in sc.drives}
        self.charge_at, self.charge_until, self.rest_at, self.chat_at = thr["NEng"], 10.0, thr["NRes"], thr["NSoc"]
        names = sc.drive_names
        self.i_eng, self.i_res, self.i_soc = names.index("NEng"), names.index("NRes"), names.index("NSoc")
        self.a = {n: sc.action_index(n) for n in ("MoveToC", "Attach", "Stay", "Rest", "MoveToR", "Chat", "MoveToH")}
        self.desired = [tuple(sc.c.action_ids[a] for a in it.desired) for it in sc.intentions]
        self.sc = sc

    def select(self, d, code):
        v = self.sc.c.views[code]
        valid = self.sc.c.valid[code]
        a = self.a
        near_charger = v["charger.distance"] == "near"
        charging = v["charger.status"] == "charging"
        if d[self.i_eng] >= self.charge_at or (charging and near_charger and d[self.i_eng] > self.charge_until):
            if not near_charger:
                return a["MoveToC"]
            return a["Stay"] if charging else a["Attach"]
        it = self.sc.c.intention_of[code]
        if it:
            for act in self.desired[it - 1]:
                if act in valid:
                    return act
        if d[self.i_res] >= self.rest_at:
            return a["Rest"] if a["Rest"] in valid else a["MoveToR"]
        if d[self.i_soc] >= self.chat_at and v["human.relation"] != "absent":
            return a["Chat"] if a["Chat"] in valid else a["MoveToH"]
        for act in (a["Rest"], a["Chat"]):
            if act in valid:
                return act
        return valid[0]


def test_rule_data_matches_the_old_hand_coded_rule_in_every_world(thesis):
    old, new = OldThesisRule(thesis), RulePolicy(thesis)
    levels = (0, 9, 10, 11, 49, 50, 51, 69, 70, 100)
    n = 0
    for code in range(0, thesis.n_codes):
        for nsoc in levels[::2]:
            for nres in levels:
                for neng in levels:
                    d = drives(nach=5, nsoc=nsoc, nres=nres, neng=neng)
                    assert new.select(new.perceive(d, code), 0) == old.select(d, code), (thesis.decode(code), d)
                    n += 1
    assert n == thesis.n_codes * 5 * 100


@pytest.mark.parametrize("seed", [0, 3, 7])
def test_rule_runs_match_the_old_hand_coded_rule(thesis, seed, monkeypatch):
    import homeo_decision.baselines as bl

    new = run_episode(RunConfig(iterations=600, seed=seed, policy="rule"), keep_actions=True)

    class OldAsPolicy(bl.RulePolicy):
        def __init__(self, sc, seed=0, **kw):
            super().__init__(sc, seed, **kw)
            self.old = OldThesisRule(sc)

        def select(self, p, t):
            return self.old.select(p.drives, p.code)

    monkeypatch.setattr(bl, "RulePolicy", OldAsPolicy)
    assert isinstance(bl.make_policy("rule", thesis), OldAsPolicy)  # the runner really gets the oracle
    old = run_episode(RunConfig(iterations=600, seed=seed, policy="rule"), keep_actions=True)
    assert len(new.actions) == 600 and new.actions == old.actions
    assert new.metrics == old.metrics


def test_rule_fall_through_and_default(toy_raw):
    raw = toy_raw()
    # rule 1 picks only TurnOn, which is invalid away from the box: fall through to rule 2 (its 'when' fails
    # while the box is off) and then to the first valid action
    raw["rule_policy"] = {"rules": [
        {"name": "a", "actions": [{"action": "TurnOn"}]},
        {"name": "b", "actions": [{"action": "GoB", "when": {"box.status": ["on"]}}]}]}
    from homeo_decision.scenario import scenario_from_dict

    sc = scenario_from_dict(raw)
    pol = RulePolicy(sc)
    at_h = sc.encode({"robot.location": "H", "human.presence": "present", "intention": "none", "box.status": "off"})
    assert sc.action_names[pol.select(pol.perceive([0.0, 0.0], at_h), 0)] == sc.action_names[sc.c.valid[at_h][0]]
    at_b = sc.encode({"robot.location": "B", "human.presence": "present", "intention": "none", "box.status": "off"})
    assert sc.action_names[pol.select(pol.perceive([0.0, 0.0], at_b), 0)] == "TurnOn"
    on_h = sc.encode({"robot.location": "H", "human.presence": "present", "intention": "none", "box.status": "on"})
    assert sc.action_names[pol.select(pol.perceive([0.0, 0.0], on_h), 0)] == "GoB"


def test_rule_hysteresis_keeps_going_above_the_low_mark(toy_raw):
    raw = toy_raw()
    raw["rule_policy"] = {"rules": [
        {"name": "go", "drive": "NEng", "keep_while": {"when": {"box.distance": ["near"]}, "above": 20},
         "actions": [{"action": "GoB", "when": {"box.distance": ["far"]}}, {"action": "TurnOff"}]},
        {"name": "rest", "actions": [{"action": "Wait"}]}]}
    from homeo_decision.scenario import scenario_from_dict

    sc = scenario_from_dict(raw)
    pol = RulePolicy(sc)
    w = lambda loc: sc.encode({"robot.location": loc, "human.presence": "present", "intention": "none",  # noqa: E731
                               "box.status": "off"})
    pick = lambda neng, loc: sc.action_names[pol.select(pol.perceive([0.0, float(neng)], w(loc)), 0)]  # noqa: E731
    assert pick(50, "H") == "GoB"  # at the threshold (50, the default 'at')
    assert pick(49, "H") == "Wait"  # below it, away from the box: no hysteresis
    assert pick(30, "B") == "TurnOff"  # below it but at the box and above 20: keep going
    assert pick(20, "B") == "Wait"  # at the low mark: stop

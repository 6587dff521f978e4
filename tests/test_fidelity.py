"""The fidelity score (issue 15): Table 4.5 inside/distance and the statements' criteria, on hand-made
aggregates whose answers are computed here by hand; the criteria's validation; the new open choices."""

from __future__ import annotations

import copy

import pytest

from homeo_decision.scenario import ScenarioError, load_scenario, scenario_from_dict
from homeo_decision.scenario.model import ReferenceSpec
from homeo_sim.report.fidelity import criteria_score, fidelity, needed_labels, table_score


def s(mean, lo, hi, per_seed=None):
    return {"mean": mean, "ci95": [lo, hi], "per_seed": per_seed or [mean]}


def agg(hsr, rsr, cda_all=s(30.0, 28.0, 32.0), ceda_all=s(4.0, 3.0, 5.0)):
    return {"HSR": hsr, "RSR": rsr, "CDA": {"D": s(40.0, 39.9, 40.1), "all": cda_all},
            "CEDA": {"D": s(2.0, 1.0, 3.0), "all": ceda_all}}


REF = {"HSR": 0.82, "RSR": 0.90, "CDA": {"D": 43.5, "all": 32.5}, "CEDA": {"D": 2.05, "all": 4.12}}


def test_table_score_inside_and_distance_by_hand():
    a = agg(s(0.80, 0.79, 0.81), s(0.88, 0.85, 0.91))
    rows = {r["metric"]: r for r in table_score(a, REF)}
    assert list(rows) == ["HSR", "RSR", "CDA.D", "CDA.all", "CEDA.D", "CEDA.all"]
    # HSR: half-width 0.01 < 5% of 0.82 = 0.041, so the floor applies: 0.02 / 0.041
    assert not rows["HSR"]["inside"] and rows["HSR"]["distance"] == pytest.approx(0.02 / 0.041)
    # RSR: inside; half-width 0.03 < 5% of 0.90 = 0.045, the floor: 0.02 / 0.045
    assert rows["RSR"]["inside"] and rows["RSR"]["distance"] == pytest.approx(0.02 / 0.045)
    # CDA D: 40 [39.9, 40.1] vs 43.5: floor 2.175, distance 3.5 / 2.175
    assert not rows["CDA.D"]["inside"] and rows["CDA.D"]["distance"] == pytest.approx(3.5 / 2.175)
    # CDA all: 30 [28, 32] vs 32.5: half-width 2 > floor 1.625, outside by a hair, distance 1.25
    assert not rows["CDA.all"]["inside"] and rows["CDA.all"]["distance"] == pytest.approx(1.25)
    # CEDA D: 2 [1, 3] vs 2.05 inside; CEDA all 4 [3, 5] vs 4.12 inside, distance 0.12
    assert rows["CEDA.D"]["inside"] and rows["CEDA.all"]["inside"]
    assert rows["CEDA.all"]["distance"] == pytest.approx(0.12)


def C(kind, **kw):
    return {"id": kind + str(len(kw)), "figure": "x", "says": "text", "criterion": "words", "kind": kind, **kw}


def M_fake():
    """Labelled aggregates: xi 0 and 2, pseudo on/off, a DoD sweep 0, 0.5, 1 and the default run at 0.25."""
    def a(h, r, cda=30.0, ceda=4.0, hs=None, rs=None):
        return agg(s(h, h - 0.01, h + 0.01, hs), s(r, r - 0.02, r + 0.02, rs), s(cda, cda - 1, cda + 1), s(ceda, ceda - .5, ceda + .5))
    return {
        "base": a(0.8, 0.9, hs=[0.8, 0.8], rs=[0.9, 0.9]),
        "pseudo=True": a(0.8, 0.9),
        "pseudo=False": a(0.7, 0.85, cda=31.5),
        "xi=0.0": a(0.85, 0.35, cda=40.0, ceda=9.0),
        "xi=2.0": a(0.83, 0.95, cda=25.0, ceda=2.0),
        "dod=0.0": a(0.62, 0.95, hs=[0.62, 0.62], rs=[0.95, 0.95]),
        "dod=0.5": a(0.9, 0.45, hs=[0.9, 0.9], rs=[0.45, 0.45]),
        "dod=1.0": a(0.95, 0.05, hs=[0.95, 0.95], rs=[0.05, 0.05]),
    }


SWEEPS = {"dod": (0.0, 0.5, 1.0), "xi": (0.0, 2.0), "pseudo": (True, False)}


@pytest.mark.parametrize("crit, holds", [
    (C("below", at="xi=0.0", metric="RSR", value=0.4), True),           # 0.35 < 0.4
    (C("below", at="xi=0.0", metric="RSR", value=0.3), False),
    (C("change_between", **{"from": "xi=0.0", "to": "xi=2.0"}, metric="HSR", lo=-0.1, hi=0.0), True),  # -0.02
    (C("change_between", **{"from": "xi=0.0", "to": "xi=2.0"}, metric="HSR", lo=-0.01, hi=0.0), False),
    (C("decreases", **{"from": "xi=0.0", "to": "xi=2.0"}, metrics=["CEDA.all", "CDA.all"]), True),
    (C("decreases", **{"from": "xi=2.0", "to": "xi=0.0"}, metrics=["CEDA.all"]), False),
    (C("same", a="pseudo=True", b="pseudo=False", metric="CDA.all"), True),   # [29, 31] and [30.5, 32.5]
    (C("same", a="pseudo=True", b="pseudo=False", metric="HSR"), False),      # [0.79, 0.81] and [0.69, 0.71]
    (C("near", at="dod=0.0", metric="HSR", value=0.6, tol=0.1), True),
    (C("near", at="dod=0.0", metric="HSR", value=0.8, tol=0.1), False),
    (C("first_below", sweep="dod", metric="RSR", level=0.5, value=0.5, tol=0.1), True),  # first below at 0.5
    (C("first_below", sweep="dod", metric="RSR", level=0.5, value=0.2, tol=0.1), False),
    # HSR x RSR: 0.589 (0), 0.72 (base, 0.25), 0.405 (0.5), 0.0475 (1): best at the default's 0.25
    (C("best_near", sweep="dod", product=["HSR", "RSR"], value=0.2, tol=0.1), True),
    (C("best_near", sweep="dod", product=["HSR", "RSR"], value=0.5, tol=0.1), False),
])
def test_each_criterion_kind_by_hand(crit, holds):
    (row,) = criteria_score([crit], M_fake(), SWEEPS, {"dod": 0.25})
    assert row["agrees"] is holds, row["ours"]


def M_staged():
    """M_fake with parts of runs (issue 31): early/late pseudo-update runs, two drives' CEDA, a mean curve."""
    M = M_fake()
    two = lambda a, b: {"CEDA": {"A": s(a, a - 1, a + 1), "B": s(b, b - 1, b + 1), "all": s((a + b) / 2, 0, 99)}}  # noqa: E731
    M["pseudo=True@1000"] = agg(s(0.6, 0.55, 0.65), s(0.7, 0.6, 0.8)) | two(2.0, 4.0)
    M["pseudo=False@1000"] = agg(s(0.3, 0.25, 0.35), s(0.6, 0.5, 0.7)) | two(10.0, 5.0)
    M["base@curve"] = {"t": [10, 100, 200, 300, 1000], "RSR": [1.0, 0.6, 0.5, 0.55, 0.8],
                       "HSR": [0.1, 0.3, 0.5, 0.6, 0.8], "CDA.NAch": [20.0, 15.0, 10.0, 5.0, 2.0]}
    return M


@pytest.mark.parametrize("crit, holds", [
    (C("within", at="base", metrics=["HSR", "RSR"], lo=0.75, hi=0.95), True),  # 0.8 and 0.9
    (C("within", at="base", metrics=["HSR", "RSR"], lo=0.85, hi=0.95), False),
    (C("ratio", **{"from": "pseudo=False", "to": "pseudo=True"}, metric="HSR", lo=1.05, hi=1.15), True),  # 0.8 / 0.7
    (C("ratio", **{"from": "pseudo=False", "to": "pseudo=True"}, metric="HSR", lo=1.15, hi=2.0), False),  # 1.143
    # early gain 0.6 - 0.3 = 0.3 against the whole run's 0.8 - 0.7 = 0.1
    (C("gain_larger", **{"from": "pseudo=False@1000", "to": "pseudo=True@1000", "than_from": "pseudo=False",
                         "than_to": "pseudo=True"}, metric="HSR"), True),
    (C("gain_larger", **{"from": "pseudo=False", "to": "pseudo=True", "than_from": "pseudo=False@1000",
                         "than_to": "pseudo=True@1000"}, metric="HSR"), False),
    # CEDA A falls 10 -> 2, B 5 -> 4: A's share 8 / 9
    (C("mostly_from", **{"from": "pseudo=False@1000", "to": "pseudo=True@1000"}, metric="CEDA", drive="A", value=0.5), True),
    (C("mostly_from", **{"from": "pseudo=False@1000", "to": "pseudo=True@1000"}, metric="CEDA", drive="A", value=0.9), False),
    # HSR [0.69, 0.71] below [0.79, 0.81]; RSR [0.83, 0.87] below [0.88, 0.92]; CDA all [29, 31] vs [30.5, 32.5] overlap
    (C("apart", lower=["pseudo=False"], higher=["pseudo=True"], metrics=["HSR", "RSR"]), True),
    (C("apart", lower=["pseudo=True"], higher=["pseudo=False"], metrics=["CDA.all"]), False),
    # DoD 0, 0.25 (base), 0.5, 1 against RSR 0.95, 0.9, 0.45, 0.05: r = -0.97467 (by hand)
    (C("sweep_corr", sweep="dod", metric="RSR", lo=-1.0, hi=-0.97), True),
    (C("sweep_corr", sweep="dod", metric="RSR", lo=-1.0, hi=-0.98), False),
    # CEDA all over the DoD sweep: 4 (0), 4 (0.25), 4 (0.5), 4 (1): a tie goes to the first, DoD 0
    (C("lowest_at", sweep="dod", metrics=["CEDA.all"], value=0.0, tol=0.0), True),
    (C("lowest_at", sweep="dod", metrics=["HSR"], value=0.5, tol=0.1), False),  # HSR lowest at DoD 0
    # the curve's HSR rises while CDA NAch falls: r = -0.97 over 10-1000; lowest RSR 0.5 at 200
    (C("curve_corr", at="base", x="HSR", y="CDA.NAch", span=[10, 1000], lo=-1.0, hi=-0.5), True),
    (C("curve_corr", at="base", x="HSR", y="RSR", span=[200, 1000], lo=-1.0, hi=-0.5), False),  # 0.5 -> 0.8: r > 0
    (C("curve_min", at="base", metric="RSR", span=[10, 1000], value=0.6, when=[100, 300]), True),
    (C("curve_min", at="base", metric="RSR", span=[10, 1000], value=0.6, when=[300, 1000]), False),
    (C("curve_min", at="base", metric="RSR", span=[10, 100], value=0.6, when=[10, 1000]), False),  # 0.6 is not < 0.6
    (C("all_of", parts=[{"kind": "below", "at": "xi=0.0", "metric": "RSR", "value": 0.4},
                        {"kind": "within", "at": "base", "metrics": ["HSR"], "lo": 0.7, "hi": 0.9}]), True),
    (C("all_of", parts=[{"kind": "below", "at": "xi=0.0", "metric": "RSR", "value": 0.4},
                        {"kind": "within", "at": "base", "metrics": ["HSR"], "lo": 0.9, "hi": 1.0}]), False),
])
def test_each_issue_31_kind_by_hand(crit, holds):
    (row,) = criteria_score([crit], M_staged(), SWEEPS, {"dod": 0.25})
    assert row["agrees"] is holds, row["ours"]


def test_a_stage_is_the_difference_of_running_sums_by_hand():
    from homeo_sim.report.fidelity import label_aggregates

    def st(n, ints, sat, sec, sums, excess):
        return {"n": n, "intentions": ints, "satisfied": sat, "secure": sec, "sum": sums, "excess": excess}

    # two seeds; after 10 and 20 ticks
    runs = {"base": [{"stages": [st(10, 8, 2, 10, [50.0, 100.0], [50.0, 0.0]), st(20, 15, 9, 16, [80.0, 300.0], [80.0, 40.0])]},
                     {"stages": [st(10, 10, 5, 5, [0.0, 100.0], [0.0, 0.0]), st(20, 20, 15, 15, [10.0, 200.0], [10.0, 0.0])]}]}
    M = label_aggregates(runs, ["A", "B"], {"base@10-20", "base@10", "base@curve"})
    late = M["base@10-20"]
    # seed 1: 7 intentions, 7 served, 6 of 10 secure; A (80-50)/10, B (300-100)/10; seed 2: 10, 10, 10 of 10
    assert late["HSR"]["per_seed"] == [1.0, 1.0] and late["RSR"]["per_seed"] == [0.6, 1.0]
    assert late["CDA"]["A"]["per_seed"] == [3.0, 1.0] and late["CDA"]["B"]["per_seed"] == [20.0, 10.0]
    assert late["CDA"]["all"]["per_seed"] == [11.5, 5.5] and late["CEDA"]["B"]["per_seed"] == [4.0, 0.0]
    assert late["misses"]["per_seed"] == [0, 0] and late["insecure"]["per_seed"] == [4, 0]
    early = M["base@10"]
    assert early["HSR"]["per_seed"] == [0.25, 0.5] and early["misses"]["per_seed"] == [6, 5]
    cur = M["base@curve"]  # per tick the mean over the seeds: HSR (0.25 + 0.5) / 2, (9/15 + 15/20) / 2
    assert cur["t"] == [10, 20] and cur["HSR"] == pytest.approx([0.375, 0.675])
    assert cur["CDA.A"] == pytest.approx([2.5, 2.25])
    # a part of the run it has no running sums for: left out (a criterion reading it says it was not measured)
    assert label_aggregates(runs, ["A", "B"], {"base@5-20", "base@10-30"}) == {}


def test_a_run_keeps_its_running_sums_at_the_stage_marks():
    from homeo_sim.metrics import stage_marks
    from homeo_sim.runner import RunConfig, run_episode

    assert stage_marks(250) == (10, 20, 30, 40, 50, 60, 70, 80, 90, 100, 200, 250)
    assert stage_marks(5000)[-3:] == (4800, 4900, 5000) and stage_marks(5) == (5,)
    r = run_episode(RunConfig(iterations=250, seed=1))
    last = r.stages[-1]
    assert [x["n"] for x in r.stages] == list(stage_marks(250))
    # the last running sums are the run's metrics
    assert last["satisfied"] / last["intentions"] == r.metrics["HSR"] and last["secure"] / 250 == r.metrics["RSR"]
    assert last["sum"][0] / 250 == r.metrics["CDA"]["NAch"]


def test_needed_labels_are_those_the_criteria_read():
    crits = [C("below", at="xi=0.0", metric="RSR", value=0.4),
             C("sweep_corr", sweep="dod", metric="RSR", lo=-1.0, hi=-0.9),
             C("best_near", sweep="dod", product=["HSR", "RSR"], value=0.2, tol=0.1)]
    assert needed_labels(crits, SWEEPS) == {"base", "xi=0.0", "dod=0.0", "dod=0.5", "dod=1.0"}


def test_summary_counts_inside_and_met():
    ref = ReferenceSpec("src", REF, None, (C("below", at="xi=0.0", metric="RSR", value=0.4),
                                            C("below", at="xi=0.0", metric="RSR", value=0.3)))
    M = M_fake()
    M["base"] = agg(s(0.80, 0.79, 0.81), s(0.88, 0.85, 0.91))
    f = fidelity(ref, M, SWEEPS, {"dod": 0.25})
    assert (f["table_inside"], f["table_total"], f["statements_met"], f["statements_total"]) == (3, 6, 1, 2)
    # errors: HSR 0.80/0.82 - 1, RSR 0.88/0.90 - 1, CDA D 40/43.5 - 1, CDA all 30/32.5 - 1, CEDA D 2/2.05 - 1,
    # CEDA all 4/4.12 - 1; the largest is CDA D's -8.05%, all within 15%; one set (M itself), 1 of 2 statements
    errs = [0.80 / 0.82 - 1, 0.88 / 0.90 - 1, 40 / 43.5 - 1, 30 / 32.5 - 1, 2 / 2.05 - 1, 4 / 4.12 - 1]
    assert [r["error"] for r in f["table"]] == pytest.approx(errs)
    assert f["errors"]["mean_abs_error"] == pytest.approx(sum(abs(e) for e in errs) / 6)
    assert f["summary"] == ("Table 4.5: mean |error| 4.3%, largest CDA D -8%, 6/6 within 15%, HSR -2.4%, RSR -2.2%; "
                            "statements per 1-seed set: 1 of 2")  # M's one seed per run: one set of one seed
    assert f["goals"] == {"mean_error": True, "each_error": True, "headline_error": True, "statements_per_set": False}
    assert fidelity(None, M, SWEEPS)["table"] == []


def test_relative_errors_and_their_goals_by_hand():
    from homeo_sim.report.fidelity import error_summary, relative_errors

    a = agg(s(0.779, 0.7, 0.8), s(0.90, 0.85, 0.91))
    rows = relative_errors(a, {"HSR": 0.82, "RSR": 0.90, "CDA": {"D": 50.0}})
    assert [(r["metric"], round(r["error"], 6)) for r in rows] == [("HSR", -0.05), ("RSR", 0.0), ("CDA.D", -0.2)]
    e = error_summary(rows)
    assert e["mean_abs_error"] == pytest.approx(0.25 / 3) and e["largest"] == "CDA.D" and e["within_each"] == 2
    # 8.3% > 8%: not met; CDA D's 20% > 15%: not met; HSR exactly 5% is within 5%
    assert e["goals"] == {"mean_error": False, "each_error": False, "headline_error": True}
    rows[2]["error"] = -0.15
    # now (5 + 0 + 15) / 3 = 6.7% <= 8%, and 15% is within 15%
    assert error_summary(rows)["goals"] == {"mean_error": True, "each_error": True, "headline_error": True}
    rows[0]["error"] = -0.0501
    assert error_summary(rows)["goals"]["headline_error"] is False


def test_seed_sets_are_disjoint_runs_of_twenty():
    from homeo_sim.report.fidelity import seed_sets

    assert seed_sets(range(100)) == [list(range(i, i + 20)) for i in range(0, 100, 20)]
    assert seed_sets(range(45)) == [list(range(20)), list(range(20, 40))]  # 40-44 in no set
    assert seed_sets(range(7)) == [list(range(7))] and seed_sets([]) == []
    assert seed_sets([5, 9, 2], size=2) == [[5, 9]]


def test_statement_shares_count_sets_by_hand():
    from homeo_sim.report.fidelity import statement_shares

    crits = [C("below", at="xi=0.0", metric="RSR", value=0.4), C("near", at="dod=0.0", metric="HSR", value=0.6, tol=0.1)]
    good, bad = M_fake(), M_fake()
    bad["xi=0.0"] = bad["xi=2.0"]  # RSR(xi 0) 0.95: the first statement fails on this set
    sh = statement_shares(crits, [good, bad, good], SWEEPS, {"dod": 0.25})
    assert sh["met_per_set"] == [2, 1, 2]
    assert [(x["held"], x["of"], x["per_set"]) for x in sh["shares"]] == [(2, 3, [True, False, True]), (3, 3, [True] * 3)]
    f = fidelity(ReferenceSpec("src", REF, None, tuple(crits)), good, SWEEPS, {"dod": 0.25}, M_sets=[good, bad, good],
                 n_seeds=6)
    assert f["statements_per_set"] == [2, 1, 2] and f["goals"]["statements_per_set"] is False  # 1 < 0.9 x 2
    assert f["summary"].endswith("statements per 2-seed set: 2, 1, 2 of 2") and "over 6 seeds" in f["summary"]
    assert [st["held"] for st in f["statements"]] == [2, 3]


# -- the thesis scenario's criteria ---------------------------------------------------------

def test_thesis_has_one_criterion_per_claim_of_sections_4_2_2_to_5():
    # issue 31: every claim of Secs 4.2.2-4.2.5 and Chapter 5 about Figs 4.1-4.5 and Table 4.5, each once
    crit = load_scenario().reference.criteria
    assert len(crit) == 30 and len({c["id"] for c in crit}) == 30
    figs = {f.strip() for c in crit for f in c["figure"].split(",")}
    assert {"4.1", "4.2", "4.3", "4.4", "4.5", "Table 4.5"} <= {f.rstrip("abcdef") for f in figs}


def test_every_claim_is_quoted_in_fidelity_md_and_the_lists_agree():
    """docs/FIDELITY.md's list of claims quotes each criterion's sentences, with its id; no id there that the
    scenario lacks."""
    import re
    from pathlib import Path

    doc = Path(__file__).resolve().parents[1].joinpath("docs", "FIDELITY.md").read_text()
    part = doc[doc.index("### The complete list of claims"):]
    part = part[:part.index("\n### ", 10)]
    crit = load_scenario().reference.criteria
    for c in crit:
        quote = c["says"].rsplit(" (", 1)[0]
        for piece in quote.split(" ... "):
            assert piece in part, (c["id"], piece)
        assert f"`{c['id']}`" in part, c["id"]
    assert set(re.findall(r"^\| `(\w+)` \|", part, re.M)) == {c["id"] for c in crit}


@pytest.mark.parametrize("change, words", [
    (lambda c: c.update(kind="around"), ("kind", "around")),
    (lambda c: c.update(metric="CDA.Power"), ("metric", "CDA.Power")),
    (lambda c: c.pop("value"), ("exactly the fields",)),
    (lambda c: c.update(at="speed=3"), ("at", "speed=3")),
    (lambda c: c.update(value="low"), ("value", "number")),
    (lambda c: c.update(at="base@late"), ("label", "base@late", "@<from>-<to>")),  # issue 31's parts of a run
    (lambda c: c.update(at="base@500-100"), ("label", "base@500-100")),
    (lambda c: c.update(kind="all_of", parts=[{"kind": "below", "at": "xi=0.0"}]) or [c.pop(k) for k in ("at", "metric", "value")],
     ("parts[0]", "exactly the fields")),
    (lambda c: c.update(kind="apart", lower=3, higher=["base"], metrics=["HSR"]) or [c.pop(k) for k in ("at", "metric", "value")],
     ("lower", "list of labels")),
])
def test_a_bad_criterion_is_one_line_error(thesis_raw, change, words):
    raw = copy.deepcopy(thesis_raw)
    i = [c["id"] for c in raw["reference"]["criteria"]].index("xi0_insecure")  # a 'below' criterion
    change(raw["reference"]["criteria"][i])
    with pytest.raises(ScenarioError) as e:
        scenario_from_dict(raw)
    assert "\n" not in str(e.value) and f"criteria[{i}]" in str(e.value)
    for w in words:
        assert w in str(e.value)


# -- the open choices of issue 15 --------------------------------------------------------------

def _valid(sc, code):
    return {sc.action_names[a] for a in sc.c.valid[code]}


def test_defaults_keep_the_constraints(thesis, enc):
    assert thesis.open.invalid_actions == "excluded" and thesis.open.always_valid_actions == ()
    assert "Rest" not in _valid(thesis, enc(thesis, "H"))


def test_always_valid_actions_drop_a_constraint_and_keep_the_effect(enc):
    sc = load_scenario(overrides={"always_valid_actions": ["Rest"]})
    code = enc(sc, "H")  # human near: Rest is forbidden by Table 3.3
    assert "Rest" in _valid(sc, code) and "Chat" in _valid(sc, code)
    assert sc.c.drive_delta[code][sc.action_index("Rest")][2] == -20.0
    assert "Attach" not in _valid(sc, code)


def test_no_effect_makes_every_action_selectable_and_an_invalid_one_idle(enc):
    sc = load_scenario(overrides={"invalid_actions": "no_effect"})
    code = enc(sc, "R")  # charger far, human far: Attach and Chat are invalid there
    assert _valid(sc, code) == set(sc.action_names)
    for a in ("Attach", "Chat"):
        i = sc.action_index(a)
        assert sc.c.next_code[code][i] == code and set(sc.c.drive_delta[code][i]) == {0.0}
    assert sc.c.drive_delta[code][sc.action_index("Rest")][2] == -20.0  # a valid one still acts


@pytest.mark.parametrize("override, words", [
    ({"invalid_actions": "ignored"}, ("invalid_actions", "excluded", "no_effect")),
    ({"always_valid_actions": ["Nap"]}, ("always_valid_actions", "action names")),
    ({"always_valid_actions": "Rest"}, ("always_valid_actions", "list")),
    ({"always_valid_actions": ["Rest", "Rest"]}, ("always_valid_actions", "distinct")),
    ({"time_increase": "later"}, ("time_increase", "after_action", "before_action")),
    ({"drive_growth": {"NAch": "always"}}, ("drive_growth", "serving_growth")),
    ({"drive_growth": {"NSoc": "sometimes"}}, ("drive_growth", "human_not_near", "robot_moved", "not_lowered")),
    ({"drive_growth": {"Mood": "always"}}, ("drive_growth", "NSoc, NRes, NEng")),
    ({"drive_growth": ["NSoc"]}, ("drive_growth", "must map")),
    ({"no_activated_motivation": "nobody"}, ("no_activated_motivation", "argmax", "none")),
    ({"ongoing_effects": "always"}, ("ongoing_effects", "actions", "every_tick")),  # issue 25's readings
    ({"ongoing_effects": True}, ("ongoing_effects",)),
    ({"activation_boundary": "below"}, ("activation_boundary", "eq_3_2", "above")),
])
def test_bad_new_open_choice_is_one_line_error(override, words):
    with pytest.raises(ScenarioError) as e:
        load_scenario(overrides=override)
    assert "\n" not in str(e.value)
    for w in words:
        assert w in str(e.value)


# -- the readings of issue 15's second part: time_increase, drive_growth, no_activated_motivation -------

def test_new_readings_default_to_the_old_behaviour(thesis):
    assert thesis.open.time_increase == "after_action"
    assert thesis.open.drive_growth == {}
    assert thesis.open.no_activated_motivation == "argmax"
    assert thesis.internal_states == thesis.motivation_names and thesis.none_state == -1


def _dyn(overrides, source="body"):
    from homeo_decision.drives import DriveDynamics
    return DriveDynamics(load_scenario(overrides=overrides), source)


def test_time_increase_order_matters_only_at_the_bounds(enc):
    """Rest at NRes 10 (rate 2, effect -20): action then time reads 2, time then action reads 0."""
    from homeo_sim.environment import SimEnvironment

    reads = {}
    for order in ("after_action", "before_action"):
        env = SimEnvironment(load_scenario(overrides={"time_increase": order}), seed=0)
        sc = env.sc
        env.world.code = enc(sc, "R")  # the human far: Rest is valid
        nres, neng = sc.drive_names.index("NRes"), sc.drive_names.index("NEng")
        env.body.values[nres], env.body.values[neng] = 10.0, 40.0
        env.step(sc.action_index("Rest"))
        reads[order] = (env.body.values[nres], env.body.values[neng])
    assert reads == {"after_action": (2.0, 42.0), "before_action": (0.0, 42.0)}


@pytest.mark.parametrize("reading, place, action, grows", [
    ("human_not_near", "H", "MoveToR", False),  # the human near when the action was taken
    ("human_not_near", "R", "Rest", True),
    ("robot_moved", "R", "MoveToH", True),
    ("robot_moved", "R", "MoveToR", False),  # already there: no move
    ("robot_moved", "R", "Rest", False),
    ("not_lowered", "R", "Rest", False),  # Rest lowers NRes
    ("not_lowered", "R", "MoveToH", True),
])
def test_drive_growth_readings(enc, reading, place, action, grows):
    dyn = _dyn({"drive_growth": {"NRes": reading}})
    sc = dyn.sc
    nres = sc.drive_names.index("NRes")
    assert (nres in dyn.still(enc(sc, place), sc.action_index(action))) is not grows
    assert dyn.still(enc(sc, place), sc.action_index(action)) == () or not grows


def test_drive_growth_applies_to_internal_drives_too(enc):
    from homeo_decision.drives import DriveModel

    sc = load_scenario(overrides={"drive_growth": {"NSoc": "human_not_near"}})
    m = DriveModel(sc)
    nsoc = sc.drive_names.index("NSoc")
    m.apply_time(still=m.still(enc(sc, "H"), sc.action_index("Chat")))
    assert m.values[nsoc] == 0.0  # near the human: no growth
    m.apply_time(still=m.still(enc(sc, "R"), sc.action_index("Rest")))
    assert m.values[nsoc] == 3.0


def test_no_activated_motivation_adds_an_internal_state():
    from homeo_decision.motivation import motivational_state
    from homeo_decision.objectq import ObjectQ

    sc = load_scenario(overrides={"no_activated_motivation": "none"})
    assert sc.internal_states == sc.motivation_names + ["none"] and sc.none_state == 4
    th = [d.threshold for d in sc.drives]
    assert motivational_state([0, 10, 10, 10], th, [0, 0, 0, 0], "first", sc.none_state)[1] == 4
    assert motivational_state([0, 10, 10, 10], th, [0, 0, 0, 0], "first")[1] == 0  # Eq 3.3's argmax
    assert motivational_state([5, 10, 10, 10], th, [0, 0, 0, 0], "first", sc.none_state)[1] == 0
    q, q0 = ObjectQ(sc), ObjectQ(load_scenario())
    assert len(q.q[0]) == len(q0.q[0]) * 5 // 4
    assert sc.fingerprint() != load_scenario().fingerprint()  # a saved table says which it is


def test_no_activated_motivation_none_runs_through_the_messages():
    from homeo_decision import codec
    import json

    from homeo_msgs_py.schemas import decode, encode

    sc = load_scenario(overrides={"no_activated_motivation": "none"})
    code = sc.c.with_intention[0][0]
    fields = codec.drives_fields(sc, (code, (0.0,) * 4, [0.0] * 4, sc.none_state), codec.world_state(sc, code), None, None)
    assert fields["m_dom"] == "none"
    fields = decode(encode("homeo/drives", 1, fields), codec.vocabulary(sc), "homeo/drives").fields
    json.dumps(fields)
    assert codec.perception_from_fields(sc, fields)[0][3] == sc.none_state




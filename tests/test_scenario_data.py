"""The scenario as data (issue #10, items 5-6): the split package, the second scenario, the optional
``rule_policy`` and ``reference`` blocks, the renamed open choices, and no thesis name in code."""

from __future__ import annotations

import io
import json
import subprocess
import sys
import tokenize
from pathlib import Path

import pytest

import homeo_decision.scenario as scenario_pkg
from homeo_decision.scenario import ScenarioError, load_scenario, scenario_from_dict
from homeo_decision.scenario import compile as sc_compile
from homeo_decision.scenario import load as sc_load
from homeo_decision.scenario import model as sc_model
from homeo_decision.scenarios import SCENARIO_DIR, default_scenario_path, shipped_scenarios

SRC = Path(__file__).resolve().parents[1] / "src"


def garden_raw() -> dict:
    return json.loads((SCENARIO_DIR / "garden.json").read_text())


def expect_error(raw, *words):
    with pytest.raises(ScenarioError) as e:
        scenario_from_dict(raw, source="test.json")
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith("test.json"), msg
    for w in words:
        assert w in msg, msg


# -- the split package ------------------------------------------------------------------------

def test_package_reexports_the_split_modules():
    assert scenario_pkg.load_scenario is sc_load.load_scenario
    assert scenario_pkg.scenario_from_dict is sc_load.scenario_from_dict
    from homeo_decision.scenario import open_choices

    assert scenario_pkg.OpenChoices is open_choices.OpenChoices
    assert scenario_pkg._compile is sc_compile._compile
    for name in ("Scenario", "DriveSpec", "ActionSpec", "IntentionSpec", "ObservationSpec", "Compiled", "ScenarioError",
                 "NONE_INTENTION", "NULL_OBJECT", "RELATIONS", "OBS_CHANNELS", "PRESENCE", "DISTANCES"):
        assert getattr(scenario_pkg, name) is getattr(sc_model, name), name


def test_every_name_imported_from_the_package_exists():
    # grep the importers (src, tests, tools) so a name dropped from __init__ fails here, not in a node
    names = set()
    for p in list(SRC.rglob("*.py")) + list((SRC.parent / "tests").glob("*.py")) + list((SRC.parent / "tools").glob("*.py")):
        for line in p.read_text().splitlines():
            line = line.strip()
            for prefix in ("from homeo_decision.scenario import ", "from .scenario import "):
                if line.startswith(prefix) and "(" not in line:
                    names |= {n.strip() for n in line[len(prefix):].split("#")[0].split(",")}
    assert {"Scenario", "load_scenario", "ScenarioError", "OBS_CHANNELS"} <= names
    missing = [n for n in names if n and not hasattr(scenario_pkg, n.split(" as ")[0])]
    assert not missing, missing


def test_loading_a_scenario_does_not_import_homeo_sim():
    code = ("import sys; from homeo_decision.scenario import load_scenario; load_scenario(); "
            "print(sorted(m for m in sys.modules if m.split('.')[0] == 'homeo_sim'))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"


def test_scenario_files_live_in_homeo_decision():
    assert default_scenario_path() == SCENARIO_DIR / "thesis.json"
    assert SCENARIO_DIR.parent.name == "homeo_decision"
    assert {"thesis", "garden"} <= set(shipped_scenarios())


def test_a_shipped_scenario_by_name():
    assert load_scenario("garden").name == "garden"
    with pytest.raises(ScenarioError, match="not found"):
        load_scenario("no_such_scenario")


@pytest.mark.parametrize("mutate, words", [
    (lambda r: r.pop("drives"), ("missing", "drives")),
    (lambda r: r["actions"].append(dict(r["actions"][0])), ("twice",)),
    (lambda r: r["intentions"][0].update(desired=["Fly"]), ("unknown action", "Fly")),
    (lambda r: r["objects"]["dock"].update(location="moon"), ("dock", "moon")),
    (lambda r: r["stimuli"][0].update(when={"weather": ["rain"]}), ("unknown variable", "weather")),
    (lambda r: r.update(version=2), ("version",)),
])
def test_the_split_loader_rejects_malformed_scenarios(mutate, words):
    raw = garden_raw()
    mutate(raw)
    expect_error(raw, *words)


# -- the second scenario ---------------------------------------------------------------------------

def test_garden_shares_no_name_with_the_thesis(thesis):
    g = load_scenario("garden")
    for attr in ("drive_names", "motivation_names", "action_names", "intention_names", "object_names"):
        common = set(getattr(g, attr)) & set(getattr(thesis, attr)) - {"none", "null"}
        assert not common, (attr, common)
    assert not set(g.locations) & set(thesis.locations)
    assert g.observations is not None and g.rule_policy is not None and g.reference is None
    assert len(g.drives) == 3 and g.drive_names[g.serving] == "Duty"


@pytest.mark.parametrize("intention", ["oracle", "bayes"])
def test_garden_runs(intention):
    from homeo_sim.runner import RunConfig, run_episode

    r = run_episode(RunConfig(iterations=300, seed=1, scenario="garden", intention=intention))
    assert set(r.metrics["CDA"]) == {"Duty", "Heat", "Power", "all"}
    assert 0.0 <= r.metrics["HSR"] <= 1.0 and 0.0 <= r.metrics["RSR"] <= 1.0


# -- renamed open choices ---------------------------------------------------------------------

@pytest.mark.parametrize("old", ["nach_growth", "leaving_charger_detaches", "human_leave_proposal"])
def test_old_open_choice_names_are_gone(thesis_raw, old):
    thesis_raw["open"][old] = thesis_raw["open"].get(old, "first")
    expect_error(thesis_raw, "unknown open choice", old)


def test_renamed_open_choices_keep_the_thesis_values(thesis):
    assert thesis.open.serving_growth == "unsatisfied"
    assert thesis.open.on_leave_effects is True
    assert thesis.open.human_proposal_choice == "random"


@pytest.mark.parametrize("value", ["first", "random", "MoveToR", "MoveToC", "LightOn"])
def test_human_proposal_choice_accepts_first_random_and_action_names(thesis_raw, value):
    thesis_raw["open"]["human_proposal_choice"] = value
    assert scenario_from_dict(thesis_raw).open.human_proposal_choice == value


@pytest.mark.parametrize("value", ["MoveToX", "last", 3, True, None])
def test_human_proposal_choice_rejects_anything_else(thesis_raw, value):
    thesis_raw["open"]["human_proposal_choice"] = value
    expect_error(thesis_raw, "open.human_proposal_choice", repr(value))


def test_human_proposal_choice_names_a_garden_action():
    raw = garden_raw()
    raw["open"]["human_proposal_choice"] = "MoveToR"  # a thesis action: not one of the garden's
    expect_error(raw, "human_proposal_choice", "GoShade")


@pytest.mark.parametrize("choice, expected", [("GoShed", "GoShed"), ("GoShade", "GoShade"), ("first", "GoShade"),
                                              ("Sprinkle", "GoShade")])  # not desired for 'away': the first
def test_named_proposal_is_preferred_when_desired(choice, expected):
    from homeo_sim.human import SimHuman

    sc = load_scenario("garden", overrides={"human_no_intention_prob": 0.0, "human_proposal_choice": choice})
    h = SimHuman(sc, seed=0)
    h.intention = sc.intention_names.index("away")
    r = h.respond(sc.action_index("Idle"))
    assert r.feedback == -1 and sc.action_names[r.proposal] == expected


# -- rule_policy block ------------------------------------------------------------------------

@pytest.mark.parametrize("rule, words", [
    ({"name": "x", "drive": "Mood", "actions": [{"action": "Idle"}]}, ("unknown drive", "Mood")),
    ({"name": "x", "actions": [{"action": "Fly"}]}, ("unknown action", "Fly")),
    ({"name": "x", "at": 5, "actions": [{"action": "Idle"}]}, ("need a 'drive'",)),
    ({"name": "x", "serve": True, "actions": [{"action": "Idle"}]}, ("serve",)),
    ({"name": "x"}, ("needs 'serve'",)),
    ({"name": "x", "drive": "Heat", "at": 120, "actions": [{"action": "Idle"}]}, ("at = 120",)),
    ({"name": "x", "drive": "Heat", "keep_while": {"when": {}}, "actions": [{"action": "Idle"}]}, ("keep_while",)),
    ({"name": "x", "actions": [{"action": "Idle", "when": {"dock.state": ["broken"]}}]}, ("broken",)),
    ({"name": "x", "priority": 1, "actions": [{"action": "Idle"}]}, ("unknown key", "priority")),
])
def test_rule_policy_validation(rule, words):
    raw = garden_raw()
    raw["rule_policy"]["rules"].append(rule)
    expect_error(raw, "rule_policy", *words)


def test_rule_at_defaults_to_the_drive_threshold(thesis):
    by_name = {r.name: r for r in thesis.rule_policy}
    assert by_name["charge"].at == 50 and by_name["chat"].at == 70 and by_name["rest"].at == 50
    assert by_name["charge"].keep_above == 10
    assert by_name["serve"].serve and by_name["idle"].drive is None


# -- reference block --------------------------------------------------------------------------

def test_thesis_reference_block(thesis):
    ref = thesis.reference
    assert ref.metrics["HSR"] == 0.82 and ref.metrics["CDA"]["NAch"] == 1.73 and ref.metrics["CEDA"]["all"] == 4.12
    assert ref.statements["pseudo_unaffected_drive"] == "NEng" and ref.statements["hsr_at_dod0"] == 0.6


@pytest.mark.parametrize("mutate, words", [
    (lambda ref: ref["metrics"].update(HSR=1.5), ("metrics.HSR",)),
    (lambda ref: ref["metrics"]["CDA"].update(NFun=3), ("unknown drive", "NFun")),
    (lambda ref: ref["statements"].update(pseudo_unaffected_drive="Power"), ("unknown drive", "Power")),
    (lambda ref: ref["statements"].pop("best_dod"), ("statements",)),
    (lambda ref: ref.pop("source"), ("source",)),
])
def test_reference_validation(thesis_raw, mutate, words):
    mutate(thesis_raw["reference"])
    expect_error(thesis_raw, "reference", *words)


def test_a_scenario_may_have_a_reference_without_statements():
    raw = garden_raw()
    raw["reference"] = {"source": "made up", "metrics": {"HSR": 0.5, "CDA": {"Duty": 3.0}}}
    sc = scenario_from_dict(raw)
    assert sc.reference.metrics["CDA"]["Duty"] == 3.0 and sc.reference.statements is None


# -- no thesis name in code -------------------------------------------------------------------

CODE = ["homeo_decision/scenario", "homeo_decision/baselines.py", "homeo_sim/report", "homeo_sim/sweep.py",
        "homeo_sim/cli.py", "homeo_sim/human.py"]


def test_no_thesis_name_in_code(thesis):
    names = set(thesis.drive_names) | set(thesis.motivation_names) | set(thesis.action_names) | set(thesis.objects)
    hits = []
    files = []
    for c in CODE:
        p = SRC / c
        files += sorted(p.glob("*.py")) if p.is_dir() else [p]
    assert len(files) >= 10
    for f in files:
        for tok in tokenize.generate_tokens(io.StringIO(f.read_text()).readline):
            if tok.type == tokenize.NAME and tok.string in names:
                hits.append((f.name, tok.start[0], tok.string))
            elif tok.type == tokenize.STRING:
                inner = tok.string.strip("rbfuRBFU").strip("'\"")
                if inner in names:
                    hits.append((f.name, tok.start[0], tok.string))
    assert not hits, hits
    assert not (SRC / "homeo_sim" / "thesis_values.py").exists()

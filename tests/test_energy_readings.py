"""Issue 25's readings of the energy drive and of the activation boundary (open choices ongoing_effects,
activation_boundary; the scenario's ongoing block): defaults as before, each reading by hand, bad values refused
on one line."""

from __future__ import annotations

import pytest

from homeo_decision.scenario import ScenarioError, load_scenario, scenario_from_dict


def test_issue_25_readings_default_to_the_old_behaviour(thesis_raw):
    """The declared defaults are the old reading: the ongoing block is read only under every_tick (the thesis
    scenario's own block chooses it since issue 25)."""
    thesis_raw["open"].pop("ongoing_effects")
    thesis_raw["open"].pop("activation_boundary", None)
    sc = scenario_from_dict(thesis_raw)
    assert sc.open.ongoing_effects == "actions" and sc.open.activation_boundary == "eq_3_2"
    assert sc.activation_thresholds == [d.threshold for d in sc.drives]
    del thesis_raw["ongoing"]  # the block alone changes no table
    bare = scenario_from_dict(thesis_raw)
    assert bare.c.drive_delta == sc.c.drive_delta and bare.c.next_code == sc.c.next_code
    thesis_raw["open"]["ongoing_effects"] = "every_tick"
    assert scenario_from_dict(thesis_raw).c.drive_delta == bare.c.drive_delta  # no block: nothing to apply


@pytest.mark.parametrize("status, action, actions, every_tick", [
    ("charging", "Play", 0.0, -20.0),      # a plugged robot playing music: charges only on every_tick
    ("charging", "Rest", 0.0, -20.0),
    ("charging", "MoveToC", 0.0, -20.0),   # already there: stays plugged
    ("charging", "Stay", -20.0, -20.0),    # Table 4.1's own -20, not twice
    ("charging", "Attach", -20.0, -20.0),  # idem
    ("charging", "Detach", 0.0, 0.0),      # the state ends with the tick
    ("charging", "MoveToH", 0.0, 0.0),     # leaving unplugs (on_leave)
    ("idle", "Attach", -20.0, -20.0),      # the state begins with the tick: Table 4.1's row alone
    ("idle", "Play", 0.0, 0.0),
])
def test_ongoing_effects_charge_every_tick_at_a_charging_charger(enc, status, action, actions, every_tick):
    for reading, want in (("actions", actions), ("every_tick", every_tick)):
        sc = load_scenario(overrides={"ongoing_effects": reading})
        code = enc(sc, "C", charger=status)
        assert sc.c.drive_delta[code][sc.action_index(action)][sc.drive_names.index("NEng")] == want, reading


def test_ongoing_charging_through_the_simulated_body(enc):
    """NEng 40 at a charging charger, the robot plays music: 40 + 2 (Table 4.2) = 42 under Table 4.1's rows,
    40 - 20 + 2 = 22 when a plugged robot charges whatever it does."""
    from homeo_sim.environment import SimEnvironment

    got = {}
    for reading in ("actions", "every_tick"):
        env = SimEnvironment(load_scenario(overrides={"ongoing_effects": reading}), seed=0)
        sc = env.sc
        env.world.code = enc(sc, "C", charger="charging")
        neng = sc.drive_names.index("NEng")
        env.body.values[neng] = 40.0
        env.step(sc.action_index("Play"))
        got[reading] = env.body.values[neng]
    assert got == {"actions": 42.0, "every_tick": 22.0}


def test_activation_boundary_at_the_threshold():
    """Eq 3.2 activates a drive at its threshold (d < at is the only zero case); 'above' (Definition 3:
    unsatisfied when d > at) does not. NAch 0 with an intention (+20) and NEng exactly 50 (+10 near the charger)."""
    from homeo_decision.motivation import motivational_state

    stim = [20.0, 0.0, 0.0, 10.0]
    for reading, want in (("eq_3_2", [20.0, 0.0, 0.0, 60.0]), ("above", [0.0, 0.0, 0.0, 0.0])):
        sc = load_scenario(overrides={"activation_boundary": reading})
        assert motivational_state([0.0, 69.0, 49.0, 50.0], sc.activation_thresholds, stim)[0] == want
        # one step above the threshold both readings agree
        assert motivational_state([0.5, 70.5, 49.0, 50.5], sc.activation_thresholds, stim)[0] == [20.5, 70.5, 0.0, 60.5]


@pytest.mark.parametrize("change, words", [
    (lambda r: r.__setitem__("ongoing", {}), ("ongoing must be a list",)),
    (lambda r: r["ongoing"][0].pop("drives"), ("ongoing[0]", "'when' and 'drives'")),
    (lambda r: r["ongoing"][0]["drives"].update(Mood=3), ("ongoing[0]", "unknown drive 'Mood'")),
    (lambda r: r["ongoing"][0]["drives"].update(NEng="-20"), ("ongoing[0].drives.NEng", "number")),
    (lambda r: r["ongoing"][0]["when"].update(charger=["x"]), ("ongoing[0].when", "unknown variable")),
])
def test_a_bad_ongoing_block_is_one_line_error(thesis_raw, change, words):
    change(thesis_raw)
    with pytest.raises(ScenarioError) as e:
        scenario_from_dict(thesis_raw)
    assert "\n" not in str(e.value)
    for w in words:
        assert w in str(e.value)

"""The thesis scenario's constraints (Table 3.3) and effects (Table 4.1); loader errors."""

from __future__ import annotations

import json

import pytest

from homeo_decision.scenario import ScenarioError, load_scenario, scenario_from_dict

DRIVES = ["NAch", "NSoc", "NRes", "NEng"]


def valid_names(sc, code):
    return {sc.action_names[a] for a in sc.c.valid[code]}


def delta(sc, code, action):
    return dict(zip(DRIVES, sc.c.drive_delta[code][sc.action_index(action)]))


def after(sc, code, action):
    return sc.decode(sc.c.next_code[code][sc.action_index(action)])


# -- the compiled world -----------------------------------------------------------------

def test_thesis_world_variables(thesis):
    # robot location 3 x human relation 3 x intention (none + 6) x charger 2 x player 2 x light 2
    assert thesis.n_codes == 3 * 3 * 7 * 2 * 2 * 2
    assert thesis.base_vars[:3] == ("robot.location", "human.relation", "intention")
    assert thesis.object_names == ["charger", "player", "light", "null"]


def test_toy_world_codes_by_hand(toy):
    # mixed radix over robot.location (H, B) x human.relation (near, far, absent) x intention
    # (none, on, come) x box.status (off, on): code = ((loc * 3 + rel) * 3 + intention) * 2 + status
    assert toy.n_codes == 2 * 3 * 3 * 2 == 36
    assert toy.encode({"robot.location": "B", "human.relation": "near", "intention": "come", "box.status": "on"}) \
        == ((1 * 3 + 0) * 3 + 2) * 2 + 1 == 23  # a person walked up to the robot at B (a robot only)
    # a presence stands for the located relation: at B the human (at H) is far
    assert toy.encode({"robot.location": "B", "human.presence": "present", "intention": "come", "box.status": "on"}) \
        == ((1 * 3 + 1) * 3 + 2) * 2 + 1 == 29
    assert toy.view(23)["human.presence"] == "present" and toy.view(23)["box.distance"] == "near"
    assert toy.c.hum[23] == 2 * 3 + 0  # S_hum = intention x relation (Eq 3.9): (come, near)
    assert toy.c.with_relation[23] == (23, 29, 35)
    assert toy.c.with_presence[23] == (29, 35)  # present where the simulation places the human, or absent


def test_presence_and_relation_must_agree(toy):
    for pres, rel in (("absent", "near"), ("absent", "far"), ("present", "absent")):
        with pytest.raises(ScenarioError, match="contradicts"):
            toy.encode({"robot.location": "H", "human.presence": pres, "human.relation": rel, "intention": "none",
                        "box.status": "off"})
    with pytest.raises(ScenarioError, match="human.presence"):
        toy.encode({"robot.location": "H", "human.presence": "gone", "intention": "none", "box.status": "off"})


def test_a_sensed_relation_is_the_worlds_wherever_the_robot_is(thesis):
    near_at_r = thesis.encode({"robot.location": "R", "human.relation": "near", "intention": "none",
                               **thesis.open.initial_objects})
    v = thesis.view(near_at_r)
    assert v["human.relation"] == "near" and v["human.presence"] == "present"
    assert "Chat" in valid_names(thesis, near_at_r) and "Rest" not in valid_names(thesis, near_at_r)  # Table 3.3
    # Table 3.2: the human is not absent (Social +10) and R is the resting place (Relaxative +10)
    assert dict(zip(thesis.motivation_names, thesis.c.stim[near_at_r])) == {
        "Serving": 0.0, "Social": 10.0, "Relaxative": 10.0, "Survival": 0.0}
    # the next world: staying keeps the person where they are; a move derives the relation from the locations
    assert after(thesis, near_at_r, "Chat")["human.relation"] == "near"
    assert after(thesis, near_at_r, "MoveToC")["human.relation"] == "far"
    assert after(thesis, near_at_r, "MoveToH")["human.relation"] == "near"
    absent_at_r = thesis.c.with_relation[near_at_r][2]
    assert after(thesis, absent_at_r, "MoveToH")["human.relation"] == "absent"


def test_the_simulation_reaches_exactly_the_located_worlds(thesis):
    """From the initial world, the simulation's moves (actions, the human coming and going, its
    intentions) reach the worlds whose relation is the one the locations give: 3 locations x
    (near-or-far as located, absent) x 7 intentions x 8 object states = 336, the old count."""
    c = thesis.c
    start = thesis.encode({"robot.location": thesis.open.initial_location, "human.presence": "present",
                           "intention": "none", **thesis.open.initial_objects})
    seen, todo = {start}, [start]
    while todo:
        code = todo.pop()
        for nxt in (*c.next_code[code], *c.with_presence[code], *c.with_intention[code]):
            if nxt not in seen:
                seen.add(nxt)
                todo.append(nxt)
    located = {code for code in range(thesis.n_codes) if thesis.view(code)["human.relation"] == thesis.located_relation(
        thesis.view(code)["robot.location"], thesis.view(code)["human.presence"])}
    assert seen == located and len(located) == 3 * 2 * 7 * 8


def test_encode_decode_round_trip(thesis):
    for code in range(thesis.n_codes):
        assert thesis.encode(thesis.decode(code)) == code


def test_relation_and_distance_derived_from_location(thesis, enc):
    assert thesis.view(enc(thesis, "H"))["human.relation"] == "near"
    assert thesis.view(enc(thesis, "C"))["human.relation"] == "far"
    assert thesis.view(enc(thesis, "H", presence="absent"))["human.relation"] == "absent"
    assert thesis.view(enc(thesis, "C"))["charger.distance"] == "near"
    assert thesis.view(enc(thesis, "R"))["charger.distance"] == "far"


# -- Table 3.3 constraints, over every world ------------------------------------------------

def test_attach_and_stay_only_when_charger_near(thesis):
    for code in range(thesis.n_codes):
        at_c = thesis.decode(code)["robot.location"] == "C"
        v = valid_names(thesis, code)
        assert ("Attach" in v) == at_c, thesis.decode(code)
        assert ("Stay" in v) == at_c, thesis.decode(code)


def test_chat_only_when_human_near(thesis):
    for code in range(thesis.n_codes):
        w = thesis.decode(code)
        assert ("Chat" in valid_names(thesis, code)) == (w["human.relation"] == "near"), w


def test_rest_only_when_human_not_near(thesis):
    for code in range(thesis.n_codes):
        w = thesis.decode(code)
        assert ("Rest" in valid_names(thesis, code)) == (w["human.relation"] != "near"), w


def test_unconstrained_actions_always_valid(thesis):
    free = {"MoveToC", "Detach", "Play", "Stop", "LightOn", "LightOff", "MoveToH", "MoveToR"}
    for code in range(thesis.n_codes):
        assert free <= valid_names(thesis, code)


def test_valid_at_human_location(thesis, enc):
    # robot at H, human present: Chat yes; Attach, Stay, Rest no
    assert valid_names(thesis, enc(thesis, "H")) == {
        "MoveToC", "Detach", "Play", "Stop", "LightOn", "LightOff", "Chat", "MoveToH", "MoveToR"}


# -- Table 4.1 effects ---------------------------------------------------------------------

def test_attach_starts_charging_and_lowers_neng(thesis, enc):
    code = enc(thesis, "C", charger="idle")
    assert after(thesis, code, "Attach")["charger.status"] == "charging"
    assert delta(thesis, code, "Attach") == {"NAch": 0, "NSoc": 0, "NRes": 0, "NEng": -20}


def test_stay_charges_only_when_charging(thesis, enc):
    assert delta(thesis, enc(thesis, "C", charger="charging"), "Stay")["NEng"] == -20
    assert delta(thesis, enc(thesis, "C", charger="idle"), "Stay")["NEng"] == 0


def test_stay_changes_nothing_in_the_world(thesis, enc):
    code = enc(thesis, "C", charger="charging")
    assert thesis.c.next_code[code][thesis.action_index("Stay")] == code


def test_detach_sets_idle(thesis, enc):
    assert after(thesis, enc(thesis, "C", charger="charging"), "Detach")["charger.status"] == "idle"


def test_chat_lowers_nsoc(thesis, enc):
    assert delta(thesis, enc(thesis, "H"), "Chat") == {"NAch": 0, "NSoc": -30, "NRes": 0, "NEng": 0}


def test_rest_lowers_nres(thesis, enc):
    assert delta(thesis, enc(thesis, "R"), "Rest") == {"NAch": 0, "NSoc": 0, "NRes": -20, "NEng": 0}


@pytest.mark.parametrize("action, var, value", [
    ("Play", "player.status", "playing"), ("Stop", "player.status", "idle"),
    ("LightOn", "light.status", "on"), ("LightOff", "light.status", "off"),
    ("MoveToH", "robot.location", "H"), ("MoveToR", "robot.location", "R"), ("MoveToC", "robot.location", "C"),
])
def test_set_effects(thesis, enc, action, var, value):
    # start from the opposite state for each variable
    code = enc(thesis, "C" if action != "MoveToC" else "H", player="playing" if action == "Stop" else "idle",
               light="on" if action == "LightOff" else "off")
    assert after(thesis, code, action)[var] == value


def test_moves_have_no_drive_effect(thesis, enc):
    for a in ("MoveToC", "MoveToH", "MoveToR", "Play", "LightOn"):
        assert set(delta(thesis, enc(thesis, "R"), a).values()) == {0.0}


def test_on_leave_effects_when_open_choice_true(thesis, enc):
    assert thesis.open.on_leave_effects is True
    code = enc(thesis, "C", charger="charging")
    for move in ("MoveToH", "MoveToR"):
        assert after(thesis, code, move)["charger.status"] == "idle", move


def test_leaving_charger_keeps_charging_when_open_choice_false(enc):
    sc = load_scenario(overrides={"on_leave_effects": False})
    code = enc(sc, "C", charger="charging")
    assert after(sc, code, "MoveToH")["charger.status"] == "charging"


def test_on_leave_mechanism_detaches_when_declared(thesis_raw, enc):
    # the mechanism works when the object declares what leaving does
    thesis_raw["objects"]["charger"]["on_leave"] = {"status": "idle"}
    sc = scenario_from_dict(thesis_raw)
    code = enc(sc, "C", charger="charging")
    assert after(sc, code, "MoveToR")["charger.status"] == "idle"
    assert after(sc, code, "MoveToC")["charger.status"] == "charging"  # not leaving: stays attached
    sc_off = scenario_from_dict(thesis_raw, overrides={"on_leave_effects": False})
    assert after(sc_off, code, "MoveToR")["charger.status"] == "charging"


def test_intentions_reasonable_per_table_4_3(thesis, enc):
    names = thesis.intention_names
    near_idle_off = {names[i] for i in thesis.c.reasonable[enc(thesis, "H")]}
    assert near_idle_off == {"light", "music", "leave"}
    far_playing_on = {names[i] for i in thesis.c.reasonable[enc(thesis, "R", player="playing", light="on")]}
    assert far_playing_on == {"no_light", "no_music", "come"}


# -- loader errors ----------------------------------------------------------------------------

def expect_error(raw, *words):
    with pytest.raises(ScenarioError) as ei:
        scenario_from_dict(raw)
    for w in words:
        assert w in str(ei.value), str(ei.value)


def test_missing_file(tmp_path):
    path = tmp_path / "nope.json"
    with pytest.raises(ScenarioError, match="not found") as ei:
        load_scenario(path)
    assert "nope.json" in str(ei.value)


def test_malformed_json(tmp_path):
    path = tmp_path / "bad.json"
    path.write_text('{"schema": "homeo-scenario", "version": 1,')
    with pytest.raises(ScenarioError, match="corrupt scenario .not JSON: .* at line 1"):
        load_scenario(path)


def test_binary_file_is_scenario_error(tmp_path):
    path = tmp_path / "bin.json"
    path.write_bytes(b"\xff\xfe\x00\x01garbage")
    with pytest.raises(ScenarioError):
        load_scenario(path)


def test_not_an_object():
    expect_error([1, 2], "JSON object")


def test_wrong_schema(thesis_raw):
    thesis_raw["schema"] = "something-else"
    expect_error(thesis_raw, "schema")


def test_wrong_version(thesis_raw):
    thesis_raw["version"] = 2
    expect_error(thesis_raw, "version", "2")


def test_action_targets_unknown_object(thesis_raw):
    thesis_raw["actions"][0]["object"] = "fridge"
    expect_error(thesis_raw, "unknown object", "fridge", "MoveToC")


def test_condition_on_unknown_variable(thesis_raw):
    thesis_raw["actions"][1]["requires"] = {"charger.colour": ["red"]}
    expect_error(thesis_raw, "unknown variable", "charger.colour")


def test_condition_with_unknown_value(thesis_raw):
    thesis_raw["stimuli"][3]["when"] = {"charger.distance": ["close"]}
    expect_error(thesis_raw, "close")


def test_unknown_open_choice(thesis_raw):
    thesis_raw["open"]["human_mood"] = "grumpy"
    expect_error(thesis_raw, "unknown open choice", "human_mood")


def test_unknown_open_choice_via_override(thesis_raw):
    with pytest.raises(ScenarioError, match="human_mood"):
        scenario_from_dict(thesis_raw, overrides={"human_mood": 1})


@pytest.mark.parametrize("key, value", [("human_no_intention_prob", 1.5), ("human_leave_prob", -0.1),
                                        ("initial_q", 1e9), ("serving_growth", "sometimes"), ("tie_break", "random")])
def test_out_of_range_open_value(thesis_raw, key, value):
    thesis_raw["open"][key] = value
    expect_error(thesis_raw, f"open.{key}", repr(value))


def test_initial_drive_out_of_range(thesis_raw):
    thesis_raw["open"]["initial_drives"]["NEng"] = 120
    expect_error(thesis_raw, "initial_drives.NEng")


def test_learning_dod_out_of_range(thesis_raw):
    thesis_raw["learning"]["dod"] = 1.5
    expect_error(thesis_raw, "learning.dod")


def test_intention_desires_unknown_action(thesis_raw):
    thesis_raw["intentions"][0]["desired"] = ["Dance"]
    expect_error(thesis_raw, "unknown action", "Dance")


def test_duplicate_action(thesis_raw):
    thesis_raw["actions"].append(dict(thesis_raw["actions"][0]))
    expect_error(thesis_raw, "MoveToC", "twice")


def test_effect_changes_unknown_drive(thesis_raw):
    thesis_raw["actions"][8]["effects"] = [{"drives": {"NFun": -5}}]
    expect_error(thesis_raw, "unknown drive", "NFun")


def test_load_file_error_names_the_file(tmp_path, thesis_raw):
    thesis_raw["actions"][0]["object"] = "fridge"
    path = tmp_path / "mine.json"
    path.write_text(json.dumps(thesis_raw))
    with pytest.raises(ScenarioError, match="mine.json"):
        load_scenario(path)


# Well-formed JSON with a value of the wrong JSON type: the loader should say so as a
# ScenarioError (the CLI turns only ScenarioError into a one-line error).
@pytest.mark.parametrize("mutate", [
    pytest.param(lambda r: r["actions"].append(42), id="action-not-object"),
    pytest.param(lambda r: r["intentions"].append(42), id="intention-not-object"),
    pytest.param(lambda r: r.__setitem__("feedback", 5), id="feedback-not-object"),
    pytest.param(lambda r: r["feedback"].__setitem__("value", "ten"), id="feedback-value-string"),
    pytest.param(lambda r: r.__setitem__("open", 5), id="open-not-object"),
    pytest.param(lambda r: r["learning"]["schedule"][0].__setitem__("alpha", "x"), id="alpha-string"),
    pytest.param(lambda r: r["objects"]["charger"].__setitem__("on_leave", ["idle"]), id="on_leave-list"),
    pytest.param(lambda r: r["actions"][0]["effects"][0].__setitem__("set", ["C"]), id="set-list"),
])
def test_wrong_json_types_are_scenario_errors(thesis_raw, mutate):
    mutate(thesis_raw)
    with pytest.raises(ScenarioError):
        scenario_from_dict(thesis_raw)

"""The message contract (homeo_msgs_py): schemas, validation reasons, the tick join."""

from __future__ import annotations

import json

import pytest

from hypothesis import given, settings
from hypothesis import strategies as st

from homeo_decision.codec import vocabulary, world_code, world_state
from homeo_decision.scenario import ScenarioError
from homeo_msgs_py.lockstep import TickJoin
from homeo_msgs_py.schemas import Message, Rejected, decode, encode
from homeo_msgs_py.diagnostics import RejectLog
from homeo_msgs_py.graph import TOPICS


@pytest.fixture(scope="module")
def voc(thesis):
    return vocabulary(thesis)


def _world(thesis) -> dict:
    w = world_state(thesis, thesis.encode({"robot.location": "R", "human.presence": "present", "intention": "none",
                                            "charger.status": "idle", "player.status": "idle",
                                            "light.status": "off"}))
    w["body"] = {"NRes": 12.0, "NEng": 40.0, "battery_percent": 60}
    return w


def test_round_trip_keeps_fields_and_envelope(thesis, voc):
    text = encode("homeo/world", 7, _world(thesis), run=2, stamp=123.5)
    m = decode(text, voc, "homeo/world")
    assert (m.schema, m.run, m.tick, m.stamp) == ("homeo/world", 2, 7, 123.5)
    assert m.fields["human"] == {"presence": "present", "relation": "far"}  # robot at R, human at H
    assert m.fields["body"]["NEng"] == 40.0 and m.fields["body"]["battery_percent"] == 60.0


def test_floats_survive_json_exactly(voc):
    x = 0.1 + 0.2  # not representable in short decimal form
    text = encode("homeo/action", 0, {"action": "Chat", "tau": x})
    assert decode(text, voc).fields["tau"] == x


def _action(**over):
    obj = {"schema": "homeo/action", "version": 1, "run": 0, "tick": 3, "stamp": 1.0, "action": "Chat"}
    obj.update(over)
    return json.dumps(obj)


@pytest.mark.parametrize("text, reason", [  # each refusal says what and where, in msgspec's words
    ("not json {", "not JSON"),
    ("[1, 2]", "not a JSON object"),
    (_action(schema="homeo/nope"), "unknown schema"),
    (_action(version=2), "version 2"),
    (_action(action="Dance"), "Invalid enum value 'Dance' - at `$.action`"),
    (_action(tick=-1), "Expected `int` >= 0 - at `$.tick`"),
    (_action(tick="3"), "Expected `int`, got `str` - at `$.tick`"),
    (_action(tau=float("inf")), "not JSON"),  # Infinity is not JSON
    (_action(tau=1e308 * 10 if False else 1.0).replace("1.0}", "1e400}"), "Number out of range - at `$.tau`"),
    (_action(tau=10 ** 400), "Number out of range - at `$.tau`"),
    (_action(schema=[]), "unknown schema"),
    (_action(schema={}), "unknown schema"),
    ('{"\\ud800": 1}', "not JSON"),  # a lone surrogate
    (_action(extra=1), "Object contains unknown field `extra`"),
    (json.dumps({"schema": "homeo/action", "version": 1, "run": 0, "tick": 0, "stamp": 1.0}),
     "Object missing required field `action`"),
])
def test_bad_messages_are_rejected_with_a_reason(voc, text, reason):
    with pytest.raises(Rejected) as exc:
        decode(text, voc, "homeo/action")
    assert reason in str(exc.value)


def test_wrong_schema_on_a_topic(voc):
    with pytest.raises(Rejected, match="on a topic that carries 'homeo/drives'"):
        decode(_action(), voc, "homeo/drives")


def test_scenario_values_are_checked(thesis, voc):
    w = _world(thesis)
    w["objects"]["light"]["status"] = "dim"
    with pytest.raises(Rejected, match=r"Invalid enum value 'dim' - at `\$.objects.light.status`"):
        decode(encode("homeo/world", 0, w), voc)
    w = _world(thesis)
    w["body"]["NEng"] = 140.0
    with pytest.raises(Rejected, match=r"body.NEng = 140.0 is outside \[0, 100\]"):
        decode(encode("homeo/world", 0, w), voc)
    with pytest.raises(Rejected, match="Invalid enum value 'dance' - at `\\$.intention`"):
        decode(encode("homeo/intention", 0, {"intention": "dance", "posterior": {}, "mode": "oracle"}), voc)
    with pytest.raises(Rejected, match="sum to 0.500000"):
        decode(encode("homeo/intention", 0, {"intention": "come", "posterior": {"come": 0.5}, "mode": "oracle"}), voc)
    with pytest.raises(Rejected, match=r"Invalid enum value 2 - at `\$.feedback`"):
        decode(encode("homeo/outcome", 0, {"action": None, "feedback": 2, "proposal": None,
                                           "clarified_intention": None}), voc)


PRESENCES, RELATIONS = ("present", "absent"), ("near", "far", "absent")
HUMAN_VALUES = st.one_of(st.sampled_from(PRESENCES + RELATIONS), st.text(max_size=8), st.none(), st.integers(),
                         st.booleans(), st.lists(st.text(max_size=3), max_size=2))


@settings(max_examples=300, deadline=None)
@given(HUMAN_VALUES, HUMAN_VALUES, st.sampled_from(["homeo/world", "homeo/drives"]))
def test_a_world_whose_presence_contradicts_its_relation_is_refused(thesis, voc, presence, relation, schema):
    """homeo/world and homeo/drives' world carry both; they must agree (absent iff absent), so a world
    node cannot say "near" and "absent" at once; the world code is then the relation's."""
    w = _world(thesis)
    w["human"] = {"presence": presence, "relation": relation}
    fields = w if schema == "homeo/world" else {
        "drives": dict.fromkeys(thesis.drive_names, 0.0), "stimuli": dict.fromkeys(thesis.motivation_names, 0.0),
        "intensities": dict.fromkeys(thesis.motivation_names, 0.0), "m_dom": thesis.motivation_names[0],
        "intention": "none", "world": {k: w[k] for k in ("robot", "objects", "human")}}
    valid = presence in PRESENCES and relation in RELATIONS and (presence == "absent") == (relation == "absent")
    if not valid:
        with pytest.raises(Rejected) as e:
            decode(encode(schema, 0, fields), voc, schema)
        assert "\n" not in str(e.value)
        return
    m = decode(encode(schema, 0, fields), voc, schema)
    world = m.fields if schema == "homeo/world" else m.fields["world"]
    code = world_code(thesis, world)
    assert thesis.view(code)["human.relation"] == relation and thesis.view(code)["robot.location"] == "R"


def test_a_contradiction_names_both_values(thesis, voc):
    w = _world(thesis)
    w["human"] = {"presence": "absent", "relation": "near"}
    with pytest.raises(Rejected, match="presence 'absent' contradicts relation 'near' - at `\\$.human`"):
        decode(encode("homeo/world", 0, w), voc)
    with pytest.raises(ScenarioError, match="contradicts"):  # the codec refuses it too (an in-process world)
        world_code(thesis, w)


def test_every_topic_has_a_schema():
    from homeo_msgs_py.schemas import SCHEMAS

    assert {t.schema for t in TOPICS.values()} <= set(SCHEMAS)


def _m(tick, run=0):
    return Message("x", run, tick, 0.0, {})


def test_join_waits_for_every_input_in_any_order():
    j = TickJoin({"world": 0, "intention": 0, "outcome": -1})
    assert j.put("intention", _m(0)) == []
    done = j.put("world", _m(0))  # tick 0 needs no outcome
    assert [k for k, _ in done] == [0]
    assert j.put("world", _m(1)) == []
    assert j.put("outcome", _m(0)) == []  # outcome of tick 0 belongs to tick 1
    done = j.put("intention", _m(1))
    assert [k for k, _ in done] == [1] and set(done[0][1]) == {"world", "intention", "outcome"}


def test_join_rejects_stale_future_and_duplicate_ticks_and_follows_a_new_run():
    j = TickJoin({"world": 0})
    j.put("world", _m(0))
    with pytest.raises(Rejected, match="stale tick 0"):
        j.put("world", _m(0))
    with pytest.raises(Rejected, match="ahead of the run"):
        j.put("world", _m(50))
    j2 = TickJoin({"world": 0, "intention": 0})
    j2.put("world", _m(0))
    assert j2.put("world", _m(0)) == []  # an exact repeat (a resent tick) is a no-op
    with pytest.raises(Rejected, match="a different world for tick 0"):
        j2.put("world", Message("x", 0, 0, 0.0, {"other": 1}))
    # a reset of the simulation: run 1 starts again at tick 0
    assert [k for k, _ in j.put("world", _m(0, run=1))] == [0]
    with pytest.raises(Rejected, match="stale run 0"):
        j.put("world", _m(1, run=0))


def test_join_takes_a_new_run_only_at_its_first_tick():
    j = TickJoin({"world": 0})
    j.put("world", _m(0))
    for run, tick in ((1, 5), (2, 0), (10**12, 0)):  # not the next run's start: refused, nothing changes
        with pytest.raises(Rejected, match="not the start of the next run"):
            j.put("world", _m(tick, run=run))
    assert (j.run, j.expected) == (0, 1)
    assert [k for k, _ in j.put("world", _m(1))] == [1]  # the real run goes on


def test_a_fresh_join_takes_the_run_where_it_is():
    j = TickJoin({"world": 0, "outcome": -1})  # a node restarted mid-run
    assert j.put("world", _m(40, run=3)) == []
    assert [k for k, _ in j.put("outcome", _m(39, run=3))] == [40]


def test_a_tick_whose_input_was_lost_is_skipped_once_a_later_tick_is_whole():
    j = TickJoin({"world": 0, "intention": 0})
    j.put("intention", _m(0))  # world(0) is lost on the way
    assert j.put("world", _m(1)) == []
    done = j.put("intention", _m(1))
    assert [k for k, _ in done] == [1] and j.skipped == 1 and j.expected == 2


def test_reject_log_reports_counts_and_last_reason():
    log = RejectLog("homeo_x")
    assert log.status()["level"] == 0
    log.reject("/homeo/action", "not JSON")
    log.reject("/homeo/action", "unknown action 'Dance'")
    st = log.status()
    assert st["level"] == 1 and "dropped 2 bad messages" in st["message"]
    assert st["values"]["rejected /homeo/action"] == "2"
    assert st["values"]["last reason /homeo/action"] == "unknown action 'Dance'"

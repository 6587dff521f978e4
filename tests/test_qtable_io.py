"""Q-tables on disk: round trip, compatibility checks, added objects, corrupt files."""

from __future__ import annotations

import copy
import json

import pytest

from homeo_decision import qtable_io
from homeo_decision.objectq import ObjectQ
from homeo_decision.qtable_io import QTableError
from homeo_decision.scenario import scenario_from_dict


def filled(sc) -> ObjectQ:
    """An ObjectQ whose every entry is distinct: value = object*10000 + row*10 + column + 0.125."""
    q = ObjectQ(sc)
    for o, table in enumerate(q.q):
        for r, row in enumerate(table):
            for j in range(len(row)):
                row[j] = o * 10000 + r * 10 + j + 0.125
    return q


def with_lamp(raw: dict) -> dict:
    """The toy plus an unlocated ``lamp`` object with two actions."""
    raw["objects"]["lamp"] = {"variables": {"status": ["off", "on"]}}
    raw["actions"] += [{"name": "LampOn", "object": "lamp", "effects": [{"set": {"lamp.status": "on"}}]},
                       {"name": "LampOff", "object": "lamp", "effects": [{"set": {"lamp.status": "off"}}]}]
    return raw


@pytest.fixture
def saved(tmp_path, toy):
    q = filled(toy)
    path = tmp_path / "q.json"
    qtable_io.save(q, path, meta={"note": "test"})
    return q, path


def test_round_trip_preserves_every_value(toy, saved):
    q, path = saved
    q2 = ObjectQ(toy)
    report = qtable_io.load(q2, path)
    assert q2.q == q.q
    assert report.loaded == ["box", "null"] and report.new == [] and report.dropped == []


def test_round_trip_thesis_scenario(tmp_path, thesis):
    q = filled(thesis)
    qtable_io.save(q, tmp_path / "t.json")
    q2 = ObjectQ(thesis)
    qtable_io.load(q2, tmp_path / "t.json")
    assert q2.q == q.q


def test_file_records_schema_and_labels(saved):
    _, path = saved
    raw = json.loads(path.read_text())
    assert raw["schema"] == "homeo-qtable" and raw["version"] == 1
    assert raw["meta"] == {"note": "test"}
    # row 0 of box: Serving | none | near | box near/off ; TurnOn is column 0 -> 0*10000 + 0 + 0 + 0.125
    assert raw["tables"]["box"]["Serving|none|near|near/off"]["TurnOn"] == 0.125


def test_different_intentions_rejected(toy_raw, saved):
    _, path = saved
    raw = toy_raw()
    raw["intentions"].append({"name": "off", "desired": ["TurnOff"]})
    q = ObjectQ(scenario_from_dict(raw))
    with pytest.raises(QTableError, match="intentions"):
        qtable_io.load(q, path)


def test_object_with_other_actions_rejected(toy_raw, saved):
    _, path = saved
    raw = toy_raw()
    raw["actions"].append({"name": "Kick", "object": "box"})
    q = ObjectQ(scenario_from_dict(raw))
    with pytest.raises(QTableError, match="box"):
        qtable_io.load(q, path)


def test_object_with_other_states_rejected(toy_raw, saved):
    _, path = saved
    raw = toy_raw()
    raw["objects"]["box"]["variables"]["status"] = ["off", "on", "broken"]
    q = ObjectQ(scenario_from_dict(raw))
    with pytest.raises(QTableError, match="box"):
        qtable_io.load(q, path)


def test_added_object_keeps_others_and_starts_fresh(toy_raw, saved):
    q_old, path = saved
    raw = with_lamp(toy_raw())
    raw["open"]["initial_q"] = 0.5
    sc = scenario_from_dict(raw)
    q = ObjectQ(sc)
    report = qtable_io.load(q, path)
    assert sc.object_names == ["box", "lamp", "null"]
    assert report.new == ["lamp"]
    assert sorted(report.loaded) == ["box", "null"]
    assert q.q[0] == q_old.q[0]  # box
    assert q.q[2] == q_old.q[1]  # null
    assert {v for row in q.q[1] for v in row} == {0.5}  # lamp at the initial value


def test_removed_object_is_dropped(tmp_path, toy_raw, toy):
    big = scenario_from_dict(with_lamp(toy_raw()))
    q_big = filled(big)
    qtable_io.save(q_big, tmp_path / "big.json")
    q = ObjectQ(toy)
    report = qtable_io.load(q, tmp_path / "big.json")
    assert report.dropped == ["lamp"]
    assert q.q[0] == q_big.q[0] and q.q[1] == q_big.q[2]


def write(tmp_path, text: str):
    p = tmp_path / "corrupt.json"
    p.write_text(text)
    return p


def corrupt_variant(saved, edit):
    _, path = saved
    raw = json.loads(path.read_text())
    edit(raw)
    return json.dumps(raw)


def _set_value(raw, value):
    raw["tables"]["box"]["Serving|none|near|near/off"]["TurnOn"] = value


@pytest.mark.parametrize("edit, words", [
    (lambda r: r.pop("tables"), "corrupt"),
    (lambda r: r["scenario"].pop("layout"), "corrupt"),
    (lambda r: r["tables"].pop("box"), "box"),
    (lambda r: r["tables"]["box"].pop("Serving|none|near|near/off"), "Serving|none|near|near/off"),
    (lambda r: _set_value(r, "high"), "non-numeric"),
    (lambda r: _set_value(r, None), "non-numeric"),
    (lambda r: _set_value(r, True), "non-numeric"),
    (lambda r: r.__setitem__("schema", "homeo-scenario"), "schema"),
    (lambda r: r.__setitem__("version", 7), "version"),
], ids=["no-tables", "no-layout", "no-object-values", "missing-state", "string-value", "null-value",
        "bool-value", "wrong-schema", "wrong-version"])
def test_corrupt_tables(tmp_path, toy, saved, edit, words):
    path = write(tmp_path, corrupt_variant(saved, edit))
    q = ObjectQ(toy)
    with pytest.raises(QTableError) as ei:
        qtable_io.load(q, path)
    assert words in str(ei.value)


def test_nan_value_rejected(tmp_path, toy, saved):
    text = corrupt_variant(saved, lambda r: _set_value(r, 1.0)).replace(
        '"TurnOn": 1.0', '"TurnOn": NaN', 1)
    assert "NaN" in text
    with pytest.raises(QTableError, match="non-numeric"):
        qtable_io.load(ObjectQ(toy), write(tmp_path, text))


@pytest.mark.parametrize("text", ["not json at all", "", "[1, 2, 3]", '"a string"', "{"])
def test_not_a_table(tmp_path, toy, text):
    with pytest.raises(QTableError):
        qtable_io.load(ObjectQ(toy), write(tmp_path, text))


def test_binary_garbage(tmp_path, toy):
    p = tmp_path / "bin.json"
    p.write_bytes(b"\xff\xfe\x00\x01")
    with pytest.raises(QTableError):
        qtable_io.load(ObjectQ(toy), p)


def test_missing_file(tmp_path, toy):
    with pytest.raises(QTableError, match="not found"):
        qtable_io.load(ObjectQ(toy), tmp_path / "none.json")


def test_failed_load_leaves_table_untouched(tmp_path, toy, saved):
    # box loads fine, then null is corrupt: nothing may have been copied in
    text = corrupt_variant(saved, lambda r: r["tables"]["null"].pop("Serving|none|near|-"))
    q = ObjectQ(toy)
    fresh = copy.deepcopy(q.q)
    with pytest.raises(QTableError):
        qtable_io.load(q, write(tmp_path, text))
    assert q.q == fresh

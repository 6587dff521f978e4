"""Q-tables on disk: round trip, compatibility checks, added objects, corrupt files."""

from __future__ import annotations

import copy
import json

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

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


# -- a decision checkpoint is a Q-table too (issue 23: --load-q of out/checkpoints/sim/homeo_decision.json) --
def _trained_core(sc, ticks: int = 200):
    from homeo_sim.runner import RunConfig, Simulation

    sim = Simulation(sc, RunConfig(iterations=ticks, seed=4))
    sim.run(ticks)
    return sim.policy


def test_a_decision_checkpoint_loads_as_its_q_table(tmp_path, toy):
    from homeo_decision import checkpoint

    core = _trained_core(toy)
    path = tmp_path / "homeo_decision.json"
    checkpoint.save(path, checkpoint.decision_checkpoint(core, 200, 0, "s1"))
    q = ObjectQ(toy)
    rep = checkpoint.load_table(q, path)
    assert q.q == core.q.q and rep.loaded and not rep.dropped
    table = tmp_path / "q.json"
    qtable_io.save(core.q, table)
    q2 = ObjectQ(toy)
    checkpoint.load_table(q2, table)  # a Q-table file as ever
    assert q2.q == core.q.q


def test_another_nodes_checkpoint_or_a_broken_one_is_refused_in_one_line(tmp_path, toy):
    from homeo_decision import checkpoint

    path = tmp_path / "homeo_intention.json"
    checkpoint.save(path, checkpoint.envelope("homeo_intention", 5, 0, 0, {}, None, {"model": 1}))
    with pytest.raises(QTableError, match="not of homeo_decision: it holds no Q-table") as exc:
        checkpoint.load_table(ObjectQ(toy), path)
    assert "\n" not in str(exc.value)
    bad = json.loads(path.read_text())
    bad.update(node="homeo_decision", state={"schema": "nope"})
    path.write_text(json.dumps(bad))
    with pytest.raises(QTableError, match="not a Q-table file"):
        checkpoint.load_table(ObjectQ(toy), path)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(doc=st.recursive(st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False) | st.text(max_size=8),
                        lambda inner: st.lists(inner, max_size=3) | st.dictionaries(
                            st.sampled_from(["schema", "version", "node", "ticks", "tick_offset", "run", "params",
                                             "state", "x"]), inner, max_size=6), max_leaves=15),
       envelope=st.booleans())
def test_any_file_loads_as_a_table_or_is_a_one_line_refusal(tmp_path, toy, doc, envelope):
    """Whatever a --load-q file holds (a checkpoint envelope around it, or not): a table, or QTableError."""
    from homeo_decision import checkpoint

    if envelope and isinstance(doc, dict):
        doc = dict(doc, schema=checkpoint.SCHEMA)
    path = tmp_path / "any.json"
    path.write_text(json.dumps(doc))
    try:
        checkpoint.load_table(ObjectQ(toy), path)
    except QTableError as exc:
        assert str(exc) and "\n" not in str(exc)


def test_the_commands_take_a_decision_checkpoint_for_load_q(tmp_path, thesis):
    """``homeo-sim run --load-q`` and ``homeo-replay --policy`` accept the decision node's checkpoint (what
    a user reaches for after a long graph run), as a Q-table file."""
    import subprocess
    import sys

    from homeo_decision import checkpoint

    path = tmp_path / "homeo_decision.json"
    checkpoint.save(path, checkpoint.decision_checkpoint(_trained_core(thesis), 200, 0, "s1"))
    r = subprocess.run([sys.executable, "-m", "homeo_sim.cli", "run", "--iterations", "100", "--json", "--quiet",
                        "--load-q", str(path)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and json.loads(r.stdout)["iterations"] == 100, r.stderr


@pytest.mark.ros
def test_the_graph_starts_from_a_decision_checkpoint(tmp_path, thesis):
    import subprocess
    import sys

    from rosgraph import fresh_domain

    from homeo_decision import checkpoint
    from homeo_launch.processes import graph_env

    path = tmp_path / "elsewhere" / "homeo_decision.json"  # outside the data directory: the user's own path
    path.parent.mkdir()
    checkpoint.save(path, checkpoint.decision_checkpoint(_trained_core(thesis), 200, 0, "s1"))
    r = subprocess.run([sys.executable, "-m", "homeo_launch.cli", "sim", "--iterations", "60", "--json", "--quiet",
                        "--load-q", str(path), "--data-dir", str(tmp_path / "out"), "--intention", "oracle"],
                       capture_output=True, text=True, timeout=240, env=graph_env(fresh_domain()))
    assert r.returncode == 0 and json.loads(r.stdout)["iterations"] == 60, r.stderr[-2000:]

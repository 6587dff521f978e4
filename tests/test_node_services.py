"""Services no other test calls: the world node's ``~/reset`` (a new run from tick 0) and the intention node's
``~/save_model`` / ``~/load_model``, on the graph over DDS; and a respawned node's start
(``homeo_decision.durable``): this launch's checkpoint, an earlier launch's, or none."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rosgraph import Probe, fresh_domain, sim_graph, sim_opts

pytestmark = pytest.mark.ros
START_S = 90.0


def test_world_reset_starts_a_new_run_and_the_intention_model_saves_and_loads(tmp_path):
    from std_srvs.srv import Trigger

    from homeo_decision.scenario import load_scenario
    from homeo_intention.model import IntentionModel

    d, n = fresh_domain(), 40
    m1, m2, m3 = (tmp_path / f"m{i}.json" for i in (1, 2, 3))
    with sim_graph(sim_opts(iterations=n, intention="bayes", data_dir=str(tmp_path)), d):
        probe = Probe(d)
        try:
            status = probe.collect("/homeo/run_status")
            done = lambda run: any(s["done"] and s["run"] == run for s in status)  # noqa: E731
            assert probe.spin_until(lambda: done(0), START_S), "the first run did not end"
            call = lambda name: probe.call(Trigger, name, Trigger.Request())  # noqa: E731
            r = call("/homeo_intention/save_model")
            assert not r.success and r.message == "model_path is not set"
            assert probe.set_param("/homeo_intention", "model_path", str(m1)).successful
            r = call("/homeo_intention/save_model")
            assert r.success and r.message == f"saved {m1}", r.message
            # the world starts over from tick 0; the robot keeps learning, so its model moves on from m1
            r = call("/homeo_world/reset")
            assert r.success and r.message.startswith("run 1 starts from tick 0"), r.message
            assert probe.spin_until(lambda: done(1), START_S), "the second run did not end"
            assert probe.set_param("/homeo_intention", "model_path", str(m2)).successful
            assert call("/homeo_intention/save_model").success
            assert probe.set_param("/homeo_intention", "model_path", str(m1)).successful
            r = call("/homeo_intention/load_model")
            assert r.success and r.message == f"loaded {m1}", r.message
            assert probe.set_param("/homeo_intention", "model_path", str(m3)).successful
            assert call("/homeo_intention/save_model").success
            assert probe.set_param("/homeo_intention", "model_path", str(tmp_path / "none.json")).successful
            r = call("/homeo_intention/load_model")
            assert not r.success and "not found" in r.message
        finally:
            probe.close()
    cpds = lambda p: json.loads(Path(p).read_text())["cpds"]  # noqa: E731
    assert cpds(m3) == cpds(m1) != cpds(m2)  # what was loaded is what had been saved, not what was learned since
    IntentionModel(load_scenario()).load(m3)  # a model file this scenario reads


@pytest.fixture
def node():
    """A real rclpy node named as the decision node (what the durable start reads: its name, its logger)."""
    import rclpy

    ctx = rclpy.Context()
    rclpy.init(context=ctx, domain_id=fresh_domain())
    n = rclpy.create_node("homeo_decision", context=ctx)
    yield n
    n.destroy_node()
    rclpy.shutdown(context=ctx)


def _checkpoint(folder: Path, name: str, session: str, ticks: int = 120) -> None:
    from homeo_decision import checkpoint

    checkpoint.save(checkpoint.path_for(folder, name), checkpoint.envelope(name, ticks, 0, 0, {}, None, {}, session))


def _respawned(folder: Path, **kw) -> dict:
    return dict(dict(checkpoint_dir=str(folder), resume_dir=str(folder), respawned=True, session="launch-B"), **kw)


def test_a_respawn_goes_on_only_from_a_checkpoint_of_its_own_launch(node, tmp_path):
    from homeo_decision import durable
    from homeo_msgs_py.node_base import NodeConfigError

    assert durable.read_start(node, _respawned(tmp_path)) is None  # none yet: a fresh start
    with pytest.raises(NodeConfigError, match="resume: .*homeo_decision.json"):
        durable.read_start(node, _respawned(tmp_path, respawned=False))  # a resume needs one
    _checkpoint(tmp_path, "homeo_decision", "launch-A", ticks=77)
    assert durable.read_start(node, _respawned(tmp_path)) is None  # an earlier launch's: a fresh start
    assert durable.read_start(node, _respawned(tmp_path, respawned=False))["ticks"] == 77  # a resume takes it
    _checkpoint(tmp_path, "homeo_decision", "launch-B")
    assert durable.read_start(node, _respawned(tmp_path))["ticks"] == 120


def test_a_start_is_a_respawn_when_any_node_has_written_a_checkpoint_of_this_launch(tmp_path):
    from homeo_decision import durable

    cfg = _respawned(tmp_path)
    assert not durable.launch_started(cfg)
    _checkpoint(tmp_path, "homeo_intention", "launch-A")
    assert not durable.launch_started(cfg)  # an earlier launch's
    _checkpoint(tmp_path, "homeo_world", "launch-B")
    assert durable.launch_started(cfg)  # another node's, of this launch
    assert not durable.launch_started(dict(cfg, session=""))  # a start without a session never rejoins
    assert not durable.launch_started(dict(cfg, checkpoint_dir=""))

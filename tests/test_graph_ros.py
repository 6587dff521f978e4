"""Integration tests of the node graph: real node processes over DDS on loopback.

Each test takes its own ROS_DOMAIN_ID, and every wait is bounded.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from rosgraph import Probe, fresh_domain, sim_graph, sim_opts

from homeo_launch.processes import graph_env

pytestmark = pytest.mark.ros

START_S = 60.0  # nodes import rclpy and discover each other; generous on a loaded 2-core machine


def _env(domain: int) -> dict:
    return graph_env(domain)


def _cli(module: str, *args, domain: int, timeout: float = 180.0) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", module, *args], env=_env(domain), capture_output=True, text=True,
                          timeout=timeout)


def _status_tick(status: list) -> int:
    return status[-1]["tick"] if status else -1


# -- equivalence --------------------------------------------------------------------------------
@pytest.mark.parametrize("intention", ["oracle", "bayes"])
def test_launcher_prints_exactly_the_in_process_metrics_and_the_same_actions(tmp_path, intention):
    n, seed = 300, 4
    d = fresh_domain()
    g = _cli("homeo_launch.cli", "sim", "--iterations", str(n), "--seed", str(seed), "--json", "--quiet",
             "--intention", intention, "--trace", str(tmp_path / "graph.jsonl"), "--data-dir", str(tmp_path),
             domain=d)
    assert g.returncode == 0, g.stderr
    p = _cli("homeo_sim.cli", "run", "--iterations", str(n), "--seed", str(seed), "--json", "--quiet",
             "--intention", intention, "--trace", str(tmp_path / "proc.jsonl"), domain=d)
    assert p.returncode == 0, p.stderr
    assert g.stdout == p.stdout  # the very same JSON text
    assert ("intention_accuracy" in g.stdout) == (intention == "bayes")
    ga = [json.loads(x)["action"] for x in (tmp_path / "graph.jsonl").read_text().splitlines()]
    pa = [json.loads(x)["action"] for x in (tmp_path / "proc.jsonl").read_text().splitlines()]
    assert len(ga) == n and ga == pa


# -- parameters ---------------------------------------------------------------------------------
def test_a_parameter_change_takes_effect_on_the_next_tick_and_bad_values_are_refused():
    d = fresh_domain()
    with sim_graph(sim_opts(iterations=0, rate=20.0), d):
        probe = Probe(d)
        try:
            actions = probe.collect("/homeo/action")
            assert probe.spin_until(lambda: len(actions) >= 3, START_S), "no actions"
            assert all(a["params"]["dod"] == 0.25 for a in actions)
            r = probe.set_param("/homeo_decision", "dod", 0.9)
            assert r.successful, r.reason
            n_at_change = len(actions)
            assert probe.spin_until(lambda: len(actions) >= n_at_change + 2, 20.0)
            dods = [a["params"]["dod"] for a in actions]
            first_new = dods.index(0.9)
            assert set(dods[first_new:]) == {0.9}  # switched once, for good
            assert first_new <= n_at_change + 1  # at most one action was already on its way
            # refused with a reason, and the old value stays
            for name, value, why in (("dod", 1.5, "range"), ("xi", -1.0, "range"), ("dod", "high", "type"),
                                     ("gamma", 2.0, "range")):
                r = probe.set_param("/homeo_decision", name, value)
                assert not r.successful and r.reason, (name, value)
            n = len(actions)
            assert probe.spin_until(lambda: len(actions) >= n + 1, 20.0)
            assert actions[-1]["params"]["dod"] == 0.9 and actions[-1]["params"]["gamma"] == 0.5
        finally:
            probe.close()


# -- services -----------------------------------------------------------------------------------
def test_save_reset_and_load_the_q_table_through_the_services(tmp_path):
    from std_srvs.srv import Trigger

    from homeo_decision.objectq import ObjectQ
    from homeo_decision.qtable_io import load
    from homeo_decision.scenario import load_scenario

    d = fresh_domain()
    q1, q_empty, q2 = (str(tmp_path / f) for f in ("q1.json", "empty.json", "q2.json"))
    with sim_graph(sim_opts(iterations=150, save_q=q1, data_dir=str(tmp_path)), d):
        probe = Probe(d)
        try:
            status = probe.collect("/homeo/run_status")
            assert probe.spin_until(lambda: status and status[-1]["done"], START_S + 60), "the run did not end"
            call = lambda name: probe.call(Trigger, f"/homeo_decision/{name}", Trigger.Request())  # noqa: E731
            r = call("save_q")
            assert r.success and Path(q1).is_file(), r.message
            r = call("reset")
            assert r.success
            assert probe.set_param("/homeo_decision", "q_table_path", q_empty).successful
            assert call("save_q").success
            assert probe.set_param("/homeo_decision", "q_table_path", q1).successful
            r = call("load_q")
            assert r.success and "charger" in r.message, r.message
            assert probe.set_param("/homeo_decision", "q_table_path", q2).successful
            assert call("save_q").success
            assert probe.set_param("/homeo_decision", "q_table_path", str(tmp_path / "missing.json")).successful
            r = call("load_q")
            assert not r.success and "not found" in r.message
            # paths outside the data directory are refused, whoever sets them
            for outside in ("/etc/passwd", str(tmp_path / ".." / "q.json"), "../q.json"):
                res = probe.set_param("/homeo_decision", "q_table_path", outside)
                assert not res.successful and "outside the data directory" in res.reason, (outside, res.reason)
            # a save that fails is a failed response, the node lives on, and no temporary file stays
            (tmp_path / "adir").mkdir()
            assert probe.set_param("/homeo_decision", "q_table_path", "adir").successful
            r = call("save_q")
            assert not r.success and "is a directory" in r.message, r.message
            assert call("reset").success  # still answering
            assert not list(tmp_path.rglob("*.tmp"))
        finally:
            probe.close()
    for path in (q1, q_empty, q2):
        load(ObjectQ(load_scenario()), path)  # each is a valid table of this scenario

    def values(path):
        t = json.loads(Path(path).read_text())["tables"]
        return [v for o in t.values() for row in o.values() for v in row.values()]

    q0 = load_scenario().open.initial_q  # a reset table holds the scenario's initial Q value (issue 15: 15)
    assert values(q1) == values(q2)  # what was saved came back
    assert any(v != q0 for v in values(q1))
    assert all(v == q0 for v in values(q_empty))


# -- bad input ------------------------------------------------------------------------------------
def _garbage(topic_schema: str) -> list[str]:
    env = {"schema": topic_schema, "version": 1, "run": 0, "tick": 0, "stamp": 1.0}
    return [
        "this is not JSON",
        json.dumps(dict(env, schema="homeo/elsewhere")),
        json.dumps(dict(env, schema="homeo/action", action="Dance")),
        json.dumps(dict(env, version=99)),
        json.dumps(dict(env, tick=-5)),
    ]


def test_garbage_on_every_input_topic_is_rejected_and_reported_while_the_run_goes_on():
    from homeo_msgs_py.graph import TOPICS, key_of

    inputs = {  # topic -> the nodes that read it
        "/homeo/action": ["homeo_world"], "/homeo/drives": ["homeo_decision"],
        "/homeo/world": ["homeo_drives"], "/homeo/observation": ["homeo_intention"],
        "/homeo/intention": ["homeo_drives"],  # no node reads homeo/outcome: it rides in world and observation
    }
    d = fresh_domain()
    # without authentication: every message reaches the decoder (with it, all are refused unsigned)
    with sim_graph(sim_opts(iterations=0, rate=50.0, auth=False), d):
        probe = Probe(d)
        try:
            status = probe.collect("/homeo/run_status")
            diag = probe.diagnostics()
            pubs = {t: probe.publisher(t) for t in inputs}
            assert probe.spin_until(lambda: _status_tick(status) >= 20, START_S), "the run did not start"
            # wait until every garbage publisher has matched its readers
            assert probe.spin_until(lambda: all(probe.node.count_subscribers(t) >= len(r) for t, r in inputs.items()), 20)
            probe.spin_until(lambda: False, 1.0)
            before = _status_tick(status)
            for topic in inputs:
                for text in _garbage(TOPICS[key_of(topic)].schema):
                    pubs[topic](text)
                    probe.spin_until(lambda: False, 0.05)
            # a well-formed but stale action: tick 0 is long past
            pubs["/homeo/action"](json.dumps({"schema": "homeo/action", "version": 1, "run": 0, "tick": 0,
                                              "stamp": 1.0, "action": "Chat"}))

            def reported():
                for topic, nodes in inputs.items():
                    for n in nodes:
                        st = diag.get(f"{n}: inputs")
                        want = 6 if topic == "/homeo/action" else 5  # + the stale action
                        if st is None or int(st["values"].get(f"rejected {topic}", 0)) < want:
                            return False
                return True

            assert probe.spin_until(reported, 20.0), json.dumps(diag, indent=1)
            sim = diag["homeo_world: inputs"]["values"]
            assert "stale tick 0" in sim["last reason /homeo/action"]
            for n, topics in (("homeo_world", ["/homeo/action"]), ("homeo_drives", ["/homeo/world"])):
                recent = " ".join(diag[f"{n}: inputs"]["values"][f"recent reasons {t}"] for t in topics)
                for why in ("not JSON", "unknown schema", "version 99", "Expected `int` >= 0 - at `$.tick`"):
                    assert why in recent, (n, why, recent)
            assert "on a topic that carries 'homeo/world'" in diag["homeo_drives: inputs"]["values"][
                "recent reasons /homeo/world"]
            # the run went on, every tick with its action
            assert probe.spin_until(lambda: _status_tick(status) >= before + 40, 20.0)
            assert status[-1]["missed"] == 0
        finally:
            probe.close()


# -- the launcher's process handling -------------------------------------------------------------------
def _children(pid: int) -> list[int]:
    out = []
    for p in Path("/proc").iterdir():
        if p.name.isdigit():
            try:
                if int((p / "stat").read_text().rsplit(")", 1)[1].split()[1]) == pid:
                    out.append(int(p.name))
            except (OSError, IndexError, ValueError):
                pass
    return out


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def _start_launcher(domain: int, *extra) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "homeo_launch.cli", "sim", "--iterations", "0", "--quiet", *extra],
                            env=_env(domain), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _wait_running(domain: int, launcher: bool = False) -> None:
    """Until the run is past tick 5; with ``launcher``, until the launcher (node ``homeo_launch``) has also
    subscribed to the run's status for 5 more ticks: what it prints on Ctrl-C is the status it received."""
    probe = Probe(domain)
    try:
        status = probe.collect("/homeo/run_status")
        assert probe.spin_until(lambda: _status_tick(status) >= 5, START_S), "the graph did not start"
        if not launcher:
            return
        assert probe.spin_until(lambda: "homeo_launch" in (i.node_name for i in probe.node.get_subscriptions_info_by_topic(
            "/homeo/run_status")), START_S), "the launcher never subscribed to homeo/run_status"
        since = _status_tick(status)
        assert probe.spin_until(lambda: _status_tick(status) >= since + 5, START_S), "the run stopped"
    finally:
        probe.close()


def test_ctrl_c_stops_every_process_with_no_orphans():
    d = fresh_domain()
    la = _start_launcher(d)
    try:
        _wait_running(d, launcher=True)
        kids = _children(la.pid)
        assert len(kids) == 4
        t0 = time.monotonic()
        la.send_signal(signal.SIGINT)
        out, err = la.communicate(timeout=30)
        took = time.monotonic() - t0
        assert took < 15.0, f"stopping took {took:.1f} s"  # its own stop ends in SIGKILL within 5 s: room for a busy machine
        assert la.returncode in (0, 130), err
        assert "interrupted" in err
        assert "HSR" in out  # the metrics of the run so far
        assert not [k for k in kids if _alive(k)], "orphaned node processes"
    finally:
        if la.poll() is None:
            la.kill()


def test_a_dead_node_is_named_and_the_rest_are_stopped():
    # without supervision (--max-restarts 0) a node that dies stops the graph; restarts of every node
    # are tested in test_durable_graph.py
    d = fresh_domain()
    la = _start_launcher(d, "--max-restarts", "0")
    try:
        _wait_running(d)
        kids = _children(la.pid)
        victim = next(k for k in kids if "homeo_decision.world_node" in Path(f"/proc/{k}/cmdline").read_text())
        os.kill(victim, signal.SIGKILL)
        out, err = la.communicate(timeout=20)
        assert la.returncode == 1
        assert "node homeo_world exited with code -9" in err
        assert not [k for k in kids if _alive(k)]
    finally:
        if la.poll() is None:
            la.kill()


def test_a_graph_that_cannot_start_is_a_clear_error(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    r = _cli("homeo_launch.cli", "sim", "--iterations", "10", "--scenario", str(bad), domain=fresh_domain(), timeout=60)
    assert r.returncode == 2 and "Traceback" not in r.stderr and "bad.json" in r.stderr


# -- homeo-topic ----------------------------------------------------------------------------------------
def test_homeo_topic_echo_list_pub_param_and_call():
    d = fresh_domain()
    r = _cli("homeo_topic.cli", "pub", "/homeo/action", '{"action": "Dance"}', domain=d, timeout=60)
    assert r.returncode == 2 and "Invalid enum value 'Dance' - at `$.action`" in r.stderr and "Traceback" not in r.stderr
    with sim_graph(sim_opts(iterations=0, rate=20.0), d):
        _wait_running(d)
        r = _cli("homeo_topic.cli", "echo", "/homeo/drives", "--count", "1", "--timeout", "30", domain=d)
        assert r.returncode == 0, r.stderr
        msg = json.loads(r.stdout)
        assert msg["schema"] == "homeo/drives" and msg["m_dom"] in ("Serving", "Social", "Relaxative", "Survival")
        r = _cli("homeo_topic.cli", "list", "--wait", "8", domain=d)
        assert r.returncode == 0 and "homeo_decision" in r.stdout and "/homeo/outcome" in r.stdout
        r = _cli("homeo_topic.cli", "param", "/homeo_decision", "dod", "0.3", domain=d)
        assert r.returncode == 0, r.stderr
        r = _cli("homeo_topic.cli", "param", "/homeo_decision", "dod", domain=d)
        assert r.returncode == 0 and json.loads(r.stdout) == 0.3
        r = _cli("homeo_topic.cli", "param", "/homeo_decision", "dod", "7", domain=d)
        assert r.returncode == 2 and "refused" in r.stderr
        r = _cli("homeo_topic.cli", "call", "/homeo_decision/save_q", domain=d)
        assert r.returncode == 1 and "q_table_path is not set" in r.stdout
        r = _cli("homeo_topic.cli", "pub", "/homeo/observation", '{"intention": "come", "tick": 0}', domain=d)
        assert r.returncode == 0, r.stderr

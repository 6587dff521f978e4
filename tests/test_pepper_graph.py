"""The node graph with ``pepper_bridge`` in place of ``homeo_sim``, against the stand-in Pepper.

Real node processes over DDS and a real libqi session on loopback; each graph takes its own
ROS_DOMAIN_ID and every wait is bounded.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time

import pytest

qi = pytest.importorskip("qi")

from rosgraph import Probe, child_pid, failure_report, fresh_domain  # noqa: E402

from homeo_launch.launch import GraphOptions, graph_specs  # noqa: E402
from homeo_launch.processes import Graph, graph_env  # noqa: E402
from pepper_bridge.config import load_config  # noqa: E402
from pepper_bridge.mapping import BATTERY_KEY, EMOTION_EVENT, TOUCH_EVENTS, WORD_EVENT  # noqa: E402
from pepper_bridge.standin import StandinRobot  # noqa: E402

pytestmark = [pytest.mark.ros, pytest.mark.qi]
qi.logging.setLevel(qi.logging.ERROR)
START_S = 60.0
ROBOT = "homeo_world: robot"
NRES = {0: 0.0, 1: 50.0, 2: 80.0, 3: 100.0}  # Table 4.6

LAUNCH = "import sys; from homeo_launch.cli import main; sys.exit(main(sys.argv[1:]))"  # homeo-launch


def test_launcher_runs_the_bridge_graph_on_the_standin_and_prints_the_interaction_log(tmp_path):
    d = fresh_domain()
    r = subprocess.run([sys.executable, "-c", LAUNCH, "pepper", "--standin", "--script", "field_user.json",
                        "--interactions", "4", "--json", "--log-dir", str(tmp_path)],
                       env=graph_env(d), capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr[-2000:]
    out = json.loads(r.stdout)
    assert [row["interaction"] for row in out["log"]] == [1, 2, 3, 4] and out["missed"] == 0
    for row in out["log"]:
        assert set(row) >= {"m_dom", "intention", "action", "feedback", "proposal"}
        assert row["feedback"] in (-1, 0, 1)
    assert out["log"][0]["intention"] == "light" and out["log"][0]["battery_percent"] == pytest.approx(30.0)
    assert len(out["user_log"]) == 4  # the stand-in's user judged every action


@pytest.mark.slow
def test_a_scripted_session_with_every_input_a_drop_and_a_freeze_completes_through_the_graph(tmp_path):
    """faults_user.json through ``homeo-launch pepper --standin``: battery falling, temperature status 1, 2, 3,
    head touches, angry and calm voices on NAOqi 2.5's 0..10, spoken proposals, the user leaving and coming
    back, a 10 s drop and a 20 s freeze. Every interaction's feedback is the user's, the drives are the body's."""
    d = fresh_domain()
    probe = Probe(d)
    robot_st: list = []

    def on_diag(arr):
        robot_st.extend({"level": s.level[0] if isinstance(s.level, bytes) else s.level, "message": s.message,
                         "values": {kv.key: kv.value for kv in s.values}} for s in arr.status if s.name == ROBOT)

    from diagnostic_msgs.msg import DiagnosticArray

    probe.node.create_subscription(DiagnosticArray, "/diagnostics", on_diag, 50)
    out_f, err_f = open(tmp_path / "out.json", "w"), open(tmp_path / "err.txt", "w")
    proc = subprocess.Popen([sys.executable, "-c", LAUNCH, "pepper", "--standin", "--script", "faults_user.json",
                             "--json", "--log-dir", str(tmp_path / "logs")],
                            env=graph_env(d), stdout=out_f, stderr=err_f, text=True)
    try:
        assert probe.spin_until(lambda: proc.poll() is not None, 240.0), "the session did not complete"
    finally:
        if proc.poll() is None:
            proc.kill()
        out_f.close()
        err_f.close()
        probe.spin_until(lambda: False, 0.3)
        probe.close()
    assert proc.returncode == 0, (tmp_path / "err.txt").read_text()[-2000:]
    out = json.loads((tmp_path / "out.json").read_text())
    log, user = out["log"], out["user_log"]

    # the two faults: each costs the action it cut (MISSED, no effect), nothing else
    missed = [r for r in log if r["missed"]]
    assert len(missed) == 2 and out["missed"] == 2, [(r["interaction"], r["reason"]) for r in log if not r["ok"]]
    assert "dropped" in missed[0]["reason"] and "unresponsive" in missed[1]["reason"]
    assert all(r["feedback"] == 0 and r["proposal"] is None for r in missed)
    # every performed action was judged by the user, and the bridge heard exactly that answer
    done = [r for r in log if r["ok"] and r["action"] is not None]
    assert [(r["action"], r["feedback"], r["proposal"]) for r in done] == \
        [(u["action"], u["feedback"], u["proposal"]) for u in user]
    fb = [r["feedback"] for r in done]
    assert 1 in fb and -1 in fb and all(r["proposal"] for r in done if r["feedback"] == -1)  # touches; anger + words
    calm = [r for r, u in zip(done, user) if u["item"] == 2]  # the calm voice (6 of 10) is no scolding
    assert len(calm) == 1 and calm[0]["feedback"] == 0
    # the body: the battery only falls (the user does not plug), the joints reach status 1, 2 and 3
    battery = [r["battery_percent"] for r in log]
    assert battery[0] == pytest.approx(40.0) and battery[-1] < 30.0 and battery == sorted(battery, reverse=True)
    assert {1, 2, 3} <= {r["temperature_status"] for r in log}
    # each interaction's drives (as the decision chose with them) are the body read that tick
    for r in log:
        assert r["drives"]["NEng"] == pytest.approx(100.0 - r["battery_percent"]), r
        assert r["drives"]["NRes"] == NRES[r["temperature_status"]], r
    praised = [k for k, r in enumerate(log[:-1]) if r["feedback"] == 1]
    assert praised and all(log[k + 1]["drives"]["NAch"] < log[k]["drives"]["NAch"] for k in praised)
    # the user left and came back: the world saw it
    rel = [r["relation"] for r in log]
    assert rel[0] != "absent" and "absent" in rel and rel[-1] != "absent"
    # /diagnostics: the voices' scale is the robot's; the drop and the freeze were reported, and ended
    assert robot_st[-1]["values"]["naoqi_version"] == "2.5.5.5 (robot)" and robot_st[-1]["values"]["emotion_scale"] == "0..10"
    assert any(s["level"] == 2 and s["values"]["connected"] == "false" for s in robot_st)
    frozen = [s for s in robot_st if s["values"]["state"] == "unresponsive"]
    assert frozen and frozen[0]["level"] == 2
    back = [s for s in robot_st if "answers again after" in s["values"]["reason"]]
    assert back, "the end of the freeze was not reported"
    held = float(back[0]["values"]["reason"].rsplit("after ", 1)[1].split(" s")[0])
    assert 15.0 <= held <= 21.0  # found within ~5 s of the 20 s freeze (heartbeat 1 s, timeout 2 s)
    assert int(robot_st[-1]["values"]["drops"]) >= 1 and int(robot_st[-1]["values"]["freezes"]) == 1
    assert int(robot_st[-1]["values"]["rejected_total"]) == 0  # every voice was on the documented scale


@pytest.fixture(scope="module")
def live():
    """An unbounded bridge graph on a stand-in without a scripted user; the test drives the user."""
    d = fresh_domain()
    robot = StandinRobot(load_config(), None, battery=40.0, time_scale=0.0)
    url = robot.start()
    # the Pepper world as homeo-launch pepper starts it (the cues name the intention), unsupervised
    specs = graph_specs(GraphOptions(world="pepper", intention="oracle", max_restarts=0, world_params={
        "iterations": 0, "qi_url": url, "collect_window": 0.6, "collect_quiet": 0.6, "action_timeout": 5.0}))
    g = Graph(specs, graph_env(d))
    g.start()
    probe = Probe(d)
    state = {"robot": robot, "probe": probe, "graph": g, "worlds": probe.collect("/homeo/world"),
             "outcomes": probe.collect("/homeo/outcome"), "statuses": probe.collect("/homeo/run_status"),
             "robot_status": []}

    def on_diag(arr):
        for s in arr.status:
            if s.name == ROBOT:
                state["robot_status"].append({"level": s.level[0] if isinstance(s.level, bytes) else s.level,
                                              "message": s.message, "values": {kv.key: kv.value for kv in s.values}})

    from diagnostic_msgs.msg import DiagnosticArray

    probe.node.create_subscription(DiagnosticArray, "/diagnostics", on_diag, 50)
    try:
        assert probe.spin_until(lambda: len(state["outcomes"]) >= 2, START_S), \
            f"no interactions; bridge log:\n{g.log_tail('homeo_world', 30)}"
        yield state
    finally:
        probe.close()
        g.stop()
        g.close()
        robot.close()


def _alive(state) -> None:
    dead = state["graph"].dead()
    assert dead is None, f"{dead} died:\n{state['graph'].log_tail(dead[0], 30)}"


def test_world_carries_the_body_readings(live):
    w = live["worlds"][-1]
    body = w["body"]
    assert set(body) >= {"battery_percent", "temperature_status", "NEng", "NRes"}
    assert body["NEng"] == pytest.approx(100.0 - body["battery_percent"])
    assert body["NRes"] == NRES[int(body["temperature_status"])]
    # started at 40 %, drains with each action (the stand-in's time is frozen); how far depends on how
    # many ticks the free-running graph took before this reads it (a loaded CI machine: below 30 %)
    assert 0.0 < body["battery_percent"] <= 40.0
    st = live["robot"].state()
    assert live["worlds"][-1]["robot"]["location"] in ("H", "C", "R") and st["battery_percent"] <= 40.0


def _next_world(state, timeout=20.0) -> dict:
    n = len(state["worlds"])
    assert state["probe"].spin_until(lambda: len(state["worlds"]) > n, timeout), "no new tick"
    return state["worlds"][-1]


def _outcome_of(state, tick: int, timeout=20.0) -> dict:
    found = lambda: [o for o in state["outcomes"] if o["tick"] == tick]  # noqa: E731
    assert state["probe"].spin_until(lambda: bool(found()), timeout), f"no outcome for tick {tick}"
    return found()[0]


def test_touch_and_angry_voice_arrive_as_feedback_on_the_outcome(live):
    robot = live["robot"]
    w = _next_world(live)  # tick k is waiting for its action: the reaction belongs to outcome(k)
    robot.raise_event(TOUCH_EVENTS[0], 1.0)
    robot.raise_event(TOUCH_EVENTS[0], 0.0)
    assert _outcome_of(live, w["tick"])["feedback"] == 1
    w = _next_world(live)
    robot.raise_event(EMOTION_EVENT, [[2, 8], [1, 8, 0, 0, 0], 7])  # angry, NAOqi 2.5's 0..10 scale
    robot.raise_event(WORD_EVENT, ["play music", 0.9])
    out = _outcome_of(live, w["tick"])
    assert out["feedback"] == -1 and out["proposal"] == "Play" and out["clarified_intention"] == "music"
    w = _next_world(live)
    assert _outcome_of(live, w["tick"])["feedback"] == 0  # nothing said: no feedback
    _alive(live)


def test_wrongly_typed_value_is_reported_on_diagnostics_and_ticks_go_on(live):
    robot, probe = live["robot"], live["probe"]
    robot.inject(BATTERY_KEY, "abc")
    try:
        assert probe.spin_until(lambda: any(int(s["values"].get("rejected_total", 0)) >= 1
                                            for s in live["robot_status"]), 20.0), live["robot_status"][-1:]
        bad = next(s for s in live["robot_status"] if int(s["values"].get("rejected_total", 0)) >= 1)
        assert bad["level"] == 1 and "rejected" in bad["message"]
        assert any("abc" in s["values"].get("recent", "") for s in live["robot_status"])
        n = len(live["outcomes"])
        assert probe.spin_until(lambda: len(live["outcomes"]) >= n + 2, 20.0), "ticks stopped"
        assert isinstance(live["worlds"][-1]["body"]["battery_percent"], float)  # the last good value stands
    finally:
        robot.clear_injections()
    _alive(live)


def test_a_failed_move_is_an_outcome_without_action_and_a_row_with_ok_false(live):
    robot, probe = live["robot"], live["probe"]
    moves = ("MoveToH", "MoveToC", "MoveToR")

    def failed_rows():
        rows = (live["statuses"][-1].get("extra") or {}).get("log") or [] if live["statuses"] else []
        return [r for r in rows if r["action"] in moves and r["ok"] is False]

    robot._motion = lambda x, y: False  # the stand-in's navigateTo answers False: the robot did not move
    try:
        assert probe.spin_until(lambda: bool(failed_rows()), 60.0), "no move was tried"
    finally:
        del robot._motion
    row = failed_rows()[0]
    assert row["reason"] == "the robot reported failure"
    out = _outcome_of(live, row["interaction"] - 1)
    assert out["action"] is None  # nothing was done
    _alive(live)


def test_robot_dropping_and_coming_back_is_survived(live):
    robot, probe = live["robot"], live["probe"]
    seen = len(live["robot_status"])
    robot.drop_for(1.5)
    t_drop = time.monotonic()
    down = lambda: [s for s in live["robot_status"][seen:] if s["values"]["connected"] == "false"]  # noqa: E731
    assert probe.spin_until(lambda: bool(down()), 10.0), "the drop was not reported"
    assert down()[0]["level"] == 2
    back = lambda: [s for s in live["robot_status"][seen:] if s["values"]["connected"] == "true"  # noqa: E731
                    and int(s["values"]["drops"]) >= 1]
    assert probe.spin_until(lambda: bool(back()), 20.0), "never reconnected"
    n = len(live["outcomes"])
    assert probe.spin_until(lambda: len(live["outcomes"]) >= n + 2, 20.0), "ticks did not resume"
    assert time.monotonic() - t_drop >= 1.5
    ticks = [o["tick"] for o in live["outcomes"]]
    assert ticks == list(range(ticks[0], ticks[0] + len(ticks)))  # no tick lost or repeated
    _alive(live)


def test_field_test_through_the_graph_matches_the_in_process_driver(tmp_path):
    """Both robots of the field test, run through the node graph (``homeo-pepper-field --graph``: the generic
    front end, ``homeo-launch pepper --standin ...``), give the in-process field test's log row for row."""
    import os

    from pepper_bridge.field import run_field, train_q

    q = {"dedicated": str(train_q(tmp_path / "qd.json", 0.25)), "selfish": str(train_q(tmp_path / "qs.json", 0.0))}
    env = dict(graph_env(fresh_domain()), HOMEO_DATA_DIR=str(tmp_path))
    r = subprocess.run([sys.executable, "-m", "pepper_bridge.field", "--graph", "--script", "field_user.json", "--seeds",
                        "0", "--q-dedicated", q["dedicated"], "--q-selfish", q["selfish"], "--json"],
                       env=env, capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert r.returncode == 0, r.stderr[-2000:]
    robots = json.loads(r.stdout)[0]["robots"]
    cols = ("m_dom", "intention", "action", "feedback", "proposal")
    for got, (label, dod) in zip(robots, (("dedicated", 0.25), ("selfish", 0.0))):
        ref = run_field("field_user.json", dod, 0, q[label], label=label)
        assert [[x[c] for c in cols] for x in got["log"]] == [[x[c] for c in cols] for x in ref.log], label
        assert got["summary"]["satisfied"] == ref.summary()["satisfied"]
    # which robot satisfies more is not asked of one session with Q-tables of one training seed (with issue
    # 15's third-stage block this session ties, 12 to 12): tests/test_pepper_field.py compares the two over
    # Q-tables of three training seeds and three sessions each
    assert [x["summary"]["label"] for x in robots] == ["dedicated", "selfish"]
    assert os.path.isdir(tmp_path / "checkpoints")  # the graph's files went where the user asked


@pytest.mark.slow
def test_the_bridge_killed_mid_session_is_restarted_and_the_session_completes(tmp_path):
    """The bridge node holds the session's lockstep: killed with -9, the launcher restarts it; it
    reconnects to the (stand-in) robot, restores its checkpoint (log, position) and goes on after the
    newest interaction the robot nodes answered. Exit 0, the log, the restart and the missed ones."""
    import os
    import signal

    from homeo_decision import checkpoint

    d = fresh_domain()
    ck_dir, logs = tmp_path / "ck", tmp_path / "logs"
    n = 14
    p = subprocess.Popen([sys.executable, "-c", LAUNCH, "pepper", "--standin", "--script", "field_user.json",
                          "--interactions", str(n), "--json", "--quiet", "--data-dir", str(tmp_path),
                          "--checkpoint-dir", str(ck_dir), "--checkpoint-every", "2", "--action-timeout", "2",
                          "--log-dir", str(logs)],
                         env=graph_env(d), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    out = err = ""
    last = None
    try:
        path = ck_dir / "homeo_world.json"
        end = time.monotonic() + 120
        while time.monotonic() < end and p.poll() is None:
            try:
                last = checkpoint.load(path, "homeo_world")
                if last["ticks"] >= 4:
                    break
            except checkpoint.CheckpointError:
                pass
            time.sleep(0.1)
        assert last is not None and last["ticks"] >= 4, "the bridge never checkpointed 4 interactions"
        pid = child_pid(p.pid, "homeo_decision.world_node")
        assert pid is not None, "the bridge process was not found"
        os.kill(pid, signal.SIGKILL)
        last = checkpoint.load(path, "homeo_world")
        out, err = p.communicate(timeout=240)
    finally:
        if p.poll() is None:
            p.kill()
            out, err = p.communicate()
        report = failure_report(p, out, err, logs)
    assert p.returncode == 0, report
    res = json.loads(out)
    assert res["restarts"] == {"homeo_world": 1}, report
    nums = [r["interaction"] for r in res["log"]]
    assert nums == sorted(set(nums)) and nums[-1] == n, report  # each once, in order, to the end
    lost = n - len(nums)  # the interactions after the checkpoint, before the restarted bridge went on
    assert nums[:last["ticks"]] == list(range(1, last["ticks"] + 1)), report
    assert res["missed"] >= lost, report
    bridge_log = (logs / "homeo_world.log").read_text()
    assert "going on with run 0 at tick" in bridge_log, report




def test_pepper_resume_goes_on_with_the_robot_nodes_learning(tmp_path):
    """``pepper --resume DIR``: a second session on the stand-in starts its robot nodes from the first
    session's final checkpoints: the decision node's schedule goes on from the interactions it has
    learned (tick offset), and its Q-table and the intention model are those it had (digests)."""
    from homeo_decision import checkpoint

    d = fresh_domain()
    ck = tmp_path / "ck"
    common = ["pepper", "--standin", "--script", "field_user.json", "--json", "--quiet", "--data-dir", str(tmp_path),
              "--checkpoint-dir", str(ck), "--intention", "bayes"]
    r = subprocess.run([sys.executable, "-c", LAUNCH, *common, "--interactions", "3"], env=graph_env(d),
                       capture_output=True, text=True, timeout=240)
    assert r.returncode == 0, r.stderr[-3000:]
    first = checkpoint.load(ck / "homeo_decision.json", "homeo_decision")
    assert first["ticks"] >= 3 and first["tick_offset"] == 0, first["ticks"]
    first_model = checkpoint.load(ck / "homeo_intention.json", "homeo_intention")
    r = subprocess.run([sys.executable, "-c", LAUNCH, *common, "--interactions", "2", "--resume", str(ck)],
                       env=graph_env(d), capture_output=True, text=True, timeout=240)
    assert r.returncode == 0, r.stderr[-3000:]
    assert len(json.loads(r.stdout)["log"]) == 2
    after = checkpoint.load(ck / "homeo_decision.json", "homeo_decision")
    assert after["tick_offset"] == first["ticks"], (after["tick_offset"], first["ticks"])  # the schedule went on
    assert after["ticks"] > first["ticks"]
    assert after["session"] != first["session"]
    model = checkpoint.load(ck / "homeo_intention.json", "homeo_intention")
    assert model["ticks"] > first_model["ticks"]  # the model learned on from where it was

"""Learning that survives: real node processes over DDS, killed with SIGKILL mid-run and restarted
by the launcher from their last checkpoint; resume of a stopped run; Ctrl-C saves what was asked."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from rosgraph import Probe, child_pid, failure_report, fresh_domain

from homeo_decision import checkpoint
from homeo_decision.agent import DecisionCore
from homeo_decision.scenario import load_scenario
from homeo_launch.processes import graph_env

pytestmark = [pytest.mark.ros, pytest.mark.slow]

MODULES = {"homeo_decision": "homeo_decision.node", "homeo_intention": "homeo_intention.node"}


def _launch(*args, domain: int) -> subprocess.Popen:
    """``homeo-launch sim`` with its data directory the test's own (the checkpoint folder is in it)."""
    return subprocess.Popen([sys.executable, "-m", "homeo_launch.cli", "sim", "--quiet", *args],
                            env=graph_env(domain), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _wait_ticks(path: Path, ticks: int, proc: subprocess.Popen, bound: float = 120.0) -> None:
    end = time.monotonic() + bound
    while time.monotonic() < end:
        assert proc.poll() is None, proc.communicate()[1][-2000:]
        try:
            if json.loads(path.read_text())["ticks"] >= ticks:
                return
        except (OSError, ValueError, KeyError):
            pass
        time.sleep(0.1)
    raise AssertionError(f"{path} never reached {ticks} ticks")


def _ticks(path: Path) -> int:
    try:
        return json.loads(path.read_text())["ticks"]
    except (OSError, ValueError, KeyError):
        return -1


def _learned_digest(node: str, ck: dict) -> str:
    sc = load_scenario()
    if node == "homeo_decision":
        core = DecisionCore(sc, 0)
        checkpoint.restore_decision(core, ck, params=True)
        return checkpoint.digest(checkpoint.decision_learned(core))
    from homeo_intention.checkpoint import intention_learned, restore_intention
    from homeo_intention.model import IntentionModel

    m = IntentionModel(sc)
    restore_intention(m, ck, "bayes")
    return checkpoint.digest(intention_learned(m))


@pytest.mark.parametrize("node", ["homeo_decision", "homeo_intention"])
def test_a_node_killed_mid_run_is_restarted_from_its_checkpoint_and_the_run_completes(tmp_path, node):
    ck_dir, logs = tmp_path / "ck", tmp_path / "logs"
    n = 500
    d = fresh_domain()
    probe = Probe(d)
    diag = probe.diagnostics()
    p = _launch("--data-dir", str(tmp_path), "--iterations", str(n), "--rate", "50", "--action-timeout", "1", "--checkpoint-dir", str(ck_dir),
                "--checkpoint-every", "50", "--log-dir", str(logs), "--json", domain=d)
    try:
        path = ck_dir / f"{node}.json"
        _wait_ticks(path, 100, p)
        pid = child_pid(p.pid, MODULES[node])
        assert pid is not None
        os.kill(pid, signal.SIGKILL)
        while Path(f"/proc/{pid}").exists() and child_pid(p.pid, MODULES[node]) == pid:
            time.sleep(0.01)
        last = json.loads(path.read_text())  # the last checkpoint the killed process wrote
        # the launcher says it on /diagnostics
        assert probe.spin_until(lambda: diag.get("homeo_launch: supervision", {}).get("values") == {node: "1"}, 60.0)
        out, err = p.communicate(timeout=240)
    finally:
        probe.close()
        if p.poll() is None:
            p.kill()
            p.communicate()
    assert p.returncode == 0, err[-3000:]
    res = json.loads(out)
    assert res["restarts"] == {node: 1}
    assert res["metrics"]["HSR"]["per_seed"] and res["iterations"] == n
    assert f"node {node} exited with code -9; restarting it" not in err  # --quiet: no chatter
    # the new process loaded exactly the last checkpoint: its learned state has the file's digest
    log = (logs / f"{node}.log").read_text()
    m = re.search(r"rejoined from .*: ticks (\d+), tick offset (\d+), learned state ([0-9a-f]+)", log)
    assert m, log[-2000:]
    assert int(m.group(1)) == last["ticks"] and int(m.group(2)) == 0
    assert m.group(3) == _learned_digest(node, last)
    assert (logs / f"{node}.1.log").exists()  # the dead process's log is kept
    final = json.loads(path.read_text())  # written at the end by the new process, same run
    assert final["ticks"] >= n and final["tick_offset"] == 0 and final["session"] == last["session"]
    assert not list(ck_dir.glob("*.tmp"))


def test_a_node_that_keeps_dying_stops_the_graph_with_one_line(tmp_path):
    p = _launch("--data-dir", str(tmp_path), "--iterations", "0", "--rate", "50", "--checkpoint-dir", str(tmp_path / "ck"), "--max-restarts", "1",
                domain=fresh_domain())
    try:
        end = time.monotonic() + 120
        killed = 0
        while killed < 2 and time.monotonic() < end:
            pid = child_pid(p.pid, MODULES["homeo_decision"])
            if pid is not None and (tmp_path / "ck").exists():
                os.kill(pid, signal.SIGKILL)
                killed += 1
                while child_pid(p.pid, MODULES["homeo_decision"]) == pid:
                    time.sleep(0.01)
            time.sleep(0.2)
        out, err = p.communicate(timeout=60)
    finally:
        if p.poll() is None:
            p.kill()
            p.communicate()
    assert p.returncode == 1
    lines = [ln for ln in err.splitlines() if "homeo_decision died" in ln]
    assert lines == ["homeo-launch: error: node homeo_decision died 2 times (last exit code -9); stopping the graph"], err


def test_resume_continues_the_schedule_and_ctrl_c_saves_q(tmp_path):
    d = fresh_domain()
    ck = tmp_path / "ck"
    r = subprocess.run([sys.executable, "-m", "homeo_launch.cli", "sim", "--quiet", "--json", "--iterations", "1000",
                        "--data-dir", str(tmp_path),
                        "--checkpoint-dir", str(ck)], env=graph_env(d), capture_output=True, text=True, timeout=240)
    assert r.returncode == 0, r.stderr[-2000:]
    first = json.loads((ck / "homeo_decision.json").read_text())
    assert first["ticks"] == 1000 and first["tick_offset"] == 0
    # resume into the same folder, until Ctrl-C; --save-q is honoured on the interrupt
    q = tmp_path / "q.json"
    probe = Probe(d)
    actions = probe.collect("/homeo/action")
    p = _launch("--data-dir", str(tmp_path), "--iterations", "0", "--rate", "100", "--resume", str(ck), "--save-q", str(q), domain=d)
    try:
        # spin the probe meanwhile: it takes in the actions as they come
        # (the probe may match the decision's writer late on a loaded machine: count what it hears)
        assert probe.spin_until(lambda: p.poll() is not None or (
            _ticks(ck / "homeo_decision.json") >= 1100 and len(actions) >= 30), 120.0)
        assert p.poll() is None
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=60)
    finally:
        probe.close()
        if p.poll() is None:
            p.kill()
            p.communicate()
    # the schedule went on at tick 1000: alpha 0.1 / tau 2.0 (a fresh start would choose at tau 4.0)
    assert len(actions) >= 30
    assert {a["tau"] for a in actions} == {2.0}
    assert p.returncode == 0, err[-2000:]  # an unbounded run ends with Ctrl-C
    assert "HSR" in out and q.exists()
    after = json.loads((ck / "homeo_decision.json").read_text())
    assert after["tick_offset"] == 1000 and after["ticks"] > 1100  # the final checkpoint, at shutdown
    assert not list(tmp_path.rglob("*.tmp"))
    bad = tmp_path / "bad"
    bad.mkdir()
    (bad / "homeo_decision.json").write_text("{")
    r = subprocess.run([sys.executable, "-m", "homeo_launch.cli", "sim", "--data-dir", str(tmp_path),
                        "--resume", str(bad)], env=graph_env(d),
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "corrupt checkpoint" in r.stderr, r.stderr


def test_the_drives_node_killed_mid_run_is_restarted_and_the_run_completes(tmp_path):
    """The drives node writes its state every tick (two slots, no fsync): restarted, it goes on from
    exactly the state it had after the last tick it answered, not from the initial drives."""
    n = 400
    logs, ck_dir = tmp_path / "logs", tmp_path / "ck"
    p = _launch("--data-dir", str(tmp_path), "--iterations", str(n), "--rate", "50", "--action-timeout", "1",
                "--checkpoint-dir", str(ck_dir), "--checkpoint-every", "50", "--log-dir", str(logs), "--json",
                domain=fresh_domain())
    out = err = ""
    last = None
    try:
        _wait_ticks(ck_dir / "homeo_decision.json", 100, p)
        pid = child_pid(p.pid, "homeo_decision.drives_node")
        assert pid is not None, "no drives node process found"
        os.kill(pid, signal.SIGKILL)
        while Path(f"/proc/{pid}").exists() and child_pid(p.pid, "homeo_decision.drives_node") == pid:
            time.sleep(0.01)
        last = checkpoint.load(ck_dir / "homeo_drives.slots", "homeo_drives")  # what the killed process left
        out, err = p.communicate(timeout=240)
    finally:
        if p.poll() is None:
            p.kill()
            out, err = p.communicate()
        # on failure, everything the next person needs: the launcher's output and each node's log
        report = failure_report(p, out, err, logs)
    assert p.returncode == 0, report
    res = json.loads(out)
    assert res["restarts"] == {"homeo_drives": 1} and res["iterations"] == n, report
    log = (logs / "homeo_drives.log").read_text()
    m = re.search(r"rejoined from .*: run (\d+), tick (\d+), learned state ([0-9a-f]+)", log)
    assert m, report
    from homeo_decision.hosts import PerceptionHost

    host = PerceptionHost(load_scenario())
    checkpoint.restore_drives(host, last)
    # the decision's checkpoint counted 100 ticks (0..99), each decided on the drives' answer: the
    # drives node had answered tick 99 at least (tick 100 too, if it was quicker than the kill)
    assert int(m.group(2)) == last["state"]["tick"] and int(m.group(2)) >= 99, report
    assert m.group(3) == checkpoint.digest(checkpoint.drives_learned(host.perception)), report


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP])
def test_sigterm_and_sighup_stop_save_print_and_leave_no_temporary_folder(tmp_path, sig):
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    env = dict(graph_env(fresh_domain()), TMPDIR=str(tmp))
    p = subprocess.Popen([sys.executable, "-m", "homeo_launch.cli", "sim", "--quiet", "--iterations", "0", "--rate",
                          "100", "--data-dir", str(tmp_path), "--checkpoint-dir", str(tmp_path / "ck")],
                         env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        _wait_ticks(tmp_path / "ck" / "homeo_decision.json", 100, p)
        assert any(tmp.iterdir())  # the launcher's log folder (and the graph's secret) live here meanwhile
        p.send_signal(sig)
        out, err = p.communicate(timeout=60)
    finally:
        if p.poll() is None:
            p.kill()
            p.communicate()
    assert p.returncode == 0 and "HSR" in out, err[-2000:]  # an unbounded run: stopping it is its end
    assert list(tmp.iterdir()) == []
    assert _ticks(tmp_path / "ck" / "homeo_decision.json") > 100  # the final checkpoint


def test_the_world_node_killed_mid_run_goes_on_with_the_same_run_and_counts_the_lost_ticks(tmp_path):
    """The simulation node holds the run: killed, it is restarted, restores its checkpoint (world,
    human, streams, metrics) and goes on after the newest tick the robot nodes answered; the ticks
    since its checkpoint are missed. The run ends with exit 0, its metrics and the restart."""
    ck_dir, logs = tmp_path / "ck", tmp_path / "logs"
    n = 400
    d = fresh_domain()
    probe = Probe(d)
    diag = probe.diagnostics()
    p = _launch("--data-dir", str(tmp_path), "--iterations", str(n), "--rate", "50", "--action-timeout", "1",
                "--checkpoint-dir", str(ck_dir), "--checkpoint-every", "50", "--log-dir", str(logs),
                "--trace", str(tmp_path / "trace.jsonl"), "--json", domain=d)
    err = ""
    try:
        path = ck_dir / "homeo_world.json"
        _wait_ticks(path, 100, p)
        pid = child_pid(p.pid, "homeo_decision.world_node")
        assert pid is not None
        os.kill(pid, signal.SIGKILL)
        last = json.loads(path.read_text())  # the killed process's last checkpoint
        assert probe.spin_until(lambda: diag.get("homeo_launch: supervision", {}).get("values") == {"homeo_world": "1"},
                                60.0)
        out, err = p.communicate(timeout=240)
    finally:
        probe.close()
        if p.poll() is None:
            p.kill()
            err = p.communicate()[1]
    log = (logs / "homeo_world.log").read_text() if (logs / "homeo_world.log").exists() else ""
    assert p.returncode == 0, err[-3000:] + log[-3000:]
    res = json.loads(out)
    assert res["restarts"] == {"homeo_world": 1} and res["iterations"] == n
    assert res["metrics"]["HSR"]["per_seed"]
    m = re.search(r"going on with run (\d+) at tick (\d+)", log)
    assert m, log[-2000:]
    run, at = int(m.group(1)), int(m.group(2))
    assert run == last["run"] == 0 and at >= last["ticks"]
    lost = at - last["ticks"]
    assert lost <= 50 + 5  # at most about one checkpoint interval
    final = json.loads(path.read_text())  # the restarted process's, at the end of the same run
    assert final["session"] == last["session"] and final["state"]["position"]["done"]
    assert final["state"]["position"]["missed"] >= lost and final["state"]["world"]["metrics"]["n"] <= n - lost
    # the trace holds each tick once, in order: the lost ticks as ticks without an action
    ticks = [json.loads(line)["tick"] for line in (tmp_path / "trace.jsonl").read_text().splitlines()]
    assert ticks == list(range(n))
    assert not list(ck_dir.glob("*.tmp"))

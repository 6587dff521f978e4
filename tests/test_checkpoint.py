"""Checkpoints without ROS: round trips, the schedule and the random stream going on, bad files as
one-line errors, no *.tmp left, and SIGKILLs during writes never leaving a file that fails to load."""

from __future__ import annotations

import json
import os
import random
import signal
import subprocess
import sys
import time

import pytest

from homeo_decision import checkpoint, jsonfile
from homeo_decision.agent import DecisionCore
from homeo_decision.checkpoint import CheckpointError
from homeo_decision.robot import OracleRecognition, Robot, run_loop
from homeo_decision.rng import UniformStream
from homeo_intention.checkpoint import intention_checkpoint, intention_learned, restore_intention
from homeo_intention.model import IntentionModel
from homeo_msgs_py.rejoin import RejoiningJoin
from homeo_msgs_py.schemas import Message, Rejected
from homeo_sim.environment import SimEnvironment


def _trained_core(sc, ticks: int, seed: int = 3) -> DecisionCore:
    core = DecisionCore(sc, seed)
    robot = Robot(sc, core, OracleRecognition(sc))
    run_loop(SimEnvironment(sc, seed), robot, ticks)
    return core


def test_random_stream_continues_exactly_from_its_state():
    for drawn in (0, 1, 4095, 4096, 5000):
        a = UniformStream(7, "decision")
        for _ in range(drawn):
            a.random()
        st = json.loads(json.dumps(a.state()))  # as it goes through a file
        b = UniformStream(0, "decision")
        b.set_state(st)
        assert [a.random() for _ in range(5000)] == [b.random() for _ in range(5000)], drawn


def test_decision_checkpoint_round_trip_and_schedule_offset(thesis, tmp_path):
    core = _trained_core(thesis, 700)
    path = tmp_path / "homeo_decision.json"
    checkpoint.save(path, checkpoint.decision_checkpoint(core, 700, 0))
    ck = checkpoint.load(path, "homeo_decision")
    other = DecisionCore(thesis, 99)
    checkpoint.restore_decision(other, ck, str(path), params=True)
    assert other.q.q == core.q.q and other.seed == core.seed
    assert checkpoint.digest(checkpoint.decision_learned(other)) == checkpoint.digest(checkpoint.decision_learned(core))
    assert [other.rng.random() for _ in range(100)] == [core.rng.random() for _ in range(100)]
    # the thesis schedule: alpha 0.3 / tau 4.0, then 0.1 / 2.0 from tick 1000 (Section 4.2.1)
    other.set_tick_offset(ck["ticks"])
    assert (other.phase(0).alpha, other.phase(0).tau) == (0.3, 4.0)  # = tick 700
    assert (other.phase(299).alpha, other.phase(299).tau) == (0.3, 4.0)  # = 999
    assert (other.phase(300).alpha, other.phase(300).tau) == (0.1, 2.0)  # = 1000
    other.set_tick_offset(2500)
    assert (other.phase(0).alpha, other.phase(0).tau) == (0.1, 2.0)


def test_resumed_run_learns_as_the_uninterrupted_one_at_the_same_ticks(thesis):
    """Two halves with the schedule and the random stream carried over use the same alpha, tau and
    draws at every tick as one run (the world starts again; the robot's state is what carries)."""
    whole = DecisionCore(thesis, 5)
    first = DecisionCore(thesis, 5)
    run_loop(SimEnvironment(thesis, 1), Robot(thesis, first, OracleRecognition(thesis)), 400)
    ck = json.loads(json.dumps(checkpoint.decision_checkpoint(first, 400, 0)))
    second = DecisionCore(thesis, 0)
    checkpoint.restore_decision(second, ck)
    second.set_tick_offset(ck["ticks"])
    run_loop(SimEnvironment(thesis, 1), Robot(thesis, whole, OracleRecognition(thesis)), 400)
    assert second.q.q == whole.q.q
    assert [second.phase(t) for t in range(1200)] == [whole.phase(t + 400) for t in range(1200)]
    assert [second.rng.random() for _ in range(50)] == [whole.rng.random() for _ in range(50)]


def test_intention_checkpoint_round_trip(thesis, tmp_path):
    m = IntentionModel(thesis)
    rnd = random.Random(0)
    alph = m.coder.alphabets
    for _ in range(60):
        cues = {ch: rnd.choice(list(a)) for ch, a in zip(("gesture", "movement", "keyword"), alph)}
        m.learn(cues, rnd.choice([None, 1, 2]))
    path = tmp_path / "homeo_intention.json"
    checkpoint.save(path, intention_checkpoint(m, 60, 0, 0, "bayes"))
    other = IntentionModel(thesis)
    restore_intention(other, checkpoint.load(path, "homeo_intention"), "bayes", str(path))
    assert checkpoint.digest(intention_learned(other)) == checkpoint.digest(intention_learned(m))
    with pytest.raises(CheckpointError, match="not 'oracle'"):
        restore_intention(other, checkpoint.load(path, "homeo_intention"), "oracle")


@pytest.mark.parametrize("text, why", [
    ("", "not JSON"), ("{\"schema\": \"homeo-checkpoint\"", "not JSON"), ("[]", "not a checkpoint"),
    ('{"schema": "homeo-checkpoint", "version": 2}', "version 2 is not supported"),
    ('{"schema": "homeo-checkpoint", "version": 1, "node": "homeo_intention"}', "not of homeo_decision"),
    ('{"schema": "homeo-checkpoint", "version": 1, "node": "homeo_decision", "ticks": -1}', "ticks must be"),
])
def test_bad_checkpoints_are_one_line_errors(tmp_path, text, why):
    p = tmp_path / "homeo_decision.json"
    p.write_text(text)
    with pytest.raises(CheckpointError, match=why) as e:
        checkpoint.load(p, "homeo_decision")
    assert "\n" not in str(e.value)


def test_a_corrupt_table_or_stream_leaves_the_core_as_it_was(thesis, tmp_path):
    core = _trained_core(thesis, 200)
    ck = checkpoint.decision_checkpoint(core, 200, 0)
    target = DecisionCore(thesis, 1)
    before = json.dumps(target.q.q)
    bad_q = json.loads(json.dumps(ck))
    first = next(iter(bad_q["state"]["tables"].values()))
    first[next(iter(first))] = {"x": 1}
    bad_rng = json.loads(json.dumps(ck)) | {"rng": {"generator": {"nonsense": 1}, "block": 4096, "drawn": 3}}
    for bad in (bad_q, bad_rng):
        with pytest.raises(CheckpointError):
            checkpoint.restore_decision(target, bad, "f", params=True)
        assert json.dumps(target.q.q) == before and target.seed == 1


def test_failed_write_leaves_no_tmp_and_the_old_file(tmp_path):
    p = tmp_path / "c.json"
    jsonfile.write_atomic(p, {"a": 1}, CheckpointError, "checkpoint")

    class Boom:  # json.dumps fails before any file exists; a failing write after mkstemp must clean up
        pass

    with pytest.raises(TypeError):
        jsonfile.write_atomic(p, {"a": Boom()}, CheckpointError, "checkpoint")
    real = os.fsync

    def failing(fd):
        raise OSError(5, "Input/output error")

    os.fsync = failing
    try:
        with pytest.raises(CheckpointError, match="Input/output error"):
            jsonfile.write_atomic(p, {"a": 2}, CheckpointError, "checkpoint")
    finally:
        os.fsync = real
    assert json.loads(p.read_text()) == {"a": 1}
    assert sorted(x.name for x in tmp_path.iterdir()) == ["c.json"]


WRITER = """
import sys, itertools
from homeo_decision import checkpoint
from homeo_decision.agent import DecisionCore
from homeo_decision.scenario import load_scenario
core = DecisionCore(load_scenario(), 0)
print("ready", flush=True)
for i in itertools.count(1):
    core.q.q[0][0][0] = float(i)
    checkpoint.save(sys.argv[1], checkpoint.decision_checkpoint(core, i, 0))
"""


def test_sigkill_during_checkpoint_writes_never_leaves_a_file_that_fails_to_load(tmp_path, thesis):
    path = tmp_path / "homeo_decision.json"
    rnd = random.Random(12)
    last = 0
    for _ in range(12):  # bounded: each round kills the writer at a random moment
        p = subprocess.Popen([sys.executable, "-c", WRITER, str(path)], stdout=subprocess.PIPE, text=True)
        assert p.stdout.readline().strip() == "ready"
        time.sleep(rnd.uniform(0.0, 0.3))
        p.send_signal(signal.SIGKILL)
        p.wait(timeout=10)
        if not path.exists():
            continue  # killed before its first rename
        ck = checkpoint.load(path, "homeo_decision")  # never raises
        checkpoint.restore_decision(DecisionCore(thesis, 0), ck, str(path))
        last = max(last, ck["ticks"])
        for tmp in tmp_path.glob("*.tmp"):  # what a SIGKILL between create and rename leaves: not the file
            tmp.unlink()
    assert last > 0


def _msg(tick: int, run: int = 0) -> Message:
    return Message("homeo/x", run, tick, 0.0, {})


def test_rejoining_join_takes_a_mid_run_start_and_skips_ticks_that_cannot_complete():
    j = RejoiningJoin({"observation": 0, "outcome": -1})
    assert j.put("observation", _msg(4000)) == []  # a restarted node: the world is at tick 4000
    assert [k for k, _ in j.put("outcome", _msg(3999))] == [4000]
    # the outcome of tick 4000 never came (this node's upstream was down): tick 4001 is skipped
    assert j.put("observation", _msg(4001)) == []
    assert [k for k, _ in j.put("outcome", _msg(4001))] == []
    assert j.expected == 4002 and j.skipped == 1
    assert [k for k, _ in j.put("observation", _msg(4002))] == [4002]
    with pytest.raises(Rejected, match="stale"):
        j.put("observation", _msg(4001))
    # an upstream node was down for a while: the newest input jumps the join past the gap
    assert j.put("observation", _msg(4003 + 50)) == []
    assert [k for k, _ in j.put("outcome", _msg(4052))] == [4053] and j.skipped == 1 + 50


@pytest.mark.parametrize("args, why", [
    (["--resume", "{d}/nothing"], "/nothing: no such directory"),
    (["--resume", "/etc"], "outside the data directory"),
    (["--checkpoint-dir", "/tmp/elsewhere"], "outside the data directory"),
    (["--resume", "{d}/ck", "--load-q", "{d}/q.json"], "--resume and --load-q"),
    (["--checkpoint-dir", "{d}/x", "--no-checkpoints"], "contradict"),
    (["--checkpoint-every", "0"], "--checkpoint-every"),
])
def test_launcher_refuses_bad_checkpoint_options_in_one_line(tmp_path, args, why):
    (tmp_path / "q.json").write_text("{}")
    args = [a.format(d=tmp_path) for a in args]
    r = subprocess.run([sys.executable, "-m", "homeo_launch.cli", "sim", "--data-dir", str(tmp_path), *args],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and why in r.stderr and r.stderr.count("\n") == 1, r.stderr

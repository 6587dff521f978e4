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
    (["--resume", "/etc"], "homeo_decision.json"),  # anywhere (the user's own path), but no checkpoint there
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


# -- the drives node: a checkpoint every tick, in two slots --------------------------------------------
def test_a_drives_node_restored_mid_run_from_its_slots_perceives_exactly_as_the_one_that_was_not_killed(thesis,
                                                                                                       tmp_path):
    """The graph on the in-memory bus; at tick 137 the drives node is replaced by a new one restored
    from its slot file (as written every tick); the run's actions and metrics equal the undisturbed
    run's, and so the runner's: nothing of the drives was lost."""
    from homeo_decision.hosts import PerceptionHost
    from homeo_msgs_py.graph import NODES, ORACLE
    from homeo_msgs_py.lockstep import DONE, LockstepDriver
    from homeo_sim.world_backend import SimWorld

    from homeo_ops.bus import Bus, graph_readers, robot_hosts

    def run(replace_at=None):
        from homeo_decision.codec import vocabulary

        bus = Bus(vocabulary(thesis), 0)
        side = SimWorld(thesis, {"seed": 3})
        drv = LockstepDriver(side, bus.send, iterations=300)
        hosts, readers = robot_hosts(thesis, ORACLE, 3), graph_readers(False)
        ck = checkpoint.Checkpointer(str(tmp_path), "homeo_drives", 1, lambda: checkpoint.drives_checkpoint(
            hosts["homeo_drives"].perception, 0, *answer[0]))
        answer, actions = [None], []
        drv.begin()
        while drv.state != DONE:
            for key, m in bus.drain():
                for n in readers.get(key, []):
                    if n == "homeo_world":
                        actions.append(m.fields["action"])
                        drv.on_action(m)
                        continue
                    for k, fields in hosts[n].stage.put(key, m):
                        if n == "homeo_drives":
                            answer[0] = (k, fields)
                            ck.save()
                            if k == replace_at:  # killed after its write: a new process reads the slots
                                hosts[n] = PerceptionHost(thesis)
                                path = checkpoint.path_for(tmp_path, "homeo_drives")
                                checkpoint.restore_drives(hosts[n], checkpoint.load(path, "homeo_drives"), str(path))
                        bus.send(NODES[n].publishes[0], k, fields)
        return actions, side.status(True)["metrics"]

    ref = run()
    assert run(replace_at=137) == ref
    assert (tmp_path / "homeo_drives.slots").stat().st_size == 2 * checkpoint.SLOT_BYTES


def test_a_torn_slot_leaves_the_other_and_a_bad_slot_file_is_one_line(thesis, tmp_path):
    from homeo_decision.hosts import PerceptionHost

    host = PerceptionHost(thesis)
    path = tmp_path / "homeo_drives.slots"
    w = checkpoint.SlotWriter(path)
    ck1 = checkpoint.drives_checkpoint(host.perception, 0, 4, _drives_answer(thesis, host))
    w.write(ck1)
    ck2 = checkpoint.drives_checkpoint(host.perception, 0, 5, _drives_answer(thesis, host))
    w.write(ck2)
    assert checkpoint.load(path, "homeo_drives")["ticks"] == 6
    raw = bytearray(path.read_bytes())
    raw[checkpoint.SLOT_BYTES + 10:checkpoint.SLOT_BYTES + 20] = b"\0" * 10  # the newest slot torn
    path.write_bytes(bytes(raw))
    assert checkpoint.load(path, "homeo_drives")["ticks"] == 5
    for bad, why in ((b"", "no whole slot"), (b"{" * 40, "no whole slot"), (b" " * (3 * checkpoint.SLOT_BYTES),
                                                                              "longer than two slots")):
        path.write_bytes(bad)
        with pytest.raises(CheckpointError, match=why) as exc:
            checkpoint.load(path, "homeo_drives")
        assert "\n" not in str(exc.value)


def _drives_answer(sc, host) -> dict:
    """A drives message of the host's perception after a first tick in the initial world."""
    from homeo_decision import codec

    env = SimEnvironment(sc, 0)
    obs = env.observe()
    world = codec.world_fields(sc, obs)
    perceived = host.perception.tick(obs.code, obs.intention, obs.body, None)
    return codec.drives_fields(sc, perceived, world, None, host.perception.after_action)


# -- world codes saved under another numbering (issue 22: the relation became part of the world code) --------
def test_a_drives_checkpoint_records_how_its_world_codes_are_numbered(thesis):
    from homeo_decision.hosts import PerceptionHost

    host = PerceptionHost(thesis)
    ck = json.loads(json.dumps(checkpoint.drives_checkpoint(host.perception, 0, 0, _drives_answer(thesis, host))))
    assert ck["state"]["world_codes"] == checkpoint.codes_print(thesis) == checkpoint.digest(thesis.code_layout())
    assert thesis.code_layout()[:3] == [["robot.location", ["H", "C", "R"]], ["human.relation", ["near", "far", "absent"]],
                                        ["intention", thesis.intention_names]]
    fresh = PerceptionHost(thesis)
    checkpoint.restore_drives(fresh, ck)
    assert fresh.perception.prev_code == host.perception.prev_code

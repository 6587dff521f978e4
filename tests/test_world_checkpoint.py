"""The world node's checkpoint without ROS: the simulation's environment, its two random streams,
the metric recorder and the lockstep driver's position round-trip exactly through the file, and a
world restored mid-run goes on with the same run without wedging the robot nodes' joins."""

from __future__ import annotations

import copy
import json

import pytest

from homeo_decision.checkpoint import CheckpointError, load, save
from homeo_msgs_py.graph import BAYES, NODES
from homeo_msgs_py.lockstep import DONE
from homeo_msgs_py.rejoin import make_rejoinable
from homeo_msgs_py.schemas import Message
from homeo_msgs_py.world_rejoin import RejoinPoint
from homeo_decision.world_host import WorldHost
from homeo_sim.world_backend import SimWorld

from homeo_ops.bus import Bus, graph_readers, robot_hosts


def sim_host(sc, seed: int, send, iterations: int) -> WorldHost:
    """The world node's host of the simulation, as the node builds it (the bayes mode: accuracy scored)."""
    return WorldHost(SimWorld(sc, {"seed": seed, "intention_learns": True}), send, iterations=iterations)


class ScriptedRobot:
    """Answers each world at once with an action, drives and a recognised intention that depend on
    the tick alone: the world's own trace is then all that can differ between two runs."""

    def __init__(self, sc):
        self.sc = sc

    def answer(self, drv, tick: int) -> Message:
        sc = self.sc
        names = sc.drive_names
        f = {"action": sc.action_names[(tick * 7) % len(sc.action_names)], "m_dom": sc.motivation_names[0],
             "tau": 1.0, "drives": {n: float((tick * 13 + 17 * i) % 101) for i, n in enumerate(names)},
             "after_action": {n: float((tick * 11 + 5 * i) % 101) for i, n in enumerate(names)},  # metrics_sample
             "intention": sc.intention_names[tick % len(sc.intention_names)],
             "params": {"dod": 0.5, "xi": 1.0, "gamma": 0.9, "feedback": True, "pseudo_update": True}}
        if drv.state == "finishing":
            f = dict(f, action=None, final=True)
        return Message("homeo/action", drv.run, tick, 0.0, f)


def _drive(drv, robot, sent, until=None):
    while drv.state != DONE and (until is None or drv.tick < until):
        drv.on_action(robot.answer(drv, drv.tick))


def world_at_tick_20(sc, seed: int) -> dict:
    """The checkpoint a world run of 40 ticks writes as it steps tick 20 (JSON round-tripped)."""
    host = sim_host(sc, seed, lambda *a: None, 40)
    drv = host.driver
    got = {}
    drv.on_step = lambda k: got.update(ck=json.loads(json.dumps(host.checkpoint())))
    drv.begin()
    _drive(drv, ScriptedRobot(sc), [], until=20)
    return got["ck"]


def test_a_world_restored_from_its_checkpoint_goes_on_exactly_as_one_that_never_stopped(thesis, tmp_path):
    """The checkpoint is taken where the driver takes it (before tick T is stepped) and read back
    from the file; the restored world answers the same actions with the same messages, byte for
    byte, and ends with the same metrics and accuracy as the uninterrupted run."""
    n, at = 300, 137
    robot = ScriptedRobot(thesis)
    ref_sent: list = []
    host = sim_host(thesis, 11, lambda k, t, f, r: ref_sent.append((k, t, json.dumps(f, sort_keys=True))), n)
    side, drv = host.world, host.driver
    path = tmp_path / "homeo_world.json"
    drv.on_step = lambda k: save(path, host.checkpoint()) if k == at else None
    drv.begin()
    _drive(drv, robot, ref_sent)
    ref_metrics = side.status(True)["metrics"]

    sent: list = []
    # a new process: the same parameters
    host2 = sim_host(thesis, 11, lambda k, t, f, r: sent.append((k, t, json.dumps(f, sort_keys=True))), n)
    side2, drv2 = host2.world, host2.driver
    ck = load(path, "homeo_world")
    pos = host2.restore(ck, str(path))
    assert pos["tick"] == at and drv2.iterations == n
    host2.go_on(pos["run"], pos["tick"], pos, 0)
    _drive(drv2, robot, sent)
    # from the observation of tick at on (it carries the outcome of at-1), every message is the uninterrupted run's
    first = ref_sent.index(sent[0])
    assert sent[0][:2] == ("observation", at) and sent == ref_sent[first:]
    assert side2.status(True)["metrics"] == ref_metrics
    assert side2.rec.state() == side.rec.state() and side2.env.state() == side.env.state()


def test_the_streams_go_on_from_the_saved_state(thesis):
    side = SimWorld(thesis, {"seed": 4})
    for t in range(50):
        side.env.step(t % len(thesis.action_names))
    st = json.loads(json.dumps(side.env.state()))
    other = SimWorld(thesis, {"seed": 4})
    other.env.set_state(st)
    ahead = [(side.env.human.rng.random(), side.env.human.obs_rng.random()) for _ in range(5000)]
    assert [(other.env.human.rng.random(), other.env.human.obs_rng.random()) for _ in range(5000)] == ahead


def _bus_run(sc, seed, n, kill_at=None, every=25, kill_phase=0):
    """The simulated graph on the in-memory bus with the robot nodes supervised (rejoining joins).
    With ``kill_at``: the world node dies at that tick (what it had sent of the tick still reaches
    the robot when ``kill_phase`` says so), and a new one restores its last checkpoint and rejoins
    after the newest tick the robot nodes answered, as their latched topics tell it."""
    bus = Bus(__import__("homeo_decision.codec", fromlist=["vocabulary"]).vocabulary(sc), seed)
    hosts, readers = robot_hosts(sc, BAYES, seed), graph_readers(True)
    for h in hosts.values():
        make_rejoinable(h.stage)
    latched: dict = {}  # topic key -> the newest message a robot node published (a state topic)

    def make_world():
        host = sim_host(sc, seed, bus.send, n)
        ck = {}
        host.driver.on_step = lambda k: ck.update(file=json.loads(json.dumps(host.checkpoint()))) \
            if k % every == 0 else None
        return host, host.world, host.driver, ck

    host, side, drv, ck = make_world()
    drv.begin()
    lost = None
    while drv.state != DONE:
        if kill_at is not None and lost is None and drv.tick == kill_at:
            if kill_phase == 0:
                bus.queue.clear()  # died before its messages of the tick went out
            else:
                while bus.queue:  # they went out and the robot answered: to a world that is gone
                    _deliver(bus, hosts, readers, latched, None)
            old = ck["file"]
            host, side, drv, ck = make_world()
            pos = host.restore(old)
            point = RejoinPoint(pos["run"], pos["tick"])
            for key, m in latched.items():
                point.put(key, m)
            run, tick = point.where(n)
            lost = tick - pos["tick"]
            host.go_on(run, tick, pos, lost)
            continue
        assert bus.queue, f"the graph stalled at tick {drv.tick}"
        _deliver(bus, hosts, readers, latched, drv)
    return drv, side, hosts, lost


def _deliver(bus, hosts, readers, latched, drv):
    for key, m in bus.drain():
        for node in readers.get(key, []):
            if node == "homeo_world":
                if drv is not None:
                    drv.on_action(m)
                continue
            for k, fields in hosts[node].stage.put(key, m):
                out = NODES[node].publishes[0]
                bus.send(out, k, fields, hosts[node].stage.run)
                if out in ("intention", "drives"):
                    latched[out] = Message(out, hosts[node].stage.run, k, 0.0, fields)


@pytest.mark.parametrize("kill_at,kill_phase", [(60, 0), (60, 1), (51, 1), (50, 0), (149, 1)])
def test_a_world_killed_mid_run_rejoins_after_the_robots_last_answer_and_the_run_completes(thesis, kill_at,
                                                                                            kill_phase):
    n, every = 150, 25
    drv, side, hosts, lost = _bus_run(thesis, 3, n, kill_at, every, kill_phase)
    assert drv.state == DONE and drv.tick == n
    last_ck = ((kill_at - 1) // every) * every  # taken before tick k is stepped: the kill comes before that of kill_at
    # lost: from the checkpoint to the tick after the robot's last answer; counted as missed
    assert lost == kill_at + kill_phase - last_ck and drv.missed == lost
    assert side.rec.n == n - lost  # the metrics hold every tick but the lost ones (no drives came back for them)
    assert all(h.stage.join.expected >= n for h in hosts.values())  # every robot node saw the final tick


def test_an_undisturbed_bus_run_records_every_tick(thesis):
    drv, side, _, lost = _bus_run(thesis, 3, 120)
    assert drv.missed == 0 and lost is None and side.rec.n == 120


@pytest.mark.parametrize("field,value", [
    ("params.scenario", "0123"), ("params.human", "person"), ("params.intention_accuracy", False),
    ("params.world_codes", "0123456789abcdef"), ("params.world_codes", None),
    ("params.rate", -1.0), ("params.iterations", "5"), ("rng.human", {"block": 4096, "drawn": 5000}),
    ("params.world", "pepper"), ("rng.observation", None), ("state.world.env.world", 10**9),
    ("state.world.env.body", [1.0]), ("state.world.env.tick", 3), ("state.world.env.cues", {"gesture": "moonwalk"}),
    ("state.world.env.human.intention", 99), ("state.world.metrics.n", -1),
    ("state.world.metrics.sum", [float("inf")] * 4), ("state.world.accuracy.first", "012"),
    ("state.world.pending", [1, 0]), ("state.world", None),
    ("state.position.outcome", [3, {"action": "Fly"}]), ("state.position.missed", 10**6),
    ("state.position.done", "no"), ("ticks", 7)])
def test_a_corrupt_world_checkpoint_is_refused_whole_with_one_line(thesis, field, value):
    good = world_at_tick_20(thesis, 2)
    bad = copy.deepcopy(good)
    *path, last = field.split(".")
    target = bad
    for p in path:
        target = target[p]
    target[last] = value
    host = sim_host(thesis, 2, lambda *a: None, 40)
    fresh, drv = host.world, host.driver
    before = (fresh.env.state(), fresh.rec.state(), fresh.hits.state(), drv.position())
    with pytest.raises(CheckpointError) as exc:
        host.restore(bad, "f")
    assert "\n" not in str(exc.value) and str(exc.value).startswith("f")
    assert (fresh.env.state(), fresh.rec.state(), fresh.hits.state(), drv.position()) == before


def test_a_world_checkpoint_written_before_the_codes_held_the_relation_is_refused(thesis):
    """Its ``state.world.env.world`` counts presence, not relation (issue 22): read now it would be another world."""
    good = world_at_tick_20(thesis, 2)
    old = copy.deepcopy(good)
    del old["params"]["world_codes"]
    host = sim_host(thesis, 2, lambda *a: None, 40)
    with pytest.raises(CheckpointError, match="written before world codes held the human's relation") as exc:
        host.restore(old, "f")
    assert "\n" not in str(exc.value)
    host.restore(copy.deepcopy(good), "f")  # the current one still loads
    assert host.world.env.world.code == good["state"]["world"]["env"]["world"]


def test_a_world_the_simulation_never_reaches_is_refused(thesis):
    """A person near the robot at R is a world of a robot (a sensed relation); the simulation derives the
    relation from the locations, so a checkpoint that puts it there is refused whole."""
    good = world_at_tick_20(thesis, 2)
    bad = copy.deepcopy(good)
    bad["state"]["world"]["env"]["world"] = thesis.encode({"robot.location": "R", "human.relation": "near",
                                                           "intention": "none", **thesis.open.initial_objects})
    host = sim_host(thesis, 2, lambda *a: None, 40)
    before = host.world.env.state()
    with pytest.raises(CheckpointError, match="not the simulation's") as exc:
        host.restore(bad, "f")
    assert "\n" not in str(exc.value) and host.world.env.state() == before


"""The node cores wired over an in-memory bus: the graph's logic without DDS.

Every message goes through encode/decode and the tick join, and the bus delivers each
tick's messages across topics in a random order (DDS orders messages within a topic
only). The per-tick actions and the metrics must equal ``homeo-sim run``'s.
"""

from __future__ import annotations

import random

import pytest

from homeo_decision.agent import DecisionCore
from homeo_decision.codec import vocabulary
from homeo_decision.hosts import DecisionHost, PerceptionHost
from homeo_intention.recognition import RecognitionHost
from homeo_ops.bus import Bus, BusGraph, graph_readers, robot_hosts
from homeo_msgs_py.graph import BAYES, NODES, ORACLE
from homeo_msgs_py.lockstep import DONE, LockstepDriver, Stale
from homeo_msgs_py.schemas import Rejected
from homeo_sim.runner import RunConfig, run_episode
from homeo_sim.world_backend import SimWorld


def run_bus_graph(sc, seed: int, iterations: int, shuffle_seed: int = 0, mode: str = ORACLE):
    """The graph of ``homeo_msgs_py.graph`` on the in-memory bus (``homeo_ops.bus``), shuffled."""
    world = SimWorld(sc, {"seed": seed, "intention_learns": mode == BAYES})
    g = BusGraph(world, iterations, mode=mode, seed=seed, shuffle=shuffle_seed)
    g.run()
    return g.actions, world.status(True)["metrics"]


@pytest.mark.parametrize("shuffle_seed", [0, 1])
def test_bus_graph_equals_the_in_process_runner(thesis, shuffle_seed):
    n = 400
    actions, metrics = run_bus_graph(thesis, seed=3, iterations=n, shuffle_seed=shuffle_seed)
    ref = run_episode(RunConfig(iterations=n, seed=3), thesis, keep_actions=True)
    assert actions == [thesis.actions[a].name for a in ref.actions]
    assert metrics == ref.metrics


def test_bus_graph_equals_runner_on_the_toy_scenario(toy):
    actions, metrics = run_bus_graph(toy, seed=5, iterations=300)
    ref = run_episode(RunConfig(iterations=300, seed=5), toy, keep_actions=True)
    assert actions == [toy.actions[a].name for a in ref.actions]
    assert metrics == ref.metrics


def test_bus_graph_equals_the_runner_with_bayesian_recognition(thesis):
    n = 400
    actions, metrics = run_bus_graph(thesis, seed=2, iterations=n, shuffle_seed=3, mode=BAYES)
    ref = run_episode(RunConfig(iterations=n, seed=2, intention=BAYES), thesis, keep_actions=True)
    assert actions == [thesis.actions[a].name for a in ref.actions]
    assert metrics == ref.metrics and "intention_accuracy" in metrics


def test_the_recognition_host_rejects_unknown_symbols_and_hides_the_truth(thesis):
    from homeo_msgs_py.schemas import Message

    host = RecognitionHost(thesis, BAYES)
    with pytest.raises(ValueError, match="unknown gesture 'moonwalk'"):
        host.check({"gesture": "moonwalk", "movement": None, "keyword": None})
    # the Bayesian mode never reads the true intention: same cues, same answer
    cues = {"gesture": None, "movement": None, "keyword": None}
    a = host.stage.put("observation", Message("homeo/observation", 0, 0, 1.0, dict(cues, intention="come")))
    b = RecognitionHost(thesis, BAYES).stage.put("observation",
                                                 Message("homeo/observation", 0, 0, 1.0, dict(cues, intention="light")))
    assert a == b and a[0][1]["mode"] == BAYES
    with pytest.raises(ValueError, match="needs the intention"):
        RecognitionHost(thesis, ORACLE).check(cues)


def test_the_driver_counts_a_tick_the_world_could_not_act_on_as_missed(thesis):
    """A world side that reports its last step as missed (a robot that was away) adds to the run's
    missed ticks, as a timeout does."""
    bus = Bus(vocabulary(thesis), 0)
    side = SimWorld(thesis, {"seed": 0})
    driver = LockstepDriver(side, bus.send, iterations=3)
    noted = []
    driver.note = noted.append
    driver.begin()
    for k, missed in ((0, True), (1, False)):
        side.last_missed = missed
        obs = [m for key, m in bus.drain() if key == "world"]
        assert obs and obs[-1].tick == k
        from homeo_msgs_py.schemas import Message
        zeros = {n: 0.0 for n in thesis.drive_names}
        driver.on_action(Message("homeo/action", 0, k, 1.0, {"action": "Chat", "drives": zeros, "after_action": zeros}))
    assert driver.tick == 2 and driver.missed == 1 and noted == ["missed ticks"]


def test_lost_messages_cost_one_timeout_each_and_nothing_else(thesis):
    """Messages crowded out of a queue (here one in twenty, on every topic, at most one per tick):
    after the stall the world sends the tick again, the robot nodes answer repeats with the answer
    they gave, and the run is the runner's, with no tick missed. (Two losses in one tick cost two
    timeouts, and the tick counts as missed: the world sends a tick again once.)"""
    from homeo_msgs_py.schemas import Message  # noqa: F401

    n, seed = 120, 4
    now = [0.0]
    bus = Bus(vocabulary(thesis), 1)
    rng = random.Random(9)
    seen: set = set()
    send = bus.send

    lost_in: set = set()

    def lossy(key, tick, fields, run=0):
        first = (key, tick, run) not in seen
        seen.add((key, tick, run))
        if first and driver.tick not in lost_in and rng.random() < 0.05:
            lost_in.add(driver.tick)
            return  # lost on the way
        send(key, tick, fields, run)

    side = SimWorld(thesis, {"seed": seed})
    driver = LockstepDriver(side, lossy, iterations=n, timeout=5.0, clock=lambda: now[0])
    hosts, readers = robot_hosts(thesis, ORACLE, seed), graph_readers(False)
    stalls = 0
    driver.begin()
    while driver.state != DONE:
        msgs = bus.drain()
        if not msgs:
            stalls += 1
            assert stalls < 200, f"stalled for good at tick {driver.tick}"
            now[0] += 5.01  # one timeout
            driver.poll()
            continue
        for key, m in msgs:
            for node in readers.get(key, []):
                if node == "homeo_world":
                    try:
                        driver.on_action(m)
                    except Rejected as exc:  # a repeat of an action it has: refused as on a real topic
                        assert str(exc).startswith(("stale tick", "duplicate action")), exc
                    continue
                try:
                    out = hosts[node].stage.put(key, m)
                except Stale:  # an input of a tick the node has left: refused as in the node
                    continue
                for k, fields in out:
                    lossy(NODES[node].publishes[0], k, fields)
    ref = run_episode(RunConfig(iterations=n, seed=seed), thesis, keep_actions=True)
    assert 5 <= stalls <= len(lost_in)  # messages were lost, each cost at most one timeout...
    assert driver.missed == 0  # ...and every tick was recovered
    assert side.status(True)["metrics"] == ref.metrics


def test_an_action_that_arrived_is_never_missed_at_any_rate(thesis):
    now = [0.0]
    bus = Bus(vocabulary(thesis), 0)
    side = SimWorld(thesis, {"seed": 0})
    driver = LockstepDriver(side, bus.send, iterations=3, rate=0.1, timeout=1.0, clock=lambda: now[0])
    host = DecisionHost(thesis, DecisionCore(thesis, 0))
    drives, intention = PerceptionHost(thesis), RecognitionHost(thesis, ORACLE)
    driver.begin()
    for _ in range(200):
        for key, m in bus.drain():
            if key == "observation":
                for k, f in intention.stage.put(key, m):
                    bus.send("intention", k, f)
            if key in ("world", "intention"):  # the world carries the outcome of the tick before
                for k, f in drives.stage.put(key, m):
                    bus.send("drives", k, f)
            if key == "drives":
                for k, f in host.stage.put(key, m):
                    bus.send("action", k, f)
            if key == "action":
                driver.on_action(m)
        now[0] += 0.5  # ten seconds a tick at 0.1 Hz: twenty polls, far beyond the 1 s timeout
        driver.poll()
        if driver.state == DONE:
            break
    assert driver.state == DONE and driver.missed == 0

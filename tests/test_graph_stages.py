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
from homeo_msgs_py.graph import BAYES, GRAPHS, NODES, ORACLE, TOPICS
from homeo_msgs_py.lockstep import DONE, LockstepDriver
from homeo_msgs_py.schemas import decode, encode
from homeo_sim.runner import RunConfig, run_episode
from homeo_sim.world_side import SimWorldSide


class Bus:
    def __init__(self, voc, seed):
        self.voc, self.rng, self.queue = voc, random.Random(seed), []

    def send(self, key, tick, fields, run=0):
        self.queue.append((key, encode(TOPICS[key].schema, tick, fields, run=run)))

    def drain(self):
        """Everything sent so far, in a shuffled order that keeps each topic's own order."""
        by_topic = {}
        for topic, text in self.queue:
            by_topic.setdefault(topic, []).append(text)
        self.queue = []
        out = []
        while by_topic:
            topic = self.rng.choice(sorted(by_topic))
            out.append((topic, decode(by_topic[topic].pop(0), self.voc)))
            if not by_topic[topic]:
                del by_topic[topic]
        return out


def run_bus_graph(sc, seed: int, iterations: int, shuffle_seed: int = 0, mode: str = ORACLE):
    """The simulated graph of ``homeo_msgs_py.graph`` on the bus: the world node's driver and side,
    and the robot nodes' hosts, routed by who reads what."""
    bus = Bus(vocabulary(sc), shuffle_seed)
    learning = mode == BAYES
    side = SimWorldSide(sc, seed, intention_accuracy=learning)
    driver = LockstepDriver(side, bus.send, iterations=iterations)
    hosts = {"homeo_intention": RecognitionHost(sc, mode), "homeo_drives": PerceptionHost(sc),
             "homeo_decision": DecisionHost(sc, DecisionCore(sc, seed))}
    readers = {}
    for n in GRAPHS["sim"]:
        for i in NODES[n].reads(learning):
            readers.setdefault(i.topic, []).append(n)
    actions = []
    driver.begin()
    while driver.state != DONE:
        msgs = bus.drain()
        assert msgs, f"the graph stalled at tick {driver.tick}"
        for key, m in msgs:
            for n in readers.get(key, []):
                if n == "homeo_sim":
                    if not m.fields.get("final"):
                        actions.append(m.fields["action"])
                    driver.on_action(m)
                    continue
                for k, fields in hosts[n].stage.put(key, m):
                    bus.send(NODES[n].publishes[0], k, fields)
    return actions, side.status(True)["metrics"]


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
    side = SimWorldSide(thesis, 0)
    driver = LockstepDriver(side, bus.send, iterations=3)
    noted = []
    driver.note = noted.append
    driver.begin()
    for k, missed in ((0, True), (1, False)):
        side.last_missed = missed
        obs = [m for key, m in bus.drain() if key == "world"]
        assert obs and obs[-1].tick == k
        from homeo_msgs_py.schemas import Message
        driver.on_action(Message("homeo/action", 0, k, 1.0, {"action": "Chat", "drives": {n: 0.0 for n in thesis.drive_names}}))
    assert driver.tick == 2 and driver.missed == 1 and noted == ["missed ticks"]

"""The node cores wired over an in-memory bus: the graph's logic without DDS.

Every message goes through encode/decode and the tick join, and the bus delivers each
tick's messages across topics in a random order (DDS orders messages within a topic
only). The per-tick actions and the metrics must equal ``homeo-sim run``'s.
"""

from __future__ import annotations

import random

import pytest

from homeo_decision.agent import DecisionCore
from homeo_decision.drive_tracker import DrivesStage
from homeo_decision.robot_step import DecisionStage
from homeo_intention.stage import RecogniserStage
from homeo_msgs_py.lockstep import TickJoin
from homeo_msgs_py.schemas import Vocabulary, decode, encode
from homeo_sim.runner import RunConfig, run_episode
from homeo_sim.sim_core import SimCore


class Bus:
    def __init__(self, voc, seed):
        self.voc, self.rng, self.queue = voc, random.Random(seed), []

    def send(self, topic, schema, tick, fields):
        self.queue.append((topic, encode(schema, tick, fields)))

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


def run_bus_graph(sc, seed: int, iterations: int, shuffle_seed: int = 0, mode: str = "oracle"):
    voc = Vocabulary(sc)
    bus = Bus(voc, shuffle_seed)
    sim = SimCore(sc, seed)
    intent = RecogniserStage(sc, mode)
    sim.intention_accuracy = mode == "bayes"
    drives = DrivesStage(sc)
    decision = DecisionStage(DecisionCore(sc, seed))
    j_int = TickJoin({"observation": 0, "outcome": -1} if intent.learns else {"observation": 0})
    j_drv = TickJoin({"world": 0, "intention": 0, "outcome": -1})
    j_dec = TickJoin({"drives": 0})
    actions = []
    bus.send("obs", "homeo/observation", 0, sim.observation_msg())
    bus.send("world", "homeo/world", 0, sim.world_msg())
    finished = False
    while not finished:
        for topic, m in bus.drain():
            if topic == "obs":
                for k, inp in j_int.put("observation", m):
                    out = inp.get("outcome")
                    bus.send("intention", "homeo/intention", k, intent.tick(inp["observation"].fields,
                                                                            out.fields if out else None))
            elif topic in ("world", "intention"):
                for k, inp in j_drv.put(topic, m):
                    out = inp.get("outcome")
                    bus.send("drives", "homeo/drives", k, drives.tick(inp["world"].fields, inp["intention"].fields["intention"],
                                                                      out.fields if out else None))
            elif topic == "outcome":
                if intent.learns:
                    for k, inp in j_int.put("outcome", m):
                        bus.send("intention", "homeo/intention", k, intent.tick(inp["observation"].fields,
                                                                                inp["outcome"].fields))
                for k, inp in j_drv.put("outcome", m):
                    bus.send("drives", "homeo/drives", k, drives.tick(
                        inp["world"].fields, inp["intention"].fields["intention"], inp["outcome"].fields))
            elif topic == "drives":
                for k, inp in j_dec.put("drives", m):
                    bus.send("action", "homeo/action", k, decision.tick(k, inp["drives"].fields))
            elif topic == "action":
                assert m.tick == sim.tick
                if sim.tick > 0:  # the drives after the last tick come with this tick's action
                    sim.record([m.fields["drives"][n] for n in sc.drive_names])
                if m.fields.get("final"):
                    finished = True
                    continue
                name = m.fields["action"]
                actions.append(name)
                k = sim.tick
                res = sim.step(sc.action_index(name), m.fields["intention"])
                bus.send("outcome", "homeo/outcome", k, res.outcome)
                final = sim.tick >= iterations
                bus.send("obs", "homeo/observation", sim.tick, sim.observation_msg())
                bus.send("world", "homeo/world", sim.tick, sim.world_msg(final=final))
    return actions, sim.metrics()


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
    actions, metrics = run_bus_graph(thesis, seed=2, iterations=n, shuffle_seed=3, mode="bayes")
    ref = run_episode(RunConfig(iterations=n, seed=2, intention="bayes"), thesis, keep_actions=True)
    assert actions == [thesis.actions[a].name for a in ref.actions]
    assert metrics == ref.metrics and "intention_accuracy" in metrics


def test_the_recogniser_stage_rejects_unknown_symbols_and_hides_the_truth(thesis):
    from homeo_intention.observation import UnknownObservation

    st = RecogniserStage(thesis, "bayes")
    with pytest.raises(UnknownObservation, match="unknown gesture 'moonwalk'"):
        st.check({"gesture": "moonwalk", "movement": None, "keyword": None})
    # the Bayesian mode never reads the true intention: same cues, same answer
    cues = {"gesture": None, "movement": None, "keyword": None}
    a = st.tick(dict(cues, intention="come"), None)
    b = RecogniserStage(thesis, "bayes").tick(dict(cues, intention="light"), None)
    assert a == b
    with pytest.raises(UnknownObservation, match="needs the intention"):
        RecogniserStage(thesis, "oracle").check(cues)

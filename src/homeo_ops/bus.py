"""The graph's own code without DDS: the world host and the robot nodes' hosts on an in-memory bus.

Every message is encoded, decoded and joined as the nodes do it, and routed by the graph
description (``homeo_msgs_py.graph``: who reads what). With a ``shuffle`` seed each batch of a
tick's messages is delivered in a random order across topics (DDS orders messages within a topic
only); without one, in the order sent. The tests compare its trace with the in-process runner's,
and the soak benchmark measures the code's cost on it apart from rclpy's.
"""

from __future__ import annotations

import random

from homeo_decision.agent import DecisionCore
from homeo_decision.codec import vocabulary
from homeo_decision.hosts import DecisionHost, PerceptionHost
from homeo_decision.world_api import WorldBackend
from homeo_decision.world_host import WorldHost
from homeo_intention.recognition import RecognitionHost
from homeo_msgs_py.graph import BAYES, GRAPH, NODES, ORACLE, TOPICS, WORLD
from homeo_msgs_py.lockstep import DONE
from homeo_msgs_py.schemas import decode, encode


class Bus:
    def __init__(self, voc, shuffle: int | None = None):
        self.voc, self.queue = voc, []
        self.rng = random.Random(shuffle) if shuffle is not None else None

    def send(self, key: str, tick: int, fields: dict, run: int = 0) -> None:
        self.queue.append((key, encode(TOPICS[key].schema, tick, fields, run=run)))

    def drain(self) -> list:
        """Everything sent so far, decoded: in order, or shuffled across topics keeping each topic's order."""
        batch, self.queue = self.queue, []
        if self.rng is None:
            return [(key, decode(text, self.voc)) for key, text in batch]
        by_topic: dict = {}
        for key, text in batch:
            by_topic.setdefault(key, []).append(text)
        out = []
        while by_topic:
            key = self.rng.choice(sorted(by_topic))
            out.append((key, decode(by_topic[key].pop(0), self.voc)))
            if not by_topic[key]:
                del by_topic[key]
        return out


def graph_readers(learning: bool) -> dict:
    """Topic key -> the nodes of the graph that read it."""
    out: dict = {}
    for n in GRAPH:
        for i in NODES[n].reads(learning):
            out.setdefault(i.topic, []).append(n)
    return out


def robot_hosts(sc, mode: str, seed: int) -> dict:
    """The robot nodes' hosts, as the nodes build them."""
    return {"homeo_intention": RecognitionHost(sc, mode), "homeo_drives": PerceptionHost(sc),
            "homeo_decision": DecisionHost(sc, DecisionCore(sc, seed))}


class BusGraph:
    """The whole graph in this process: ``world`` in a ``WorldHost`` and the three robot hosts."""

    def __init__(self, world: WorldBackend, iterations: int, *, mode: str = ORACLE, seed: int = 0,
                 shuffle: int | None = None, trace=None):
        sc = world.sc
        self.bus = Bus(vocabulary(sc), shuffle)
        self.host = WorldHost(world, self.bus.send, iterations=iterations, trace=trace)
        self.driver = self.host.driver
        self.hosts = robot_hosts(sc, mode, seed)
        self.readers = graph_readers(mode == BAYES)
        self.actions: list = []  # the action of every tick, as the world took it

    def deliver(self) -> int:
        """One round: every message sent so far to its readers; returns how many were delivered."""
        msgs = self.bus.drain()
        for key, m in msgs:
            for n in self.readers.get(key, ()):
                if n == WORLD:
                    if not m.fields.get("final"):
                        self.actions.append(m.fields["action"])
                    self.driver.on_action(m)
                    continue
                for k, fields in self.hosts[n].stage.put(key, m):
                    self.bus.send(NODES[n].publishes[0], k, fields)
        return len(msgs)

    def run(self, on_round=None) -> dict:
        """To the end of the run; the last status fields. ``on_round(tick)`` after each round."""
        self.driver.begin()
        while self.driver.state != DONE:
            if not self.deliver():
                raise RuntimeError(f"the graph stalled at tick {self.driver.tick}")
            if on_round is not None:
                on_round(self.driver.tick)
        return self.host.status_fields()

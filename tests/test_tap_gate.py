"""A robot node's writer holds its messages until the graph's readers and the launcher's tap
(``extra_readers``) have matched it: the tap hearing a writer is not the writer having matched the
tap, and an event sent in between is lost to a bag for good. Real rclpy over Fast DDS, loopback."""

from __future__ import annotations

import json

import pytest

from rosgraph import Probe, fresh_domain

from homeo_msgs_py.graph import GRAPHS, NODES, min_readers, readers

pytestmark = pytest.mark.ros

ROBOT_TOPICS = sorted({t for n in NODES.values() if n.role != "world" for t in n.publishes})


def test_a_robot_topic_has_the_same_number_of_graph_readers_in_every_graph_and_mode():
    # a robot node does not know its graph: its gate is right only if the count never differs
    assert ROBOT_TOPICS, "the graph description names no robot topic"
    for t in ROBOT_TOPICS:
        counts = {readers(g, t, learning) for g in GRAPHS for learning in (False, True)}
        assert counts == {min_readers(t)}, (t, counts)
        assert min_readers(t) >= 1, t


def _robot_node(probe: Probe, extra: int):
    from rclpy.parameter import Parameter

    from homeo_msgs_py.node_base import HomeoNode

    node = HomeoNode("homeo_drives", context=probe.ctx,
                     parameter_overrides=[Parameter("extra_readers", value=extra)])
    probe.ex.add_node(node)
    return node


@pytest.fixture()
def probe(monkeypatch):
    monkeypatch.delenv("HOMEO_AUTH_FILE", raising=False)  # unsigned: this test is about matching only
    p = Probe(fresh_domain())
    yield p
    p.close()


def test_a_robot_writer_waits_for_the_tap_before_its_first_message(probe):
    node = _robot_node(probe, extra=1)
    pub = node.robot_publisher("drives")
    assert pub.min_subs == min_readers("drives") + 1
    graph_reader = probe.collect("/homeo/drives")
    assert probe.spin_until(lambda: pub.matched() >= 1, 20.0), "the graph's reader never matched"
    pub.publish(json.dumps({"n": 1}))
    probe.spin_until(lambda: graph_reader, 1.5)
    assert graph_reader == [], "sent before the tap matched: the tap would have lost it"
    tap = probe.collect("/homeo/drives")  # a second reader: the tap
    assert probe.spin_until(lambda: graph_reader and tap, 20.0), (graph_reader, tap)
    assert graph_reader == tap == [{"n": 1}]
    node.destroy_node()


def test_without_a_tap_a_robot_writer_sends_once_the_graph_reader_matched(probe):
    node = _robot_node(probe, extra=0)
    pub = node.robot_publisher("intention")
    got = probe.collect("/homeo/intention")
    assert probe.spin_until(lambda: pub.matched() >= 1, 20.0)
    pub.publish(json.dumps({"n": 2}))
    assert probe.spin_until(lambda: got, 10.0)
    assert got == [{"n": 2}]
    node.destroy_node()

"""A robot node's writer holds its messages until the graph's readers and the launcher's tap
(``extra_readers``) have matched it: the tap hearing a writer is not the writer having matched the
tap, and an event sent in between is lost to a bag for good. Real rclpy over Fast DDS, loopback."""

from __future__ import annotations

import json

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rosgraph import Probe, fresh_domain

from homeo_msgs_py.graph import NODES, min_readers, readers

pytestmark = pytest.mark.ros

ROBOT_TOPICS = sorted({t for n in NODES.values() if n.role != "world" for t in n.publishes})


def test_a_robot_topic_has_the_same_number_of_graph_readers_in_every_mode():
    # a robot node does not know whether the intention node learns: its gate is right only if the count never differs
    assert ROBOT_TOPICS, "the graph description names no robot topic"
    for t in ROBOT_TOPICS:
        counts = {readers(t, learning) for learning in (False, True)}
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


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(value=st.integers(-2**63, 2**63 - 1) | st.text(max_size=20) | st.floats(allow_nan=False) | st.booleans())
def test_extra_readers_at_start_is_in_range_or_a_one_line_refusal(probe, value):
    """A bad value is rclpy's ParameterException, which ``run_node`` prints on one line (exit 2)."""
    from rclpy.exceptions import ParameterException

    from homeo_msgs_py.node_base import config_error_line

    try:
        node = _robot_node(probe, extra=value)
    except ParameterException as exc:
        line = config_error_line(exc)
        assert "extra_readers" in line and "\n" not in line
        assert not (type(value) is int and 0 <= value <= 100)
        return
    assert type(value) is int and 0 <= value <= 100 and node.extra_readers == value
    probe.ex.remove_node(node)
    node.destroy_node()

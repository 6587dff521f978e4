"""The launcher's tap on the graph: one raw subscription per topic of the graph, and /diagnostics,
whose messages go to sinks (a bag, a live view) as they came off the wire.

Raw: rclpy hands over the CDR bytes without building a Python message, which is what a rosbag2
bag stores; the tap neither decodes nor encodes, so watching a run costs one more reader per
topic and a copy. Subscriptions use the graph description's QoS (``homeo_msgs_py.qos``), so the
latched state topics match as every node's do.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass

from homeo_msgs_py.graph import DIAGNOSTICS, TOPICS

STRING = "std_msgs/msg/String"
DIAGNOSTIC_ARRAY = "diagnostic_msgs/msg/DiagnosticArray"
DIAG_KEY = "diagnostics"


@dataclass(frozen=True)
class Tapped:
    key: str  # key of graph.TOPICS, or DIAG_KEY
    name: str  # absolute topic name
    msgtype: str  # ROS 2 type
    kind: str  # "state", "event" (graph.TOPICS) or "diagnostics"


def tapped_topics(extra: tuple = ()) -> list[Tapped]:
    """Every topic of the graph (absolute names: the launcher has no namespace), then /diagnostics."""
    out = [Tapped(k, "/" + t.name, STRING, t.kind) for k, t in TOPICS.items()]
    out += [Tapped(k, "/" + TOPICS[k].name if k in TOPICS else "/" + k, STRING, "event") for k in extra]
    return out + [Tapped(DIAG_KEY, DIAGNOSTICS, DIAGNOSTIC_ARRAY, "diagnostics")]


def string_data(raw: bytes) -> str:
    """The text of a CDR-encoded std_msgs/String: a 4-byte encapsulation header, a uint32 length
    (with the terminating NUL), the bytes. Raises ValueError if it is not one."""
    if len(raw) < 8 or raw[0] != 0 or raw[1] not in (0, 1):
        raise ValueError("not a CDR std_msgs/String")
    n = int.from_bytes(raw[4:8], "little" if raw[1] == 1 else "big")
    if n < 1 or 8 + n > len(raw):
        raise ValueError("CDR string length out of bounds")
    return raw[8:8 + n - 1].decode("utf-8")


def pub_qos_of(t: Tapped):
    """The QoS the writers of ``t`` offer (a bag replays with it)."""
    from rclpy.qos import QoSProfile

    from homeo_msgs_py.qos import pub_qos

    return pub_qos(t.key) if t.key in TOPICS else QoSProfile(depth=10)


class Tap:
    """Raw subscriptions on ``node`` to ``topics``; every message goes to each sink's
    ``write(tapped, t_ns, raw)``. ``done`` turns true once a run status that says so was seen."""

    def __init__(self, node, sinks, topics: list[Tapped] | None = None):
        from diagnostic_msgs.msg import DiagnosticArray
        from rclpy.qos import HistoryPolicy, QoSProfile
        from std_msgs.msg import String

        from homeo_msgs_py.qos import quiet_sub_events, sub_qos

        self.topics = topics or tapped_topics()
        self.sinks = list(sinks)
        self.count = 0
        self.done = False
        self.subs = []
        for t in self.topics:
            # the graph's QoS (what matching depends on), but keep all: a latched state topic's
            # readers keep a few, and the tap must not lose a tick when it lags behind a burst
            qos = sub_qos(t.key) if t.key in TOPICS else QoSProfile(depth=50)
            qos = QoSProfile(history=HistoryPolicy.KEEP_ALL, reliability=qos.reliability, durability=qos.durability)
            mtype = DiagnosticArray if t.msgtype == DIAGNOSTIC_ARRAY else String
            self.subs.append(node.create_subscription(mtype, t.name, self._callback(t), qos, raw=True,
                                                      event_callbacks=quiet_sub_events()))

    def _callback(self, t: Tapped):
        sinks = self.sinks
        is_status = t.key == "run_status"

        def cb(raw: bytes) -> None:
            now = time.time_ns()
            self.count += 1
            for s in sinks:
                s.write(t, now, raw)
            if is_status and not self.done:
                try:
                    self.done = json.loads(string_data(raw)).get("done") is True
                except ValueError:
                    pass

        return cb

    def unmatched(self, keys) -> list[str]:
        """Topics among ``keys`` whose tap subscription has no writer yet."""
        return [t.name for s, t in zip(self.subs, self.topics) if t.key in keys and s.get_publisher_count() < 1]

"""What every homeo node shares: the scenario, validated subscriptions, gated publishers,
/diagnostics, and the standard ``main`` (ros2/demos style: build, spin, always clean up).
"""

from __future__ import annotations

import json
import os
import signal
import sys
import time
from typing import Callable

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rcl_interfaces.msg import ParameterDescriptor
from std_msgs.msg import String

from .diagnostics import RejectLog
from .qos import pub_qos, quiet_pub_events, quiet_sub_events, sub_qos
from .schemas import Message, Rejected, Vocabulary, decode, encode
from .topics import DIAGNOSTICS, TOPICS

DIAG_PERIOD_S = 1.0


class NodeConfigError(Exception):
    """A node cannot start as configured (bad parameter, unreadable file): one line, exit 2."""


class GatedPublisher:
    """Publishes only once ``min_subs`` subscriptions have matched (ARCHITECTURE.md: never publish
    an event that must not be lost before its reader matched). Messages wait in order; after
    ``bound_s`` without a match they go out anyway, with a warning."""

    def __init__(self, node: "HomeoNode", topic: str, min_subs: int = 1, bound_s: float = 10.0):
        self.node = node
        self.topic = topic
        self.pub = node.create_publisher(String, topic, pub_qos(topic), event_callbacks=quiet_pub_events())
        self.min_subs = min_subs
        self.bound_s = bound_s
        self.open = min_subs <= 0
        self._queue: list[str] = []
        self._since: float | None = None
        self._timer = None

    def matched(self) -> int:
        return self.pub.get_subscription_count()

    def publish(self, text: str) -> None:
        if not self.open and self.matched() >= self.min_subs:
            self.open = True
        if self.open and not self._queue:
            self.pub.publish(String(data=text))
            return
        self._queue.append(text)
        if self._since is None:
            self._since = time.monotonic()
        if self._timer is None:
            self._timer = self.node.create_timer(0.005, self._flush)

    def _flush(self) -> None:
        if not self.open:
            if self.matched() >= self.min_subs:
                self.open = True
            elif time.monotonic() - self._since > self.bound_s:
                self.node.get_logger().warning(
                    f"{self.topic}: only {self.matched()} of {self.min_subs} readers matched after "
                    f"{self.bound_s:.0f} s; publishing anyway")
                self.open = True
            else:
                return
        for text in self._queue:
            self.pub.publish(String(data=text))
        self._queue.clear()
        self._timer.cancel()
        self.node.destroy_timer(self._timer)
        self._timer = None


class HomeoNode(Node):
    """Base of the homeo nodes: parameters ``scenario`` and ``overrides``, the vocabulary,
    validated JSON subscriptions, and an input-health status on /diagnostics."""

    def __init__(self, name: str, **kw):
        super().__init__(name, **kw)
        self.declare_parameter("scenario", "", ParameterDescriptor(
            description="scenario JSON file ('' = the thesis scenario); fixed at start", read_only=True))
        self.declare_parameter("overrides", "{}", ParameterDescriptor(
            description="JSON object of open-choice overrides, as homeo-sim --set; fixed at start", read_only=True))
        self.sc = load_node_scenario(self.get_parameter("scenario").value, self.get_parameter("overrides").value)
        self.voc = Vocabulary(self.sc)
        self.rejects = RejectLog(name)
        from diagnostic_msgs.msg import DiagnosticArray

        self._diag_pub = self.create_publisher(DiagnosticArray, DIAGNOSTICS, 10, event_callbacks=quiet_pub_events())
        self._diag_timer = self.create_timer(DIAG_PERIOD_S, self.publish_diagnostics)

    # -- topics ---------------------------------------------------------------------
    def publisher(self, topic: str, min_subs: int = 0) -> GatedPublisher:
        return GatedPublisher(self, topic, min_subs)

    def send(self, pub: GatedPublisher, tick: int, fields: dict, run: int = 0) -> None:
        pub.publish(encode(TOPICS[pub.topic][0], tick, fields, run=run))

    def subscribe(self, topic: str, handler: Callable[[Message], None]):
        """``handler`` gets validated messages; bad ones are dropped with a reason and counted.
        Handlers raise :class:`Rejected` for messages that are valid alone but not here (stale)."""
        schema = TOPICS[topic][0]

        def cb(msg: String) -> None:
            try:
                handler(decode(msg.data, self.voc, schema))
            except Rejected as exc:
                self.reject(topic, str(exc))

        return self.create_subscription(String, topic, cb, sub_qos(topic), event_callbacks=quiet_sub_events())

    def reject(self, topic: str, reason: str) -> None:
        self.rejects.reject(topic, reason)
        self.get_logger().warning(f"dropped a message on {topic}: {reason}", throttle_duration_sec=1.0)
        if self.rejects.counts[topic] == 1:
            self.publish_diagnostics()  # the first of a kind goes out at once

    def publish_diagnostics(self) -> None:
        from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

        arr = DiagnosticArray()
        arr.header.stamp = self.get_clock().now().to_msg()
        arr.status = [DiagnosticStatus(level=bytes([st["level"]]), name=st["name"], message=st["message"],
                                       hardware_id=st["hardware_id"],
                                       values=[KeyValue(key=k, value=v) for k, v in st["values"].items()])
                      for st in [self.rejects.status(), *self.extra_statuses()]]
        self._diag_pub.publish(arr)
        self.rejects.changed = False

    def extra_statuses(self) -> list[dict]:
        """More DiagnosticStatus dicts (level, name, message, hardware_id, values) a node reports."""
        return []


def load_node_scenario(path: str, overrides: str):
    from homeo_decision.scenario import load_scenario

    try:
        ov = json.loads(overrides or "{}")
    except json.JSONDecodeError as exc:
        raise NodeConfigError(f"parameter overrides is not JSON: {exc}") from None
    if not isinstance(ov, dict):
        raise NodeConfigError("parameter overrides must be a JSON object")
    return load_scenario(path or None, overrides=ov)


def _die_with_parent() -> None:
    """Nodes started by the launcher end if it is killed outright (no orphans)."""
    ppid = os.environ.get("HOMEO_PARENT_PID")
    if not ppid:
        return
    try:
        import ctypes

        libc = ctypes.CDLL("libc.so.6", use_errno=True)
        # PR_SET_PDEATHSIG: the launcher stops its nodes gracefully; this fires only when it died
        # without doing so, and then nothing must be left running
        libc.prctl(1, signal.SIGKILL)
        if os.getppid() != int(ppid):  # the parent died before prctl
            os._exit(1)
    except (OSError, AttributeError, ValueError):
        pass


def run_node(factory: Callable[[], Node], args=None) -> int:
    """Build the node, spin until Ctrl-C / SIGTERM / shutdown, always destroy it and shut down."""
    from rclpy.exceptions import ParameterException

    from homeo_decision.scenario import ScenarioError

    _die_with_parent()
    rclpy.init(args=args)  # installs SIGINT/SIGTERM handlers that end spin()
    node = None
    code = 0
    try:
        node = factory()
        rclpy.spin(node)  # one SingleThreadedExecutor per process
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except (ScenarioError, NodeConfigError, ParameterException) as exc:  # bad start-up configuration
        print(f"error: {exc}", file=sys.stderr)
        code = 2
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return code

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

from homeo_msgs_py.graph import DIAGNOSTICS, RECORDER, TOPICS
from homeo_msgs_py.schemas import parse_json

STRING = "std_msgs/msg/String"
DIAGNOSTIC_ARRAY = "diagnostic_msgs/msg/DiagnosticArray"
DIAG_KEY = "diagnostics"


@dataclass(frozen=True)
class Tapped:
    key: str  # key of graph.TOPICS, or DIAG_KEY
    name: str  # absolute topic name
    msgtype: str  # ROS 2 type
    kind: str  # "state", "event" (graph.TOPICS) or "diagnostics"


def tapped_topics(extra: tuple = (), namespace: str = "") -> list[Tapped]:
    """Every topic of the graph (absolute names, in the graph's ``namespace``), then /diagnostics."""
    ns = namespace.rstrip("/")
    out = [Tapped(k, f"{ns}/{t.name}", STRING, t.kind) for k, t in TOPICS.items()]
    out += [Tapped(k, f"{ns}/{TOPICS[k].name}" if k in TOPICS else f"{ns}/{k}", STRING, "event") for k in extra]
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


def lower_priority(nice: int) -> None:
    """Every thread of this process but the main one (the tap's, the middleware's receive threads) at a
    lower priority: on a busy machine they take the CPU the nodes leave. Linux nice is per thread; the
    main thread keeps its own, so the node processes it starts do not inherit it. Best effort."""
    import os

    main = os.getpid()
    try:
        tids = [int(t) for t in os.listdir("/proc/self/task") if int(t) != main]
    except OSError:
        return
    for tid in tids:
        try:
            os.setpriority(os.PRIO_PROCESS, tid, max(os.getpriority(os.PRIO_PROCESS, tid), nice))
        except OSError:
            pass  # the thread ended, or no permission: keep its priority


def pub_qos_of(t: Tapped):
    """The QoS the writers of ``t`` offer (a bag replays with it)."""
    from rclpy.qos import QoSProfile

    from homeo_msgs_py.qos import pub_qos

    return pub_qos(t.key) if t.key in TOPICS else QoSProfile(depth=10)


class Tap:
    """Raw subscriptions to ``topics`` on a node of its own, taken by a lean loop in a thread; every
    message goes to each sink's ``write(tapped, t_ns, raw)`` (in that thread). ``done`` turns true
    once a run status that says so was seen.

    Why not an rclpy executor: it rebuilds its wait set from every entity and wraps each message in
    a task, about 0.3 ms of CPU a message here (measured: 2-3 ms a tick of seven messages, on a
    2-core machine where the nodes need that CPU). The loop waits on the subscriptions alone and,
    on each wake, takes every message that is there."""

    WAKE_S = 0.1  # the loop looks at ``close`` at least this often
    # a wake costs a wait-set rebuild: gather a few ticks' messages per wake (KEEP_ALL holds them; the
    # stamps are the middleware's arrival times, so nothing is skewed; a live view lags by this much)
    GATHER_S = 0.02
    NICE = 10  # the tap is no part of the tick: its threads yield the CPU to the nodes'

    def __init__(self, context_node, sinks, topics: list[Tapped] | None = None, signer=None):
        import threading

        import rclpy
        from diagnostic_msgs.msg import DiagnosticArray
        from rclpy.qos import HistoryPolicy, QoSProfile
        from std_msgs.msg import String

        from homeo_msgs_py.qos import quiet_sub_events, sub_qos

        self.context = context_node.context
        ns = context_node.get_namespace()
        node = self.node = rclpy.create_node(RECORDER, namespace=ns, context=self.context,
                                             start_parameter_services=False, enable_rosout=False)
        self.topics = topics or tapped_topics(namespace="" if ns == "/" else ns)
        self.signer = signer  # the run ends with the graph's own status, not a stranger's
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
            self.subs.append(node.create_subscription(mtype, t.name, lambda m: None, qos, raw=True,
                                                      event_callbacks=quiet_sub_events()))
        self._stop = False
        self._thread = threading.Thread(target=self._loop, name="homeo-tap", daemon=True)
        self._thread.start()

    def _loop(self) -> None:
        from contextlib import ExitStack

        from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy

        subs = [(s, t) for s, t in zip(self.subs, self.topics)]
        lower_priority(self.NICE)
        try:
            with ExitStack() as held:  # the handles stay valid while the loop uses them
                for s, _ in subs:
                    held.enter_context(s.handle)
                held.enter_context(self.context.handle)
                ws = _rclpy.WaitSet(len(subs), 0, 0, 0, 0, 0, self.context.handle)
                wake = int(self.WAKE_S * 1e9)
                while not self._stop:
                    ws.clear_entities()
                    for s, _ in subs:
                        ws.add_subscription(s.handle)
                    ws.wait(wake)
                    ready = set(ws.get_ready_entities("subscription"))
                    for s, t in subs:
                        if s.handle.pointer not in ready:
                            continue
                        while True:
                            got = s.handle.take_message(s.msg_type, True)
                            if got is None:
                                break
                            self._take(t, got[0], got[1].get("received_timestamp") or time.time_ns())
                    time.sleep(self.GATHER_S)  # let messages gather: one wake takes several
        except Exception:  # noqa: BLE001 - the context went down under it (Ctrl-C): the tap just stops
            if not self._stop:
                raise

    def _take(self, t: Tapped, raw: bytes, now: int) -> None:
        self.count += 1
        for s in self.sinks:
            s.write(t, now, raw)
        if t.key == "run_status" and not self.done:
            try:
                text = string_data(raw)
                obj = parse_json(text if self.signer is None else self.signer.verify(text))
                self.done = isinstance(obj, dict) and obj.get("done") is True
            except ValueError:  # Rejected is one: not the graph's, or not JSON
                pass

    def close(self) -> None:
        """Stop taking messages (the sinks are closed by their owner afterwards)."""
        self._stop = True
        self._thread.join(timeout=2.0)
        self.node.destroy_node()

    def unmatched(self, keys) -> list[str]:
        """Topics among ``keys`` whose tap subscription has no writer yet."""
        return [t.name for s, t in zip(self.subs, self.topics) if t.key in keys and s.get_publisher_count() < 1]

"""What every homeo node shares: validated subscriptions, gated publishers, /diagnostics, and the
standard ``main`` (ros2/demos style: build, spin, always clean up). Scenario-free: the scenario's
vocabulary comes from the subclass (``homeo_decision.node_runtime.ScenarioNode``).
"""

from __future__ import annotations

import os
import re
import signal
import sys
import time
from typing import Callable

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from std_msgs.msg import String

from . import data_dir
from .auth import AuthError, load_signer
from .cli_args import die_with_parent
from .diagnostics import RejectLog
from .graph import DIAGNOSTICS, EVENT, LAUNCHER, NODES, RECORDER, SIGNED, TOPICS, max_readers, min_readers, own_endpoints
from .params import ParamSpec
from .qos import pub_qos, quiet_pub_events, quiet_sub_events, sub_qos
from .schemas import Message, Rejected, Vocabulary, decode, encode, one_line

DIAG_PERIOD_S = 1.0
SWITCH_INTERVAL_S = 0.0005


class NodeConfigError(Exception):
    """A node cannot start as configured (bad parameter, unreadable file): one line, exit 2."""


class GatedPublisher:
    """Publishes only once ``min_subs`` subscriptions have matched (ARCHITECTURE.md: never publish
    an event that must not be lost before its reader matched). Messages wait in order; after
    ``bound_s`` without a match they go out anyway, with a warning."""

    def __init__(self, node: "HomeoNode", key: str, min_subs: int = 1, bound_s: float = 10.0, lazy: bool = False):
        self.node = node
        self.key = key
        # an event no node of the graph reads (homeo/outcome, which rides in the next tick's messages): sent
        # only while someone listens (a person, a recorder's tap); kept in the spool when recording at the writers
        self.lazy = lazy
        self.topic = TOPICS[key].name
        self.schema = TOPICS[key].schema
        self.pub = node.create_publisher(String, self.topic, pub_qos(key), event_callbacks=quiet_pub_events())
        self.min_subs = min_subs
        self.bound_s = bound_s
        self.open = min_subs <= 0
        self._queue: list[str] = []
        self._since: float | None = None
        self._timer = None

    def matched(self) -> int:
        return self.pub.get_subscription_count()

    def wanted(self) -> bool:
        """Whether a message would go anywhere: a lazy event with no listener and no recording goes nowhere."""
        return not self.lazy or self.node.spool is not None or self.pub.get_subscription_count() > 0

    def publish(self, text: str) -> None:
        if not self.open and self.matched() >= self.min_subs:
            self.open = True
        if self.open and not self._queue:
            self._send(text)
            return
        self._queue.append(text)
        if self._since is None:
            self._since = time.monotonic()
        if self._timer is None:
            self._timer = self.node.create_timer(0.005, self._flush)
        else:
            self._timer.reset()

    def _send(self, text: str) -> None:
        if not self.lazy or self.pub.get_subscription_count():
            self.pub.publish(String(data=text))
        self.node.spooled(self.pub.topic_name, text)

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
            self._send(text)
        self._queue.clear()
        self._timer.cancel()  # kept for the next wait: no entity destroyed in its own callback (events executor)


class HomeoNode(Node):
    """Base of the homeo nodes: validated JSON subscriptions against ``self.voc`` (set by the
    subclass before it subscribes), gated publishers, and an input-health status on /diagnostics."""

    def __init__(self, name: str, **kw):
        super().__init__(name, **kw)
        self.voc = Vocabulary()
        self.rejects = RejectLog(name)
        try:
            self.signer = load_signer()  # None: the graph runs without authentication (--no-auth)
        except AuthError as exc:
            raise NodeConfigError(str(exc)) from None
        from diagnostic_msgs.msg import DiagnosticArray

        from rcl_interfaces.msg import ParameterDescriptor

        self._fixed: dict = {}  # parameters set at start: a change is refused, the same value accepted
        self._specs: dict = {}  # name -> ParamSpec of the parameters declared from one (declare_specs)
        self._data_dir = self.declare_fixed("data_dir", data_dir.default_dir(), ParameterDescriptor(
            description="files named by parameters (paths) live here; set at start"))
        from rcl_interfaces.msg import IntegerRange

        self.extra_readers = self.declare_fixed("extra_readers", 0, ParameterDescriptor(
            description="readers beyond the graph's (a recorder, a live view) that this node's topics wait for "
                        "before their first message: so that they miss nothing of the run; set at start",
            integer_range=[IntegerRange(from_value=0, to_value=100, step=1)]))
        self.spool = self._open_spool(self.declare_fixed("record_spool", "", ParameterDescriptor(
            description="a folder (in data_dir) where this node appends every message it sends, for the launcher's "
                        "--record to merge into the bag after the run; '' = not recording; set at start")))
        self.executor_kind = self.declare_specs((EXECUTOR,))[EXECUTOR.name]
        self.add_on_set_parameters_callback(self._guard_fixed)
        self._diag_pub = self.create_publisher(DiagnosticArray, DIAGNOSTICS, 10, event_callbacks=quiet_pub_events())
        self._diag_timer = self.create_timer(DIAG_PERIOD_S, self.publish_diagnostics)
        # and one status as soon as the node spins: a run shorter than the period still has one (the timer
        # is cancelled, not destroyed, in its own callback: the events executor must not lose an entity then)
        self._first_diag = self.create_timer(0.0, self._publish_first_diagnostics)

    def _publish_first_diagnostics(self) -> None:
        self._first_diag.cancel()
        self.publish_diagnostics()

    # -- recording at the writers (homeo_msgs_py.spool) ----------------------------------------
    def _open_spool(self, folder: str):
        return open_spool(self._data_dir, folder, self.get_name())

    def spooled(self, topic: str, text: str | None = None, raw: bytes | None = None) -> None:
        """Keep a message this node just sent, when recording: the text of a String, or CDR bytes.
        A spool that cannot be written (disk full) stops recording with one error, never the node."""
        if self.spool is None:
            return
        try:
            if text is not None:
                self.spool.text(topic, text)
            else:
                self.spool.cdr(topic, raw)
        except OSError as exc:
            self.spool.close()
            self.spool = None
            self.get_logger().error(f"recording stopped: writing {topic} to the spool failed: {exc.strerror}")

    # -- files named by parameters ---------------------------------------------------------
    def data_path(self, path: str, what: str, trusted: bool = False) -> str:
        """``path`` (a parameter's value) inside the data directory, or ``OutsideDataDir``; a value
        the node started with (``trusted``) may lie anywhere (``homeo_msgs_py.data_dir``)."""
        return data_dir.resolve(self._data_dir, path, what, trusted)

    def declare_fixed(self, name: str, default, descriptor):
        """A parameter that takes effect at start only. Not ``read_only``: ``ros2 param load`` of a
        ``ros2 param dump`` sets every parameter, and a read-only one fails even with its own value."""
        value = self.declare_parameter(name, default, descriptor).value
        self._fixed[name] = value
        return value

    def declare_specs(self, specs, defaults: dict | None = None) -> dict:
        """Declare parameters from their declarations (``homeo_msgs_py.params.ParamSpec``): the
        descriptor carries the doc and the range, a ``fixed`` one is set at start only. ``defaults``
        (by name) replace the declared defaults (a scenario's values). Returns their values; a value
        the declaration refuses is a NodeConfigError (one line)."""
        values = {}
        for s in specs:
            try:  # as the declared type: a scenario's integer 1 for a float parameter declares a float
                default = s.check((defaults or {}).get(s.name, s.default))
            except ValueError as exc:
                raise NodeConfigError(f"parameter {exc}") from None
            default = list(default) if isinstance(default, tuple) else default
            declare = self.declare_fixed if s.fixed else self.declare_parameter
            value = declare(s.name, default, descriptor(s))
            value = value.value if hasattr(value, "value") else value
            try:
                values[s.name] = s.check(value)
            except ValueError as exc:
                raise NodeConfigError(f"parameter {exc}") from None
            self._specs[s.name] = s
        return values

    def _guard_fixed(self, params):
        from rcl_interfaces.msg import SetParametersResult

        for prm in params:
            if prm.name in self._fixed and prm.value != self._fixed[prm.name]:
                return SetParametersResult(successful=False,
                                           reason=f"{prm.name} is set when the node starts (restart it to change it)")
            spec = self._specs.get(prm.name)
            if spec is not None:
                try:
                    spec.check(prm.value)  # choices, and what the descriptor cannot say
                except ValueError as exc:
                    return SetParametersResult(successful=False, reason=str(exc))
        return SetParametersResult(successful=True)

    # -- topics ---------------------------------------------------------------------
    def publisher(self, key: str, min_subs: int = 0) -> GatedPublisher:
        """A writer of topic ``key`` (of ``graph.TOPICS``); an event no node of the graph reads goes out
        only while someone listens."""
        return GatedPublisher(self, key, min_subs, lazy=TOPICS[key].kind == EVENT and not max_readers(key))

    def robot_publisher(self, key: str) -> GatedPublisher:
        """A robot node's writer of ``key``: its messages wait until the graph's readers and the
        launcher's tap (``extra_readers``) have matched it. The tap hearing the writer is not the
        writer having matched the tap (discovery is per side), and an event sent in between is
        lost to the tap for good."""
        return GatedPublisher(self, key, min_readers(key) + self.extra_readers)

    def send(self, pub: GatedPublisher, tick: int, fields: dict, run: int = 0) -> None:
        if not pub.wanted():  # the outcome each tick, with nobody listening: neither encoded nor signed
            return
        text = encode(pub.schema, tick, fields, run=run)
        if self.signer is not None and pub.key in SIGNED:
            text = self.signer.sign(text)
        pub.publish(text)

    def subscribe(self, key: str, handler: Callable[[Message], None]):
        """``handler`` gets validated messages of topic ``key``; bad ones are dropped with a reason
        and counted. Handlers raise :class:`Rejected` for messages valid alone but not here (stale)."""
        schema = TOPICS[key].schema
        where = [TOPICS[key].name]
        verify = self.signer.verify if self.signer is not None and key in SIGNED else None

        def cb(msg: String) -> None:
            try:
                handler(decode(msg.data if verify is None else verify(msg.data), self.voc, schema))
            except Rejected as exc:
                self.reject(where[0], str(exc))
            except Exception as exc:  # noqa: BLE001 - a message must never take the node down
                self.get_logger().error(f"handling a message on {where[0]} failed: {exc!r}",
                                        throttle_duration_sec=5.0)
                self.reject(where[0], f"internal error {type(exc).__name__} (see the node's log)")

        sub = self.create_subscription(String, TOPICS[key].name, cb, sub_qos(key), event_callbacks=quiet_sub_events())
        where[0] = sub.topic_name  # reported fully resolved, namespace included
        return sub

    def subscribe_text(self, key: str, handler: Callable[[str], None]):
        """``handler`` gets the text of each message of topic ``key``, a topic from outside the graph
        (a person's input: no envelope, no signature); a ``Rejected`` it raises drops the message
        with its reason, counted and reported as for the graph's own topics."""
        where = [TOPICS[key].name]

        def cb(msg: String) -> None:
            try:
                handler(msg.data)
            except Rejected as exc:
                self.reject(where[0], str(exc))

        sub = self.create_subscription(String, where[0], cb, sub_qos(key), event_callbacks=quiet_sub_events())
        where[0] = sub.topic_name
        return sub

    def trigger(self, name: str, answer: Callable[[], tuple[bool, str]]):
        """A ``std_srvs/Trigger`` service (``~/save_q``, ``~/reset``...) answered by ``answer()``:
        (success, message)."""
        from std_srvs.srv import Trigger

        def cb(request, response):
            response.success, response.message = answer()
            return response

        return self.create_service(Trigger, name, cb)

    # -- the start gate -------------------------------------------------------------------
    def gate_missing(self, pubs: dict, want: Callable[[str], int], inputs) -> list[str]:
        """What a world node still waits for before tick 0: for each publisher (key -> GatedPublisher)
        ``want(key)`` readers, matched and belonging to this graph (its nodes, or the launcher's tap,
        in this namespace: another program listening on the domain does not count), and a writer of
        this graph for each input topic key."""
        ns = self.get_namespace()
        mine = set(NODES) | {LAUNCHER, RECORDER}
        out = []
        for key, pub in pubs.items():
            n = want(key)
            own = own_endpoints(self.get_subscriptions_info_by_topic(pub.pub.topic_name), mine, ns)
            got = min(own, pub.matched())
            if got < n:
                out.append(f"{pub.topic} has {got}/{n} readers")
        for key in inputs:
            topic = self.resolve_topic_name(TOPICS[key].name)
            if own_endpoints(self.get_publishers_info_by_topic(topic), mine, ns) < 1:
                out.append(f"{TOPICS[key].name} has no writer")
        return out

    def reject(self, topic: str, reason: str) -> None:
        reason = self.rejects.reject(topic, reason)
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
        if self.spool is not None:
            from rclpy.serialization import serialize_message

            self.spooled(DIAGNOSTICS, raw=serialize_message(arr))
        self.rejects.changed = False

    def extra_statuses(self) -> list[dict]:
        """More DiagnosticStatus dicts (level, name, message, hardware_id, values) a node reports."""
        return []


def descriptor(spec):
    """The ROS ParameterDescriptor of a ``ParamSpec``: its doc (with the equation), its range."""
    from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor

    doc = spec.doc + (f" (Eq {spec.eq})" if spec.eq[:1].isdigit() else f" ({spec.eq})" if spec.eq else "")
    if spec.choices:
        doc += ": " + " | ".join(spec.choices)
    d = ParameterDescriptor(description=doc)
    if spec.kind is int and (spec.lo is not None or spec.hi is not None):
        d.integer_range = [IntegerRange(from_value=int(spec.lo if spec.lo is not None else -2**63),
                                        to_value=int(spec.hi if spec.hi is not None else 2**63 - 1), step=1)]
    elif spec.kind is float and (spec.lo is not None or spec.hi is not None):
        d.floating_point_range = [FloatingPointRange(from_value=float(spec.lo if spec.lo is not None else -1e308),
                                                     to_value=float(spec.hi if spec.hi is not None else 1e308))]
    return d


def open_spool(base: str, folder, who: str):
    """The ``record_spool`` parameter's spool (``homeo_msgs_py.spool``) for node ``who``: None for '',
    else a writer in ``folder`` inside the data directory ``base``, or a one-line NodeConfigError."""
    if not folder:
        return None
    from .spool import SpoolWriter

    try:
        path = data_dir.resolve(base, folder, "record_spool", trusted=True)  # set at start
    except data_dir.OutsideDataDir as exc:
        raise NodeConfigError(str(exc)) from None
    try:
        return SpoolWriter(path, who)
    except OSError as exc:
        raise NodeConfigError(f"record_spool {one_line(folder)}: {one_line(str(exc.strerror))}") from None


def config_error_line(exc: Exception) -> str:
    """What a node prints for a bad start-up configuration: one line, whatever value was given."""
    return "error: " + one_line(str(exc).strip())


# where rcl says in its message which of its C sources refused: not the user's business
_RCL_SOURCE = re.compile(r", at /\S+:\d+")


def ros_args_refusal(args=None) -> str | None:
    """rcl's own reading of the ROS arguments (``--params-file``, ``-p``, remaps; ``None``: the process's
    command line): None if rcl takes them, else why, in one line. rcl's parse is the one the node
    will run, so a parameters file is judged by the parser that reads it, not a second one of ours.
    rcl also logs "Failed to parse global arguments" to stderr; that is muted for the parse, so the
    user reads one line."""
    from rclpy.context import Context
    from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy

    context = Context()
    sys.stderr.flush()
    saved = os.dup(2)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 2)
        context.init(args)
    except _rclpy.RCLError as exc:
        return one_line(_RCL_SOURCE.sub("", str(exc)).removeprefix("failed to initialize rcl: "))
    finally:
        os.dup2(saved, 2)
        os.close(saved)
        context.try_shutdown()
    return None


# rclpy's EventsExecutor (default) or its SingleThreadedExecutor: docs/GRAPH.md, "The executor"
EXECUTOR = ParamSpec("executor", "events", "the node's executor: rclpy's EventsExecutor (one wake a message, no wait "
                     "set rebuilt) or its SingleThreadedExecutor", choices=("events", "single"), fixed=True)
SPIN_S = 1.0  # the longest wait of one spin: the loop checks for shutdown this often at least


def make_executor(kind: str):
    if kind == "events":
        from rclpy.experimental import EventsExecutor

        return EventsExecutor()
    from rclpy.executors import SingleThreadedExecutor

    return SingleThreadedExecutor()


def run_node(factory: Callable[[], Node], args=None, config_errors: tuple = ()) -> int:
    """Build the node, spin until Ctrl-C / SIGTERM / shutdown, always destroy it and shut down; exit
    code 0 however it was stopped (2: a bad start-up configuration). ``config_errors``: more
    exception types that mean a bad start-up configuration."""
    from rclpy.exceptions import ParameterException

    die_with_parent()
    # a helper thread (the checkpoint writer, a blocking world's worker) hands the GIL back within
    # 0.5 ms when a message wakes the main thread, not CPython's 5 ms: the tick never waits on it long
    sys.setswitchinterval(SWITCH_INTERVAL_S)
    refusal = ros_args_refusal(args)  # else rclpy.init raises it with a traceback
    if refusal is not None:
        print(f"error: {refusal}", file=sys.stderr)
        return 2
    rclpy.init(args=args)  # installs SIGINT/SIGTERM handlers that shut the context down
    node = executor = None
    code = 0
    try:
        node = factory()
        executor = make_executor(getattr(node, "executor_kind", EXECUTOR.default))  # one executor per process
        executor.add_node(node)
        spin_forever(executor)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except (NodeConfigError, ParameterException, *config_errors) as exc:  # bad start-up configuration
        print(config_error_line(exc), file=sys.stderr)
        code = 2
    finally:
        # the stop is under way: a second signal (ros2 launch sends SIGINT and the terminal's Ctrl-C
        # reaches the node too; then SIGTERM) must not cut the final checkpoint short with a traceback
        for sig in (signal.SIGINT, signal.SIGTERM):
            signal.signal(sig, signal.SIG_IGN)
        if executor is not None:
            executor.shutdown()  # before the node's entities go: the events executor must not hold them then
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return code


def spin_forever(executor) -> None:
    """Spin until the context shuts down (Ctrl-C, SIGTERM, ``ros2 launch``'s stop). A finite timeout: the
    events executor spun without one busy-loops and never fires timers. Once the context is shutting down,
    the events executor may fail to hand a callback its argument ("Unable to convert call argument"): the
    stop, not an error."""
    while rclpy.ok():
        try:
            executor.spin_once(timeout_sec=SPIN_S)
        except RuntimeError:
            if rclpy.ok():
                raise
            return

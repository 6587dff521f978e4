"""The launcher's own node: discovery of the graph, its run status, service and parameter calls."""

from __future__ import annotations

import time

from homeo_msgs_py.graph import TOPICS, own_endpoints

from .processes import Graph

DISCOVERY_TIMEOUT_S = 60.0


class GraphError(Exception):
    """The graph failed: a node died or never came up. Exit code 1."""


class Monitor:
    """The launcher's own node: watches discovery, /homeo/run_status, and calls services.
    It lives in the graph's namespace, so relative names resolve as the nodes' do; with the
    graph's ``signer`` it believes only run statuses its own graph signed."""

    def __init__(self, namespace: str = "", signer=None):
        import rclpy
        from rclpy.signals import SignalHandlerOptions
        from std_msgs.msg import String

        from homeo_msgs_py.qos import sub_qos
        from homeo_msgs_py.schemas import Rejected, Vocabulary, decode

        from rclpy.executors import SingleThreadedExecutor

        rclpy.init(signal_handler_options=SignalHandlerOptions.NO)  # Ctrl-C stays a KeyboardInterrupt here
        self.rclpy = rclpy
        self.namespace = namespace
        self.node = rclpy.create_node("homeo_launch", namespace=namespace or "/")
        # one executor for the node's life: rclpy.spin_once(node) adds and removes the node every call
        self.executor = SingleThreadedExecutor()
        self.executor.add_node(self.node)
        self.status = None
        self.rejected = 0  # run statuses not believed (unsigned, foreign, malformed)
        voc = Vocabulary()

        def on_status(msg: String) -> None:
            try:
                self.status = decode(msg.data if signer is None else signer.verify(msg.data), voc,
                                     "homeo/run_status")
            except Rejected:
                self.rejected += 1

        self.node.create_subscription(String, TOPICS["run_status"].name, on_status, sub_qos("run_status"))

    def spin(self, timeout: float = 0.05) -> None:
        self.executor.spin_once(timeout_sec=timeout)

    def missing(self, nodes, endpoints) -> list[str]:
        """What of the graph is not up yet: its nodes, and the writers and readers of each topic
        that belong to them (another program's endpoints on the domain do not count)."""
        ns = self.namespace or "/"
        present = {n for n, space in self.node.get_node_names_and_namespaces() if space == ns}
        out = [f"node {n}" for n in nodes if n not in present]
        mine = set(nodes)
        for key, (w, r) in endpoints.items():
            topic = self.node.resolve_topic_name(TOPICS[key].name)
            nw = own_endpoints(self.node.get_publishers_info_by_topic(topic), mine, ns)
            nr = own_endpoints(self.node.get_subscriptions_info_by_topic(topic), mine, ns)
            if nw < w:
                out.append(f"{topic}: {nw}/{w} writers")
            if nr < r:
                out.append(f"{topic}: {nr}/{r} readers")
        return out

    def call_trigger(self, service: str, timeout: float = 10.0) -> tuple[bool, str]:
        from std_srvs.srv import Trigger

        cli = self.node.create_client(Trigger, service)
        try:
            if not cli.wait_for_service(timeout_sec=timeout):
                return False, f"service {service} is not available"
            fut = cli.call_async(Trigger.Request())
            end = time.monotonic() + timeout
            while not fut.done() and time.monotonic() < end:
                self.spin(0.05)
            if not fut.done():
                return False, f"service {service} did not answer within {timeout:g} s"
            res = fut.result()
            return res.success, res.message
        finally:
            self.node.destroy_client(cli)

    def close(self) -> None:
        self.executor.remove_node(self.node)
        self.executor.shutdown(timeout_sec=1.0)
        self.node.destroy_node()
        self.rclpy.try_shutdown()


class RunFollower:
    """The run as its statuses told it: ``last`` (the newest fields, with the tick) and when the
    first tick ran, for the launcher and for ``homeo-launch watch``."""

    def __init__(self, last: dict | None = None):
        self.last = {} if last is None else last
        self.t_start: float | None = None
        self._seen = None

    def take(self, status) -> bool:
        """Take the monitor's status if it is new (True)."""
        if status is None or status is self._seen:
            return False
        self._seen = status
        if self.t_start is None and status.fields["state"] in ("running", "finishing", "done"):
            self.t_start = time.monotonic()
        self.last.update(status.fields, tick=status.tick)
        return True

    def elapsed_s(self) -> float:
        """The run's own time (its status's ``extra.elapsed_s``), else the time since its first tick."""
        own = (self.last.get("extra") or {}).get("elapsed_s")
        if own is not None:
            return own
        return time.monotonic() - self.t_start if self.t_start is not None else 0.0


def wait_until_up(graph: Graph, mon: Monitor, nodes, endpoints, bound: float, check=None) -> None:
    """Until every node and endpoint of the graph is discovered; ``check`` (default: no node has
    died) runs on every turn and raises to stop the wait."""
    end = time.monotonic() + bound
    while True:
        check() if check is not None else check_alive(graph)
        missing = mon.missing(nodes, endpoints)
        if not missing:
            return
        if time.monotonic() > end:
            raise GraphError(f"the graph did not come up within {bound:g} s; missing: {'; '.join(missing)}")
        mon.spin(0.1)


def check_alive(graph: Graph) -> None:
    dead = graph.dead()
    if dead:
        name, code = dead
        tail = graph.log_tail(name)
        raise GraphError(f"node {name} exited with code {code}" + (f"; its last output:\n{tail}" if tail else ""))



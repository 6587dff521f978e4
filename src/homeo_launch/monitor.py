"""The launcher's own node: discovery of the graph, its run status, service and parameter calls."""

from __future__ import annotations

import time

from homeo_msgs_py.graph import TOPICS

from .processes import Graph

DISCOVERY_TIMEOUT_S = 60.0


class GraphError(Exception):
    """The graph failed: a node died or never came up. Exit code 1."""


class Monitor:
    """The launcher's own node: watches discovery, /homeo/run_status, and calls services."""

    def __init__(self):
        import rclpy
        from rclpy.signals import SignalHandlerOptions
        from std_msgs.msg import String

        from homeo_msgs_py.qos import sub_qos
        from homeo_msgs_py.schemas import Rejected, Vocabulary, decode

        from rclpy.executors import SingleThreadedExecutor

        rclpy.init(signal_handler_options=SignalHandlerOptions.NO)  # Ctrl-C stays a KeyboardInterrupt here
        self.rclpy = rclpy
        self.node = rclpy.create_node("homeo_launch")
        # one executor for the node's life: rclpy.spin_once(node) adds and removes the node every call
        self.executor = SingleThreadedExecutor()
        self.executor.add_node(self.node)
        self.status = None
        voc = Vocabulary()

        def on_status(msg: String) -> None:
            try:
                self.status = decode(msg.data, voc, "homeo/run_status")
            except Rejected:
                pass

        self.node.create_subscription(String, TOPICS["run_status"].name, on_status, sub_qos("run_status"))

    def spin(self, timeout: float = 0.05) -> None:
        self.executor.spin_once(timeout_sec=timeout)

    def missing(self, nodes, endpoints) -> list[str]:
        present = set(self.node.get_node_names())
        out = [f"node {n}" for n in nodes if n not in present]
        for key, (w, r) in endpoints.items():
            topic = TOPICS[key].name
            nw, nr = self.node.count_publishers(topic), self.node.count_subscribers(topic)
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


def wait_until_up(graph: Graph, mon: Monitor, nodes, endpoints, bound: float) -> None:
    end = time.monotonic() + bound
    while True:
        check_alive(graph)
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



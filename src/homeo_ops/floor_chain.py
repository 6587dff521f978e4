"""The benchmark floor: a ring of processes that pass a message on with empty callbacks.

Process i reads /homeo_floor/hop{i-1} and writes /homeo_floor/hop{i}; process 0 starts each
round and times ``iterations`` rounds of ``hops`` publish-receive hops, as many hops per
round as the graph's tick has on its critical path. It prints ``{"s_per_tick": x}``.
Parameters: index, hops, iterations, executor (the graph's: rclpy's EventsExecutor or its
SingleThreadedExecutor, so the floor runs on the executor the graph runs on).
"""

from __future__ import annotations

import json
import sys
import time

from rclpy.node import Node
from std_msgs.msg import String

from homeo_msgs_py.node_base import EXECUTOR, run_node
from homeo_msgs_py.qos import EVENT, quiet_pub_events, quiet_sub_events

PAYLOAD = "x" * 300  # about the size of a homeo message


class FloorNode(Node):
    def __init__(self):
        super().__init__("homeo_floor")
        self.index = self.declare_parameter("index", 0).value
        self.hops = self.declare_parameter("hops", 4).value
        self.iterations = self.declare_parameter("iterations", 1000).value
        self.executor_kind = self.declare_parameter(EXECUTOR.name, EXECUTOR.default).value  # run_node's executor
        prev = (self.index - 1) % self.hops
        # the same endpoint settings as the graph's nodes, so the comparison is like for like
        self.pub = self.create_publisher(String, f"/homeo_floor/hop{self.index}", EVENT,
                                         event_callbacks=quiet_pub_events())
        cb = self._relay if self.index else self._round
        self.create_subscription(String, f"/homeo_floor/hop{prev}", cb, EVENT, event_callbacks=quiet_sub_events())
        if self.index == 0:
            self.n = -1  # -1: warming up until one round trip made it
            self.msg = String(data=PAYLOAD)
            self.warm = self.create_timer(0.2, lambda: self.pub.publish(String(data="warm")))

    def _relay(self, msg: String) -> None:
        self.pub.publish(msg)

    def _round(self, msg: String) -> None:
        if self.n < 0:
            if msg.data != "warm":
                return
            self.warm.cancel()
            self.n, self.t0 = 0, time.perf_counter()
        elif msg.data == "warm":
            return
        else:
            self.n += 1
        if self.n >= self.iterations:
            print(json.dumps({"s_per_tick": (time.perf_counter() - self.t0) / self.iterations}), flush=True)
            self.context.try_shutdown()  # run_node's spin ends (an exception out of a callback would not, on every executor)
            return
        self.pub.publish(self.msg)


def main(args=None) -> int:
    return run_node(FloorNode, args)


if __name__ == "__main__":
    sys.exit(main())

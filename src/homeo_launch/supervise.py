"""Supervision of a running graph, as ROS launch's ``respawn``: a node that dies is started again
after a back-off and reloads its last checkpoint (``homeo_decision.durable``: parameters
``respawned`` and ``resume_dir``). A robot node rejoins the ticks; the world node's lockstep counts
the ticks it missed meanwhile. A restarted world node goes on with the same run after the newest
tick the robot nodes answered (``homeo_msgs_py.world_rejoin``); the ticks since its checkpoint are
counted as missed. A node that dies more than ``max_restarts`` times stops the graph with one line
naming it. Restarts are reported on ``/diagnostics`` and in the run's output.
"""

from __future__ import annotations

import os
import sys
import time

from homeo_msgs_py.graph import NODES

from . import monitor
from .monitor import GraphError
from .processes import Graph

BACKOFF_S = (0.5, 1.0, 2.0, 4.0)  # before the 1st, 2nd, 3rd, ... restart of a node
MAX_RESTARTS = 3
CONFIG_ERROR = 2  # a node's exit code for a bad start-up configuration (node_base.run_node)
DIAG_PERIOD_S = 1.0


class Supervisor:
    def __init__(self, graph: Graph, node=None, max_restarts: int = MAX_RESTARTS, checkpoint_dir: str = "",
                 log=None, clock=time.monotonic, spool=None):
        self.graph, self.max_restarts, self.checkpoint_dir = graph, max_restarts, checkpoint_dir
        self.log = log or (lambda text: print(text, file=sys.stderr))
        self.clock = clock
        self.restarts: dict[str, int] = {}
        self._due: dict[str, float] = {}  # node -> when to start it again
        self._pub = self._diag_at = None
        self._node = node
        self._spool = spool  # recording at the writers: the launcher keeps what it publishes too
        if node is not None:
            from diagnostic_msgs.msg import DiagnosticArray

            self._pub = node.create_publisher(DiagnosticArray, "/diagnostics", 10)
            self._diag_at = 0.0

    def respawnable(self, name: str) -> bool:
        return self.max_restarts > 0 and name in NODES

    def check(self) -> None:
        """Call often: restart dead nodes when their back-off is over; raise GraphError for a node that
        may not be restarted."""
        now = self.clock()
        g = self.graph
        for name, p in list(g.procs.items()):
            code = p.poll()
            if code is None:
                continue
            n = self.restarts.get(name, 0)
            if not self.respawnable(name) or code == CONFIG_ERROR:  # a bad configuration stays bad
                tail = g.log_tail(name)
                what = "node" if name in NODES else "process"  # a companion (a stand-in robot) is not restarted
                raise GraphError(f"{what} {name} exited with code {code}" + (f"; its last output:\n{tail}" if tail else ""))
            if n >= self.max_restarts:
                raise GraphError(f"node {name} died {n + 1} times (last exit code {code}); stopping the graph")
            delay = BACKOFF_S[min(n, len(BACKOFF_S) - 1)]
            self.log(f"homeo-launch: node {name} exited with code {code}; restarting it in {delay:g} s "
                     f"(restart {n + 1} of at most {self.max_restarts})")
            del g.procs[name]
            _keep_log(g, name, n + 1)
            self._due[name] = now + delay
        for name, at in list(self._due.items()):
            if now >= at:
                del self._due[name]
                self._respawn(name)
        if self._pub is not None and (self.restarts and now - self._diag_at >= DIAG_PERIOD_S):
            self.publish()
            self._diag_at = now

    def _respawn(self, name: str) -> None:
        spec = next(s for s in self.graph.specs if s.name == name)
        spec.params["respawned"] = True
        if self.checkpoint_dir:
            spec.params["resume_dir"] = self.checkpoint_dir  # its own latest checkpoint of this launch
        self.graph.start([name])
        self.restarts[name] = self.restarts.get(name, 0) + 1
        if self._pub is not None:
            self.publish()

    def publish(self) -> None:
        from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

        arr = DiagnosticArray()
        arr.header.stamp = self._node.get_clock().now().to_msg()
        total = sum(self.restarts.values())
        arr.status = [DiagnosticStatus(
            level=bytes([1 if total else 0]), name="homeo_launch: supervision", hardware_id="homeo_launch",
            message=", ".join(f"{n} restarted {k}x" for n, k in sorted(self.restarts.items())) or "no restarts",
            values=[KeyValue(key=n, value=str(k)) for n, k in sorted(self.restarts.items())])]
        self._pub.publish(arr)
        if self._spool is not None:
            from rclpy.serialization import serialize_message

            self._spool.cdr("/diagnostics", serialize_message(arr))


def _keep_log(g: Graph, name: str, n: int) -> None:
    """The dead process's log stays as NAME.N.log; the new one writes NAME.log."""
    src = g.log_dir / f"{name}.log"
    try:
        os.replace(src, g.log_dir / f"{name}.{n}.log")
    except OSError:
        pass


def wait_until_up(graph: Graph, mon, check, nodes, endpoints, bound: float) -> None:
    """``monitor.wait_until_up`` with supervision: the run may start (the world node decides) while
    the launcher is still discovering, and a node that dies then is restarted as later (``check``:
    ``Supervisor.check``, with whatever else the launcher watches)."""
    monitor.wait_until_up(graph, mon, nodes, endpoints, bound, check=check)

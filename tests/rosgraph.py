"""Helpers for tests that start node processes: a fresh ROS_DOMAIN_ID each, a probe node
in the test process, bounded waits. Everything stays on loopback."""

from __future__ import annotations

import itertools
import json
import os
import time
from contextlib import contextmanager
from pathlib import Path

from homeo_launch.processes import dds_defaults

os.environ.update(dds_defaults())  # before any rclpy context of the test process

# domain ids 0..232 are valid; the tests take 100..229, or the range HOMEO_TEST_DOMAINS=LO-HI names
# (two checkouts testing side by side on one machine, each in its own range). Each pytest-xdist worker
# (``make test`` runs two) has a share of its own, so two tests running at once never meet on one
# domain; a plain pytest session spreads its start by pid, for two sessions side by side.
_LO, _HI = (int(x) for x in os.environ.get("HOMEO_TEST_DOMAINS", "100-229").split("-"))
_WORKER = os.environ.get("PYTEST_XDIST_WORKER", "")
_WORKERS = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1") or 1)
_SPAN = (_HI - _LO + 1) // max(_WORKERS, 1)
_START = (_LO + int(_WORKER[2:]) * _SPAN if _WORKER[2:].isdigit()
          else _LO + (os.getpid() * 3) % (_HI - _LO + 1))
_DOMAINS = itertools.count(0)


def fresh_domain() -> int:
    d = next(_DOMAINS)
    if _WORKER:
        return _START + d % _SPAN
    return _LO + (_START - _LO + d) % (_HI - _LO + 1)


class Probe:
    """An rclpy node in the test process, on the test's own domain."""

    def __init__(self, domain: int):
        import rclpy
        from rclpy.context import Context

        self.rclpy = rclpy
        self.ctx = Context()
        rclpy.init(context=self.ctx, domain_id=domain)
        from rclpy.executors import SingleThreadedExecutor

        self.node = rclpy.create_node(f"probe_{os.getpid()}", context=self.ctx)
        self.ex = SingleThreadedExecutor(context=self.ctx)
        self.ex.add_node(self.node)

    def spin_until(self, cond, timeout: float) -> bool:
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if cond():
                return True
            self.ex.spin_once(timeout_sec=0.05)
        return cond()

    def collect(self, topic: str) -> list:
        """Decoded JSON of every message on a homeo topic, appended as they arrive."""
        from std_msgs.msg import String

        from homeo_msgs_py.graph import key_of
        from homeo_msgs_py.qos import sub_qos

        got: list = []
        self.node.create_subscription(String, topic, lambda m: got.append(json.loads(m.data)), sub_qos(key_of(topic)))
        return got

    def diagnostics(self) -> dict:
        """Latest DiagnosticStatus per status name, as plain dicts."""
        from diagnostic_msgs.msg import DiagnosticArray

        latest: dict = {}

        def cb(arr):
            for s in arr.status:
                latest[s.name] = {"message": s.message, "values": {kv.key: kv.value for kv in s.values}}

        self.node.create_subscription(DiagnosticArray, "/diagnostics", cb, 50)
        return latest

    def publisher(self, topic: str):
        from std_msgs.msg import String

        from homeo_msgs_py.graph import key_of
        from homeo_msgs_py.qos import pub_qos

        pub = self.node.create_publisher(String, topic, pub_qos(key_of(topic)))
        return lambda text: pub.publish(String(data=text))

    def call(self, srv_type, name: str, request, timeout: float = 20.0):
        cli = self.node.create_client(srv_type, name)
        assert self.spin_until(lambda: cli.service_is_ready(), timeout), f"service {name} never came up"
        fut = cli.call_async(request)
        assert self.spin_until(fut.done, timeout), f"{name} did not answer"
        return fut.result()

    def set_param(self, node: str, name: str, value, timeout: float = 20.0):
        from rcl_interfaces.srv import SetParameters
        from rclpy.parameter import Parameter

        req = SetParameters.Request(parameters=[Parameter(name, value=value).to_parameter_msg()])
        return self.call(SetParameters, f"{node}/set_parameters", req, timeout).results[0]

    def close(self):
        self.node.destroy_node()
        self.rclpy.try_shutdown(context=self.ctx)


def child_pid(parent: int, module: str) -> int | None:
    """The pid of ``parent``'s child process running ``python -m module``."""
    for d in Path("/proc").iterdir():
        if not d.name.isdigit():
            continue
        try:
            ppid = int((d / "stat").read_text().rsplit(")", 1)[1].split()[1])
            cmd = (d / "cmdline").read_bytes().split(b"\0")
        except (OSError, IndexError, ValueError):
            continue
        if ppid == parent and module.encode() in cmd:
            return int(d.name)
    return None


def failure_report(proc, out: str, err: str, logs: Path) -> str:
    """What the next person needs when a launched graph test fails: the launcher's exit code and
    output, and the end of every node's log under ``logs``."""
    return f"exit {proc.returncode}\nstdout: {(out or '')[-1500:]}\nstderr: {(err or '')[-3000:]}\n" + "\n".join(
        f"--- {f.name}\n{f.read_text(errors='replace')[-2500:]}" for f in sorted(logs.rglob("*.log")))


WORLD_KEYS = ("iterations", "rate", "action_timeout", "human", "human_timeout")


def sim_opts(**kw):
    """``launch.GraphOptions`` of the simulated world, from the flat settings ``homeo-launch sim`` takes."""
    from homeo_launch.launch import GraphOptions

    world = {"iterations": kw.pop("iterations", 5000)}
    world.update({k: kw.pop(k) for k in WORLD_KEYS if k in kw})
    return GraphOptions(world=kw.pop("world", "sim"), world_params=world, **kw)


@contextmanager
def sim_graph(opts, domain: int):
    """The four nodes of the simulated graph as processes on ``domain``; stopped and checked on exit."""
    from homeo_launch.launch import graph_specs
    from homeo_launch.processes import Graph, graph_env

    g = Graph(graph_specs(opts), graph_env(domain), namespace=opts.namespace, auth=opts.auth)
    g.start()
    try:
        yield g
    finally:
        g.stop()
        g.close()


def wait_spooled_actions(data_dir: Path, proc, n: int, bound: float = 120.0) -> None:
    """Until the decision node of a run recording at the writers into ``data_dir`` has kept ``n``
    actions in its spool (``proc``: the launcher, which must not end meanwhile)."""
    from homeo_msgs_py.spool import read_spool

    end = time.monotonic() + bound
    while True:
        assert proc.poll() is None and time.monotonic() < end, proc.stderr.read() if proc.poll() is not None else ""
        kept = [r for f in data_dir.glob(".homeo-record-*/homeo_decision-*.spool") for r in read_spool(f)[0]
                if r.topic == "/homeo/action"]
        if len(kept) >= n:
            return
        time.sleep(0.2)

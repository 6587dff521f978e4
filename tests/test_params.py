"""Every node's parameters survive ``ros2 param dump`` then ``ros2 param load`` (issue 11), on the graph
``homeo-launch sim`` starts, with the real ``ros2`` command line (``make ros2-tools``; under ``ros2 launch`` in a
colcon workspace: tests/test_ros2_workspace.py). Then a change of a start-only parameter is refused with a reason.
"""

from __future__ import annotations

import re
import subprocess
import time

import pytest

import ros2cli
from rosgraph import Probe, fresh_domain, sim_graph, sim_opts

from homeo_launch.processes import graph_env

pytestmark = pytest.mark.ros
# rclpy declares this one read-only on every Jazzy node: ``ros2 param load`` reports it on any node, as the
# ROS 2 parameters tutorial shows (osrf/ros2_test_cases#1117); all of ours load
ROS_OWN = {"start_type_description_service"}


def _ros2(args: list, env: dict, bound: float = 90.0) -> subprocess.CompletedProcess:
    """``ros2 ARGS``, again while it does not yet know the node: discovery (the ros2 daemon's too) is eventual."""
    end = time.monotonic() + bound
    while True:
        r = subprocess.run([str(ros2cli.BIN / "ros2"), *args], env=env, capture_output=True, text=True, timeout=120)
        if "Node not found" not in r.stderr or time.monotonic() > end:
            return r
        time.sleep(1.0)


@pytest.mark.parametrize("node", ["/homeo_world", "/homeo_intention", "/homeo_drives", "/homeo_decision"])
def test_dump_then_load_sets_every_parameter(tmp_path, node):
    ros2cli.require_tools()
    d = fresh_domain()
    env = ros2cli.env_with_venv(graph_env(d))
    with sim_graph(sim_opts(iterations=0, rate=5.0, overrides=(("initial_q", 0.5),), data_dir=str(tmp_path)), d):
        probe = Probe(d)
        try:
            r = _ros2(["param", "dump", node], env)
            assert r.returncode == 0 and "ros__parameters" in r.stdout, r.stderr
            assert "initial_q=0.5" in r.stdout  # a JSON object here would come back as a YAML mapping (rclpy#1507)
            f = tmp_path / "params.yaml"
            f.write_text(r.stdout)
            r = _ros2(["param", "load", node, str(f)], env)
            results = re.findall(r"Set parameter (\S+) (successful|failed)", r.stdout + r.stderr)
            assert len(results) >= 5 and {n for n, how in results if how == "failed"} == ROS_OWN, (r.stdout, r.stderr)
            # a start-only parameter keeps its value: a change is refused with the reason
            r = probe.set_param(node, "data_dir", str(tmp_path / "elsewhere"))
            assert not r.successful and "set when the node starts" in r.reason
        finally:
            probe.close()
            ros2cli.stop_daemon(env)

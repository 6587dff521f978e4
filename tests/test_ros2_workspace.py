"""The project in a ROS 2 Jazzy workspace, as a lab uses it: cloned into ``src/``, built by colcon,
sourced, and driven by the real ``ros2`` command line and launch system (``tests/ros2cli.py``).

- ``ros2 pkg list`` / ``executables`` see the package and every node;
- ``ros2 launch homeo_robot sim.launch.py iterations:=300`` runs the graph and ends with exit 0 and
  the run's metrics, also with ``params_file:=`` the shipped ``config/params.yaml`` or a file that
  ``ros2 param dump`` wrote, and the dumped parameters load back with ``ros2 param load``;
- Ctrl-C of ``ros2 launch``: every node exits 0, no traceback in any log, and the interrupted run's
  summary counts the ticks that ran;
- a path set over the network with ``ros2 param set`` outside the data directory is refused;
- ``ros2 run`` starts any executable of the package, a bad parameter is one line and exit 2; a parameters
  file rcl cannot parse is one line from ``ros2 run`` and from ``ros2 launch`` (before any node starts).
"""

from __future__ import annotations

import json
import os
import re
import signal
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

import ros2cli
from rosgraph import fresh_domain

pytestmark = [pytest.mark.ros, pytest.mark.slow]
NODE_NAMES = ("/homeo_world", "/homeo_intention", "/homeo_drives", "/homeo_decision")
ROS_OWN = ("use_sim_time", "start_type_description_service")


@pytest.fixture(scope="module")
def ws(tmp_path_factory):
    ros2cli.require_tools()
    return ros2cli.build_workspace(tmp_path_factory.mktemp("ws"))


@pytest.fixture
def env(tmp_path):
    from homeo_launch.processes import graph_env

    e = ros2cli.env_with_venv(graph_env(fresh_domain()))
    e["ROS_LOG_DIR"] = str(tmp_path / "roslog")
    yield e
    ros2cli.stop_daemon(e)


def _finished_cleanly(out: str) -> list[str]:
    """The launched processes that did not finish cleanly (launch says 'process has died' for them)."""
    return re.findall(r"process has died \[pid \d+, exit code (-?\d+), cmd '([^']*)'", out)


def test_the_package_and_every_node_executable_are_found(ws, env):
    from homeo_msgs_py.graph import NODES

    r = ros2cli.run(ws, "ros2 pkg list", env)
    assert r.returncode == 0 and ros2cli.PACKAGE in r.stdout.split(), r.stderr
    r = ros2cli.run(ws, f"ros2 pkg executables {ros2cli.PACKAGE}", env)
    found = {line.split()[1] for line in r.stdout.splitlines() if line.strip()}
    assert {n.executable for n in NODES.values()} | {"homeo-launch", "homeo-sim", "homeo-topic"} <= found, r.stdout
    prefix = Path(ros2cli.run(ws, f"ros2 pkg prefix {ros2cli.PACKAGE}", env).stdout.strip())
    share = prefix / "share" / ros2cli.PACKAGE
    assert {p.name for p in (share / "launch").iterdir()} == {"world.launch.py", "sim.launch.py", "pepper.launch.py"}
    assert {p.name for p in (share / "config").iterdir()} == {"params.yaml", "pepper.yaml"}


def test_ros2_launch_runs_the_graph_and_ends_with_exit_0_and_the_metrics(ws, env):
    r = ros2cli.run(ws, f"ros2 launch {ros2cli.PACKAGE} sim.launch.py iterations:=300 intention:=oracle seed:=3",
                    env, timeout=240)
    out = r.stdout + r.stderr
    assert r.returncode == 0, out[-3000:]
    assert "300 iterations x 1 seed" in out and re.search(r"HSR\s+0\.\d+", out), out[-3000:]
    assert not _finished_cleanly(out) and out.count("process has finished cleanly") == 5, out[-3000:]


def test_ros2_launch_runs_a_world_nobody_here_wrote_by_its_name(ws, env):
    """The example package (examples/homeo_rover: a robot of one's own, built beside the project in the
    workspace) through ``world.launch.py world:=rover``, its own parameter a launch argument; and the
    arguments of every installed world listed, the Pepper's and the rover's among them."""
    r = ros2cli.run(ws, f"ros2 launch {ros2cli.PACKAGE} world.launch.py --show-args", env)
    assert r.returncode == 0 and "'speed'" in r.stdout and "'qi_url'" in r.stdout and "'world'" in r.stdout, r.stdout
    r = ros2cli.run(ws, f"ros2 launch {ros2cli.PACKAGE} world.launch.py world:=rover iterations:=100 speed:=2.0",
                    env, timeout=240)
    out = r.stdout + r.stderr
    assert r.returncode == 0 and "100 ticks, 0 missed" in out and "Traceback" not in out, out[-3000:]
    assert not _finished_cleanly(out), out[-3000:]
    for bad, why in (("speed:=0", "launch argument speed = 0.0 is outside"),  # the rover's declaration refuses it
                     ("human:=person", "launch argument human is not one of world rover's")):  # another world's
        r = ros2cli.run(ws, f"ros2 launch {ros2cli.PACKAGE} world.launch.py world:=rover {bad}", env, timeout=120)
        out = r.stdout + r.stderr
        assert r.returncode != 0 and why in out and "process started" not in out, out[-3000:]


def test_ros2_run_starts_an_executable_and_a_bad_parameter_is_one_line(ws, env):
    r = ros2cli.run(ws, f"ros2 run {ros2cli.PACKAGE} homeo-sim run --iterations 200 --json --quiet", env)
    assert r.returncode == 0 and json.loads(r.stdout)["iterations"] == 200, r.stderr
    r = ros2cli.run(ws, f"ros2 run {ros2cli.PACKAGE} homeo-world-node --ros-args -p world:=tiago", env)
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert r.returncode == 2 and len(lines) == 1 and "no world 'tiago'" in lines[0], r.stderr


def test_a_params_file_rcl_cannot_parse_is_one_line_from_ros2_run_and_ros2_launch(ws, env, tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("homeo_decision:\n  ros__parameters:\n    seed: [1, {a: 2}\n")  # an unclosed list
    r = ros2cli.run(ws, f"ros2 run {ros2cli.PACKAGE} homeo-decision-node --ros-args --params-file {bad}", env)
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert r.returncode == 2 and len(lines) == 1 and "Couldn't parse params file" in lines[0], r.stderr
    r = ros2cli.run(ws, f"ros2 launch {ros2cli.PACKAGE} sim.launch.py params_file:={bad}", env, timeout=120)
    out = r.stdout + r.stderr
    assert r.returncode != 0 and "launch argument params_file: Couldn't parse params file" in out, out[-3000:]
    assert "Traceback" not in out and "process started" not in out, out[-3000:]  # refused before any node


def _wait_subscribed(ws, env, topic: str, node: str, bound: float = 60.0) -> None:
    """Until ``ros2 topic info -v TOPIC`` lists ``node`` among its subscribers."""
    end = time.monotonic() + bound
    while time.monotonic() < end:
        info = ros2cli.run(ws, f"ros2 topic info -v {topic}", env, timeout=30).stdout
        subscribers = info.split("Subscription count:", 1)[-1]
        if re.search(rf"^Node name: {node}$", subscribers, re.M):
            return
        time.sleep(0.5)
    raise AssertionError(f"{node} never subscribed to {topic}")


def _wait_running(ws, env, proc, bound: float = 90.0) -> None:
    end = time.monotonic() + bound
    while time.monotonic() < end:
        assert proc.poll() is None, proc.stdout.read()[-3000:]
        r = ros2cli.run(ws, "ros2 topic echo --once --full-length --qos-durability transient_local --qos-reliability reliable /homeo/run_status", env, timeout=30)
        if r.returncode == 0 and "running" in r.stdout:
            return
    raise AssertionError("the graph did not start running")


def test_params_dump_load_and_params_file_and_paths_set_over_the_network(ws, env, tmp_path):
    launch = ros2cli.popen(ws, f"ros2 launch {ros2cli.PACKAGE} sim.launch.py iterations:=0 rate:=20 dod:=0.4", env)
    dump = tmp_path / "dump.yaml"
    try:
        _wait_running(ws, env, launch)
        texts = []
        for node in NODE_NAMES:
            r = ros2cli.run(ws, f"ros2 param dump {node}", env)
            assert r.returncode == 0 and "ros__parameters" in r.stdout, r.stderr
            texts.append(r.stdout)
            (tmp_path / f"{node[1:]}.yaml").write_text(r.stdout)
        dump.write_text("\n".join(texts))
        for node in NODE_NAMES:  # each node's own dump loads back into it
            r = ros2cli.run(ws, f"ros2 param load {node} {tmp_path / (node[1:] + '.yaml')}", env)
            results = re.findall(r"Set parameter (\S+) (successful|failed)", r.stdout + r.stderr)
            bad = [n for n, how in results if how == "failed" and n not in ROS_OWN]
            assert results and not bad, (node, r.stdout, r.stderr)
        assert "0.4" in ros2cli.run(ws, "ros2 param get /homeo_decision dod", env).stdout
        for outside in ("/etc/x.json", "~/x.json"):  # over the network: only inside the data directory
            r = ros2cli.run(ws, f"ros2 param set /homeo_decision q_table_path '{outside}'", env)
            assert "outside the data directory" in r.stdout + r.stderr, (outside, r.stdout, r.stderr)
        assert "successful" in ros2cli.run(ws, "ros2 param set /homeo_decision q_table_path q.json", env).stdout
    finally:
        os.killpg(launch.pid, signal.SIGINT)
        out = launch.communicate(timeout=60)[0]
    assert launch.returncode == 0 and not _finished_cleanly(out), out[-3000:]
    for params in (dump, "$(ros2 pkg prefix homeo_robot)/share/homeo_robot/config/params.yaml"):
        r = ros2cli.run(ws, f"ros2 launch {ros2cli.PACKAGE} sim.launch.py iterations:=150 params_file:={params}",
                        env, timeout=240)
        out = r.stdout + r.stderr
        assert r.returncode == 0 and "150 iterations x 1 seed" in out and not _finished_cleanly(out), out[-3000:]
    # the dumped rate (20 ticks/s) was taken from the file: 150 ticks took at least 7 s
    seconds = float(re.search(r"graph: ([\d.]+) s for 150 ticks", ros2cli.run(
        ws, f"ros2 launch {ros2cli.PACKAGE} sim.launch.py iterations:=150 params_file:={dump}", env,
        timeout=240).stdout).group(1))
    assert seconds >= 7.0


def test_ctrl_c_of_ros2_launch_stops_every_node_with_exit_0_and_no_traceback(ws, env, tmp_path):
    from homeo_msgs_py.graph import LAUNCHER

    launch = ros2cli.popen(ws, f"ros2 launch {ros2cli.PACKAGE} sim.launch.py iterations:=0 rate:=50", env)
    try:
        _wait_running(ws, env, launch)
        # the summary comes from what the launch's watcher received: on a busy machine it may discover
        # the graph seconds after the graph runs (a CI-like run once interrupted it before it had a status)
        _wait_subscribed(ws, env, "/homeo/run_status", LAUNCHER)
        time.sleep(2.0)
    finally:
        os.killpg(launch.pid, signal.SIGINT)  # a terminal's Ctrl-C reaches the whole foreground group
        out = launch.communicate(timeout=60)[0]
    assert launch.returncode == 0, out[-3000:]
    assert not _finished_cleanly(out) and out.count("process has finished cleanly") == 5, out[-3000:]
    logs = [p for p in Path(env["ROS_LOG_DIR"]).rglob("*") if p.is_file()]
    assert logs and not [p for p in logs if "Traceback" in p.read_text(errors="replace")]
    assert "Traceback" not in out
    # the interrupted run's summary counts the ticks that ran, with their time
    m = re.search(r"scenario \S+: (\d+) iterations x 1 seed", out)
    g = re.search(r"graph: ([\d.]+) s for (\d+) ticks \(([\d.]+) ms/tick\)", out)
    assert m and g and int(m.group(1)) == int(g.group(2)) > 50 and float(g.group(3)) > 0, out[-3000:]


def test_the_shipped_parameter_files_are_the_nodes_own(env):
    import subprocess
    import sys

    for world, name in (("sim", "params.yaml"), ("pepper", "pepper.yaml")):
        r = subprocess.run([sys.executable, "-m", "homeo_launch.params_yaml", world], env=env, capture_output=True,
                           text=True, timeout=120)
        assert r.returncode == 0, r.stderr
        assert r.stdout == (ros2cli.REPO / "config" / name).read_text(), \
            f"regenerate: python -m homeo_launch.params_yaml {world} > config/{name}"


def test_package_xml_names_every_runtime_dependency_by_its_rosdep_key():
    """Every dependency of pyproject.toml is in package.xml by its rosdep key (ros/rosdistro
    rosdep/python.yaml), or is one of those rosdep has no key for, said so in package.xml."""
    import tomllib

    root = ET.parse(ros2cli.REPO / "package.xml").getroot()
    assert root.get("format") == "3" and root.findtext("name") == ros2cli.PACKAGE
    assert root.find("export/build_type").text == "ament_python"
    deps = {e.text for e in root if e.tag.endswith("depend")}
    text = (ros2cli.REPO / "package.xml").read_text()
    rosdep = {"numpy": "python3-numpy", "matplotlib": "python3-matplotlib", "tqdm": "python3-tqdm",
              "websockets": "python3-websockets", "pytest": "python3-pytest", "pytest-xdist": "python3-pytest-xdist",
              "hypothesis": "python3-hypothesis",
              "ros-jazzy-rclpy": "rclpy", "ros-jazzy-common-interfaces": "std_msgs",
              "ros-jazzy-rmw-fastrtps-cpp": "rclpy"}
    no_key = ("pgmpy", "qi", "rosbags", "mcap", "mcap-ros2-support", "foxglove-sdk", "msgspec")
    project = tomllib.loads((ros2cli.REPO / "pyproject.toml").read_text())["project"]
    for req in project["dependencies"]:
        name = re.split(r"[=<>!~\[]", req)[0]
        if name in no_key:
            assert f"{name}," in text or f"{name} " in text, f"package.xml does not say {name} has no rosdep key"
        else:
            assert rosdep[name] in deps, f"{name}: {rosdep[name]} is not a dependency in package.xml"
    assert (ros2cli.REPO / "resource" / ros2cli.PACKAGE).exists()


def test_a_node_killed_under_ros2_launch_is_respawned_and_rejoins_the_run(ws, env, tmp_path):
    """As homeo-launch's supervisor does: the launch respawns it, it finds this launch's checkpoints
    (respawn_rejoins) and goes on with its learned state; the run completes, every process exits 0."""
    import subprocess

    # 50 s at 20 ticks/s: the kill comes at its first checkpoint (tick 100), long before the end on a busy machine
    launch = ros2cli.popen(ws, f"ros2 launch {ros2cli.PACKAGE} sim.launch.py iterations:=1000 rate:=20 "
                               f"data_dir:={tmp_path / 'out'}", env)
    try:
        ck = tmp_path / "out" / "checkpoints" / "sim" / "homeo_decision.json"
        end = time.monotonic() + 120
        while not ck.exists() and time.monotonic() < end and launch.poll() is None:  # its first checkpoint
            time.sleep(0.2)
        # this launch's decision node: launch and its nodes share the session ros2cli.popen began
        victim = subprocess.run(["pgrep", "-s", str(launch.pid), "-f", f"lib/{ros2cli.PACKAGE}/homeo-decision-node"],
                                capture_output=True, text=True).stdout.split()
        assert ck.exists() and len(victim) == 1, victim
        os.kill(int(victim[0]), signal.SIGKILL)
        out = launch.communicate(timeout=180)[0]
    finally:
        if launch.poll() is None:
            os.killpg(launch.pid, signal.SIGINT)
            launch.communicate(timeout=60)
    assert launch.returncode == 0, out[-3000:]
    died = _finished_cleanly(out)
    assert len(died) == 1 and died[0][0] == "-9" and "homeo-decision-node" in died[0][1], died
    assert "a respawn, rejoining the run" in out and "1000 iterations x 1 seed" in out, out[-3000:]
    assert out.count("process has finished cleanly") == 5, out[-3000:]

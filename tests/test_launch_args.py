"""``homeo-launch`` checks its options against the nodes' ranges and the file rules before any
node starts: one line, exit 2 (issue 11). Nothing here starts a node."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import pytest

from homeo_launch.processes import check_namespace


def _launch(*args, cwd=None):
    t = time.monotonic()
    p = subprocess.run([sys.executable, "-m", "homeo_launch.cli", *map(str, args)], capture_output=True, text=True,
                       timeout=60, cwd=cwd)
    return p, time.monotonic() - t


@pytest.mark.parametrize("args, words", [
    (("sim", "--seed", 2**31), ["--seed", "outside [0, 2147483647]"]),  # the node's own range (WORLD_PARAMS)
    (("sim", "--iterations", 10**10), ["--iterations", "outside [0, 1000000000]"]),
    (("sim", "--seed", "9" * 5000), ["--seed", "must be an integer"]),
    (("sim", "--namespace", "1r"), ["not a ROS name"]),
    (("sim", "--namespace", "r/../x"), ["not a ROS name"]),
    (("sim", "--load-q", "/etc/hostname"), ["/etc/hostname", "not JSON"]),
    (("sim", "--trace", "/proc/x/t.jsonl"), ["--trace", "/proc/x"]),
    (("sim", "--log-dir", "/proc/nope"), ["--log-dir"]),
    (("pepper", "--standin", "--q-table", "/etc/hostname"), ["/etc/hostname", "not JSON"]),
    (("pepper", "--standin", "--seed", -1), ["outside [0, 2147483647]"]),
    (("pepper", "--standin", "--qi-url", "tcp://127.0.0.1:9"), ["qi_url and standin"]),
    (("pepper", "--script", "field_user.json"), ["script needs standin"]),
    (("day", "--day", "/"), ["day script", "/"]),
])
def test_a_bad_option_is_one_line_and_exit_2(tmp_path, args, words):
    p, _ = _launch(*args, cwd=tmp_path)
    assert p.returncode == 2, (p.returncode, p.stderr)
    lines = p.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("homeo-launch: error:") and "Traceback" not in p.stderr, p.stderr
    for w in words:
        assert w in lines[0], lines[0]


def test_save_q_that_is_a_directory(tmp_path):
    (tmp_path / "out" / "q").mkdir(parents=True)
    p, _ = _launch("sim", "--save-q", "out/q", cwd=tmp_path)
    assert p.returncode == 2 and "is a directory" in p.stderr and len(p.stderr.splitlines()) == 1, p.stderr


def test_namespaces():
    assert check_namespace("r1") == "/r1" and check_namespace("/a/b_2/") == "/a/b_2" and check_namespace("") == ""
    for bad in ("1a", "a b", "a//b", "é", "a-b"):
        with pytest.raises(ValueError):
            check_namespace(bad)


def test_data_dir_resolution(tmp_path):
    from homeo_msgs_py.data_dir import OutsideDataDir, resolve

    base = tmp_path / "out"
    base.mkdir()
    (base / "sub").mkdir()
    (base / "link").symlink_to(tmp_path)  # a link out of the data directory
    assert resolve(str(base), "q.json") == str(base / "q.json")
    assert resolve(str(base), str(base / "sub" / "q.json")) == str(base / "sub" / "q.json")
    assert resolve(str(base), "sub/../q.json") == str(base / "q.json")
    assert resolve(str(base), "") == ""
    for bad in ("../q.json", "/etc/passwd", "link/q.json", str(tmp_path / "q.json"), ".", "a\0b"):
        with pytest.raises(OutsideDataDir):
            resolve(str(base), bad)


def _launch_values(**given) -> dict:
    from homeo_launch.ros_launch import COMMON, values, world_args

    return values({**{n: d for n, d, _ in COMMON}, **{n: "" for n in world_args("sim")}, **given}, "sim")


@pytest.mark.parametrize("given, ns", [("", ""), ("r1", "/r1"), ("/r1/", "/r1"), ("r1/a", "/r1/a")])
def test_ros2_launch_namespace_is_the_nodes_own_in_the_recording_too(tmp_path, given, ns):
    """``ros2 launch homeo_robot sim.launch.py namespace:=r1 record:=BAG``: the nodes publish under /r1, and
    the recorder keeps the topics its manifest names, so the manifest must name /r1/homeo/..., not
    r1/homeo/... (a bag of /diagnostics alone, as it was)."""
    from homeo_record.record import read_manifest
    from homeo_launch.ros_launch import _recording

    v = _launch_values(namespace=given, record=str(tmp_path / "bag"), data_dir=str(tmp_path))
    assert v["namespace"] == ns
    from homeo_decision.scenario import load_scenario

    _bag, _launcher, _settings, topics = read_manifest(Path(_recording(v, "sim", load_scenario(), None)))
    names = [t.name for t in topics if t.name != "/diagnostics"]
    assert names and all(n.startswith(f"{ns}/homeo/") for n in names), names


@pytest.mark.parametrize("bad", ["1r", "r/../x", "a b"])
def test_ros2_launch_namespace_that_is_not_a_ros_name_is_one_line(bad):
    from homeo_launch.ros_launch import LaunchArgError

    with pytest.raises(LaunchArgError, match="^launch argument namespace .* is not a ROS name"):
        _launch_values(namespace=bad)

"""``homeo-launch`` checks its options against the nodes' ranges and the file rules before any
node starts: one line, exit 2 (issue 11). Nothing here starts a node."""

from __future__ import annotations

import subprocess
import sys
import time

import pytest

from homeo_launch.processes import check_namespace


def _launch(*args, cwd=None):
    t = time.monotonic()
    p = subprocess.run([sys.executable, "-m", "homeo_launch.cli", *map(str, args)], capture_output=True, text=True,
                       timeout=60, cwd=cwd)
    return p, time.monotonic() - t


@pytest.mark.parametrize("args, words", [
    (("sim", "--seed", 2**31), ["--seed", "above the maximum 2147483647"]),
    (("sim", "--iterations", 10**10), ["--iterations", "above the maximum"]),
    (("sim", "--seed", "9" * 5000), ["--seed", "is not an integer"]),
    (("sim", "--namespace", "1r"), ["not a ROS name"]),
    (("sim", "--namespace", "r/../x"), ["not a ROS name"]),
    (("sim", "--load-q", "/etc/hostname"), ["/etc/hostname", "not JSON"]),
    (("sim", "--trace", "/proc/x/t.jsonl"), ["--trace", "/proc/x"]),
    (("sim", "--log-dir", "/proc/nope"), ["--log-dir"]),
    (("pepper", "--standin", "--q-table", "/etc/hostname"), ["/etc/hostname", "not JSON"]),
    (("pepper", "--standin", "--seed", -1), ["below the minimum 0"]),
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

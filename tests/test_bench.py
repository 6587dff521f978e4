"""``homeo-launch bench``: where a tick's time goes (py-spy's samples put in the budget's categories),
the rounds' alternation, and a small run of the whole command (the profile and the checkpoints'
comparison included) over DDS."""

from __future__ import annotations

import json
import re
import subprocess
import sys

import pytest

from homeo_launch.ops import bench, profile

MAIN = "thread (100): MainThread;_run_module_as_main (<frozen runpy>:198);run_node (homeo_msgs_py/node_base.py:378)"
SPIN = MAIN + ";SingleThreadedExecutor.spin_once (rclpy/executors.py:839)"
CB = SPIN + ";Executor._take_subscription.<locals>._execute (rclpy/executors.py:406);HomeoNode.subscribe.<locals>.cb " \
            "(homeo_msgs_py/node_base.py:223)"


def test_each_sample_goes_to_the_category_of_its_innermost_named_frame():
    wait = profile.wait_frames()[0]
    raw = "\n".join([
        f"{SPIN};Executor.wait_for_ready_callbacks (rclpy/executors.py:793);{wait} 50",
        f"{SPIN};Executor.wait_for_ready_callbacks (rclpy/executors.py:793);Executor._wait_for_ready_callbacks "
        f"(rclpy/executors.py:1) 7",  # building the wait set: the executor's own work, not waiting
        f"{CB};Signer.verify (homeo_msgs_py/auth.py:61);Signer._mac (homeo_msgs_py/auth.py:49) 3",
        f"{CB};decode (homeo_msgs_py/schemas.py:524);parse_json (homeo_msgs_py/schemas.py:512);"
        f"JSONDecoder.raw_decode (json/decoder.py:353) 4",
        f"{CB};DrivesNode._put (homeo_decision/drives_node.py:64);JoinedStage.put (homeo_msgs_py/lockstep.py:409);"
        f"PerceptionHost._tick (homeo_decision/hosts.py:25);drives_fields (homeo_decision/codec.py:1) 5",
        f"{CB};DrivesNode._put (homeo_decision/drives_node.py:64);JoinedStage.put (homeo_msgs_py/lockstep.py:409);"
        f"TickJoin.put (homeo_msgs_py/lockstep.py:60) 2",
        f"{CB};DrivesNode._put (homeo_decision/drives_node.py:70);HomeoNode.send (homeo_msgs_py/node_base.py:210);"
        f"encode (homeo_msgs_py/schemas.py:415);dumps (json/__init__.py:238) 6",
        f"{CB};HomeoNode.send (homeo_msgs_py/node_base.py:212);GatedPublisher.publish (homeo_msgs_py/node_base.py:60);"
        f"GatedPublisher._send (homeo_msgs_py/node_base.py:67);Publisher.publish (rclpy/publisher.py:70) 9",
        f"{CB};DrivesNode._put (homeo_decision/drives_node.py:76);Checkpointer.save (homeo_decision/checkpoint.py:1) 1",
        f"{CB};DrivesNode._put (homeo_decision/drives_node.py:66) 2",  # the node's own lines: glue
        f"{SPIN};Executor._take_subscription (rclpy/executors.py:396) 8",
        "thread (101): homeo_decision-checkpoints;Thread._bootstrap (threading.py:1002);BackgroundWriter._run "
        "(homeo_decision/checkpoint_writer.py:50);Condition.wait_for (threading.py:360);Condition.wait "
        "(threading.py:327) 90",  # the writer waiting: not work
        "thread (101): homeo_decision-checkpoints;Thread._bootstrap (threading.py:1002);BackgroundWriter._run "
        "(homeo_decision/checkpoint_writer.py:54);write_atomic (homeo_decision/jsonfile.py:28) 10",
        "garbage line without a count",
    ])
    b = profile.parse_raw(raw)
    assert dict(b["main"]) == {"waiting": 50, "executor": 15, "HMAC check": 3, "decode": 4, "core step": 5,
                               "join": 2, "encode": 6, "publish": 9, "checkpoint": 1, "node glue": 2}
    assert dict(b["helpers"]) == {"homeo_decision-checkpoints thread (off the tick)": 10}
    ms = profile.per_tick({"homeo_drives": b}, 2.0)["homeo_drives"]
    assert ms["waiting"] == pytest.approx(2.0 * 50 / 97) and sum(v for k, v in ms.items() if "thread" not in k) == \
        pytest.approx(2.0)
    text = profile.table({"homeo_drives": ms}, 2.0)
    lines = text.splitlines()
    assert lines[0].split()[-1] == "homeo_drives" and lines[-1].startswith("busy (not waiting)")
    assert [ln.split("  ")[0] for ln in lines[2:5]] == ["decode", "HMAC check", "join"]
    assert any(ln.startswith("homeo_decision-checkpoints thread (off the tick)") for ln in lines)


def test_the_wait_frame_is_rclpys_wait_set_wait_line():
    import inspect

    from rclpy.executors import Executor

    frame = profile.wait_frames()[0]
    line = int(frame.rsplit(":", 1)[1].rstrip(")"))
    src, first = inspect.getsourcelines(Executor._wait_for_ready_callbacks)
    assert "wait_set.wait(" in src[line - first]


def test_the_graph_comes_first_in_even_rounds_and_last_in_odd_ones():
    assert bench.pair_order(0, ["no_checkpoints"]) == ["graph", "no_checkpoints"]
    assert bench.pair_order(1, ["no_checkpoints"]) == ["no_checkpoints", "graph"]
    assert bench.pair_order(2, []) == ["graph"]
    assert bench.ratios([2.0, 3.0], [1.0, 2.0]) == [2.0, 1.5]


def test_the_bench_checkpoints_as_sim_does_by_default(tmp_path):
    import os

    o = bench.bench_options(100, str(tmp_path))
    assert o.checkpoint_dir and os.path.dirname(o.checkpoint_dir) == str(tmp_path) and o.checkpoint_every == 100
    assert o.auth and o.max_restarts == 3 and o.iterations == 100
    assert bench.bench_options(100, str(tmp_path), checkpoints=False, auth=False).checkpoint_dir == ""


def test_a_missing_profiler_is_one_line_that_says_how_to_install_it(monkeypatch, capsys):
    from homeo_launch.cli import build_parser

    monkeypatch.setattr(profile, "find_pyspy", lambda: None)
    args = build_parser().parse_args(["bench", "--profile"])
    assert bench.cmd_bench(args) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "make profile-setup" in err and "requirements-profile.lock" in err


@pytest.mark.ros
@pytest.mark.slow
def test_a_small_bench_prints_each_round_the_checkpoints_share_and_where_the_time_goes(tmp_path):
    from rosgraph import fresh_domain

    from homeo_launch.processes import graph_env

    if profile.find_pyspy() is None:
        pytest.fail(f"py-spy is not installed: {profile.INSTALL}")  # make test installs it
    r = subprocess.run([sys.executable, "-m", "homeo_launch.cli", "bench", "--iterations", "150", "--rounds", "2",
                        "--compare-checkpoints", "--profile"], env=graph_env(fresh_domain()),
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-3000:]
    rounds = [ln for ln in r.stderr.splitlines() if ln.startswith("round ")]
    assert len(rounds) == 2 and all("checkpoints off" in ln and "ratio" in ln for ln in rounds), r.stderr
    out = r.stdout
    assert "ratio graph / floor" in out and "on / off" in out and "checkpoints' share of the tick" in out, out
    table = out[out.index("ms a tick"):].splitlines()
    assert table[0].split()[-4:] == ["homeo_world", "homeo_intention", "homeo_drives", "homeo_decision"], out
    rows = {ln.split("  ")[0] for ln in table[2:]}
    # a category is a row once py-spy caught it: signing (microseconds) went uncaught in a full run at load 15
    assert {"decode", "core step", "publish", "waiting"} <= rows, out
    # every node's categories add up to the tick (each sample is in one of them)
    cells = {ln.split("  ")[0]: [float(x) for x in re.findall(r"(\d+\.\d+) \(\s*\d+\.\d%\)", ln)]
             for ln in table[2:]}
    assert all(len(v) == 4 for v in cells.values()), out
    tick = float(re.search(r"at (\d+\.\d+) ms/tick", out).group(1))
    for col in range(4):
        total = sum(v[col] for k, v in cells.items() if "thread" not in k and not k.startswith("busy"))
        assert total == pytest.approx(tick, rel=0.02), out


@pytest.mark.ros
@pytest.mark.slow
def test_the_bench_json_has_the_ratios_per_round(tmp_path):
    from rosgraph import fresh_domain

    from homeo_launch.processes import graph_env

    r = subprocess.run([sys.executable, "-m", "homeo_launch.cli", "bench", "--iterations", "100", "--rounds", "1",
                        "--compare-auth", "--json"], env=graph_env(fresh_domain()), capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, r.stderr[-3000:]
    out = json.loads(r.stdout)
    assert len(out["ratio_per_round"]) == 1 and out["ratio"] == pytest.approx(out["graph_s_per_tick"] /
                                                                              out["floor_s_per_tick"])
    assert len(out["auth_ratio_per_round"]) == 1 and "checkpoint_ratio" not in out and "profile" not in out

"""A bag is hostile until decoded: whatever is handed to ``homeo-replay`` as a bag, the answer is a
one-line error (exit 2) or a run, never a traceback. No graph here: bags are built by hand."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from homeo_record.bag import BagError, load_run
from homeo_record.record import RUN_INFO_KEY, BagSink, run_info
from homeo_record.tap import tapped_topics


def _replay(*args):
    return subprocess.run([sys.executable, "-m", "homeo_record.replay", *map(str, args)], capture_output=True,
                          text=True, timeout=60)


def _cdr_string(text: str) -> bytes:
    b = text.encode() + b"\0"
    return b"\x00\x01\x00\x00" + len(b).to_bytes(4, "little") + b


def _bag(path, thesis, messages, info=None):
    s = BagSink(path, info or run_info("sim", 2, 0, thesis, {}), tapped_topics())
    topics = {t.name: t for t in tapped_topics()}
    for i, (name, raw) in enumerate(messages):
        s.write(topics[name], 1_000 + i, raw)
    s.close()
    return path


def test_a_handmade_bag_with_garbage_messages_replays_what_decodes(tmp_path, thesis):
    status = json.dumps({"schema": "homeo/run_status", "version": 1, "run": 0, "tick": 2, "stamp": 1.0,
                         "iterations": 2, "done": True, "missed": 0, "state": "done", "metrics": {"x": 1}})
    bag = _bag(tmp_path / "b", thesis, [("/homeo/world", b"\x00\x01\x00\x00garbage"),
                                        ("/homeo/drives", _cdr_string("{not json")),
                                        ("/homeo/run_status", _cdr_string(status))])
    run = load_run(bag)
    assert run.rejected == {"world": 1, "drives": 1}
    assert run.final_status()["metrics"] == {"x": 1}


@pytest.mark.parametrize("mutate,words", [
    (lambda p: (p / "metadata.yaml").unlink(), "no metadata.yaml"),
    (lambda p: (p / "metadata.yaml").write_text("{{{: ["), "unreadable"),
    (lambda p: (p / "metadata.yaml").write_text("rosbag2_bagfile_information: 3\n"), "not a homeo run"),
    (lambda p: [f.write_bytes(b"\x89MCAP0\r\n" + b"\x00" * 40) for f in p.glob("*.mcap")], "not a readable"),
    (lambda p: [f.unlink() for f in p.glob("*.mcap")], "not a readable"),
])
def test_broken_bags_are_one_line_errors(tmp_path, thesis, mutate, words):
    bag = _bag(tmp_path / "b", thesis, [])
    mutate(bag)
    with pytest.raises(BagError, match=words):
        load_run(bag)
    r = _replay(bag, "--json")
    assert r.returncode == 2 and "Traceback" not in r.stderr and len(r.stderr.splitlines()) == 1, r.stderr


def test_run_info_with_wrong_types_and_a_bad_scenario_are_refused(tmp_path, thesis):
    info = run_info("sim", 2, 0, thesis, {})
    bad = dict(info, seed="zero")
    with pytest.raises(BagError, match="seed"):
        load_run(_bag(tmp_path / "a", thesis, [], bad))
    worse = dict(info, scenario={"schema": "homeo-scenario", "version": 1})
    with pytest.raises(BagError, match="scenario stored in the bag is invalid"):
        load_run(_bag(tmp_path / "b", thesis, [], worse))
    assert RUN_INFO_KEY in (tmp_path / "a" / "metadata.yaml").read_text()


def test_a_bag_without_metrics_says_so(tmp_path, thesis):
    r = _replay(_bag(tmp_path / "b", thesis, []), "--json")
    assert r.returncode == 2 and "no run status with metrics" in r.stderr


def test_record_refuses_an_existing_folder(tmp_path):
    from homeo_launch.cli import main

    assert main(["sim", "--record", str(tmp_path), "--iterations", "1"]) == 2

"""``homeo-launch recover``: the bag of a recording whose launcher was killed outright, from its
spool folder alone. Bags are read back with the independent ``mcap`` reader; the folder's manifest
is hostile input (any JSON, any text: a bag or a one-line refusal, the folder then left as it was)."""

from __future__ import annotations

import itertools
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest
import yaml
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from homeo_record import record
from homeo_ops.recover import NotRecovered, recover_folder
from homeo_record.tap import tapped_topics
from homeo_msgs_py.spool import CDR, TEXT, SpoolWriter


def _cli(*args, env=None, timeout=120):
    return subprocess.run([sys.executable, "-m", "homeo_launch.cli", *map(str, args)], capture_output=True,
                          text=True, env=env, timeout=timeout)


def _mcap_topics(bag: Path) -> list[tuple[str, object]]:
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    (f,) = bag.glob("*.mcap")
    with open(f, "rb") as fh:
        return [(ch.topic, msg) for _s, ch, _m, msg in
                make_reader(fh, decoder_factories=[DecoderFactory()]).iter_decoded_messages()]


def _left_folder(data: Path, bag: Path, launcher: list) -> Path:
    """A spool folder as a killed launcher leaves it: its manifest, two nodes' spools."""
    folder = Path(tempfile.mkdtemp(prefix=record.SPOOL_PREFIX, dir=data))
    record.write_manifest(folder, bag, {"graph": "sim", "iterations": 0, "seed": 0}, tapped_topics())
    m = json.loads((folder / record.MANIFEST).read_text())
    m["launcher"] = launcher
    (folder / record.MANIFEST).write_text(json.dumps(m))
    a, b = SpoolWriter(folder, "homeo_decision"), SpoolWriter(folder, "homeo_world")
    a.text("/homeo/action", '{"tick":0}', stamp_ns=10)
    b.text("/homeo/world", '{"tick":1}', stamp_ns=15)
    a.text("/homeo/action", '{"tick":1}', stamp_ns=20)
    a.text("/homeo/elsewhere", "not a topic of the bag", stamp_ns=25)
    a.close()
    b.close()
    return folder


def test_a_left_folder_becomes_its_bag_in_the_order_sent_and_is_deleted(tmp_path):
    me, start = os.getpid(), record.proc_start(os.getpid())
    folder = _left_folder(tmp_path, tmp_path / "bag", [me, start + 1])  # this pid, another start: pid reuse
    r = _cli("recover", "--data-dir", tmp_path)
    assert r.returncode == 0, r.stderr
    assert r.stdout == f"recovered {tmp_path / 'bag'}: 3 messages (from {folder.name})\n"
    assert not folder.exists()
    got = _mcap_topics(tmp_path / "bag")
    assert [(t, m.data) for t, m in got] == [("/homeo/action", '{"tick":0}'), ("/homeo/world", '{"tick":1}'),
                                             ("/homeo/action", '{"tick":1}')]
    assert _cli("recover", "--data-dir", tmp_path).stdout == f"nothing to recover in {tmp_path}\n"


def test_a_live_recording_and_an_existing_bag_are_left_alone_with_one_line_each(tmp_path):
    me = [os.getpid(), record.proc_start(os.getpid())]
    live = _left_folder(tmp_path, tmp_path / "live-bag", me)  # its launcher (this process) still runs
    (tmp_path / "bag").mkdir()
    dead = _left_folder(tmp_path, tmp_path / "bag", [me[0], me[1] + 1])
    r = _cli("recover", "--data-dir", tmp_path)
    assert r.returncode == 1 and r.stdout == ""
    lines = sorted(r.stderr.splitlines())
    assert lines == sorted([f"not recovered: {live}: still recording (its launcher, process {me[0]}, is running)",
                            f"not recovered: {dead}: its bag {tmp_path / 'bag'} already exists (a bag is never "
                            "overwritten); move that away and run recover again"])
    assert live.is_dir() and dead.is_dir() and not (tmp_path / "live-bag").exists()
    (tmp_path / "bag").rmdir()
    with pytest.raises(NotRecovered):
        recover_folder(live)
    assert recover_folder(dead).endswith(f"3 messages (from {dead.name})") and not dead.exists()


def test_a_bag_that_cannot_be_written_is_one_line_and_the_folder_is_kept(tmp_path):
    me = [os.getpid(), record.proc_start(os.getpid()) + 1]
    folder = _left_folder(tmp_path, Path("/proc/self/bag"), me)  # /proc takes no new folder, even from root
    with pytest.raises(NotRecovered, match=r"^.*: writing /proc/self/bag: .+$"):
        recover_folder(folder)
    assert folder.is_dir() and len(list(folder.glob("*.spool"))) == 2


def test_a_folder_without_a_manifest_and_a_missing_data_dir_are_one_line(tmp_path):
    (tmp_path / (record.SPOOL_PREFIX + "old")).mkdir()
    r = _cli("recover", "--data-dir", tmp_path)
    assert r.returncode == 1 and len(r.stderr.splitlines()) == 1 and "no bag.json" in r.stderr, r.stderr
    r = _cli("recover", "--data-dir", tmp_path / "nowhere")
    assert r.returncode == 2 and r.stderr == f"homeo-launch: error: --data-dir {tmp_path / 'nowhere'}: not a directory\n"


_json = st.recursive(st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False) | st.text(max_size=8),
                     lambda c: st.lists(c, max_size=4) | st.dictionaries(st.text(max_size=8), c, max_size=4),
                     max_leaves=12)
_VALID = {"schema": record.MANIFEST_SCHEMA, "version": 1, "bag": "BAG", "launcher": [0, 5], "info": {"graph": "sim"},
          "topics": [["action", "/homeo/action", "std_msgs/msg/String", "event"]]}
_BAD = {"schema": st.just("x"), "version": st.sampled_from([2, "1", True]),
        "bag": st.sampled_from(["relative", "", "/"]) | st.text(max_size=10),
        "launcher": st.sampled_from([[1, None], [-1, 3], "x", [1], [True, 2]]) | _json,
        "info": _json, "topics": st.sampled_from([[], [["a", "b", "c", "d"]], [["x", "/a", "std_msgs/msg/Int8", "event"]]])
        | _json}


@st.composite
def _manifest(draw):
    """A valid manifest with at most one field (or none) spoilt, or removed."""
    m = dict(_VALID)
    key = draw(st.sampled_from([None, None, None, *_VALID]))
    if key is not None:
        if draw(st.booleans()):
            m[key] = draw(_BAD[key])
        else:
            del m[key]
    return m


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(doc=_manifest() | _json | st.text(max_size=40), spoilt=st.lists(st.tuples(
    st.sampled_from([TEXT, CDR, 7]), st.sampled_from(["/homeo/action", "/diagnostics", "/x"]), st.binary(max_size=12)),
    max_size=3))
def test_any_manifest_is_a_bag_or_a_one_line_refusal_that_leaves_the_folder(doc, spoilt):
    """...and any records in its spools: a text that is not UTF-8 or not on a String topic is
    counted (``unreadable_records``) and left out, never a traceback."""
    with tempfile.TemporaryDirectory() as d:
        folder = Path(d) / (record.SPOOL_PREFIX + "x")
        folder.mkdir()
        if isinstance(doc, dict) and doc.get("bag") == "BAG":
            doc = dict(doc, bag=str(Path(d) / "bag"))
        (folder / record.MANIFEST).write_text(doc if isinstance(doc, str) else json.dumps(doc))
        w = SpoolWriter(folder, "n")
        w.text("/homeo/action", '{"tick":0}', stamp_ns=1)
        for kind, topic, payload in spoilt:
            w.add(kind, topic, payload, stamp_ns=2)
        w.close()
        try:
            line = recover_folder(folder)
        except NotRecovered as exc:
            event("refused")
            assert "\n" not in str(exc) and folder.is_dir()
        else:
            event("a bag")
            assert line.startswith(str(Path(d) / "bag")) and not folder.exists() and (Path(d) / "bag").is_dir()
            want = 0  # texts on the bag's one String topic that are not UTF-8 (a record of no kind ends the file)
            for kind, topic, payload in itertools.takewhile(lambda r: r[0] != 7, spoilt):
                try:
                    payload.decode("utf-8")
                except UnicodeDecodeError:
                    want += kind == TEXT and topic == "/homeo/action"
            meta = yaml.safe_load((Path(d) / "bag" / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
            assert json.loads(meta["custom_data"][record.RUN_INFO_KEY])["unreadable_records"] == want


@pytest.mark.ros
def test_a_launcher_killed_outright_leaves_a_folder_that_recover_turns_into_a_replayable_bag(tmp_path):
    """SIGKILL to the launcher alone (its nodes die with it, PR_SET_PDEATHSIG): nothing merged, the
    spool folder stays; ``recover`` writes the bag with every action from tick 0 on, none twice,
    and ``homeo-replay`` reads it."""
    from rosgraph import child_pid, fresh_domain, wait_spooled_actions

    from homeo_launch.processes import graph_env
    bag = tmp_path / "bag"
    proc = subprocess.Popen([sys.executable, "-m", "homeo_launch.cli", "sim", "--iterations", "0", "--rate", "100",
                             "--quiet", "--record", str(bag), "--data-dir", str(tmp_path)],
                            env=graph_env(fresh_domain()), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        wait_spooled_actions(tmp_path, proc, 50)
        nodes = [child_pid(proc.pid, m) for m in ("homeo_decision.node", "homeo_decision.world_node")]
        os.kill(proc.pid, signal.SIGKILL)
        proc.communicate(timeout=30)
        end = time.monotonic() + 30
        while any(p and Path(f"/proc/{p}").exists() for p in nodes) and time.monotonic() < end:
            time.sleep(0.05)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    (folder,) = tmp_path.glob(".homeo-record-*")
    assert not bag.exists()
    r = _cli("recover", "--data-dir", tmp_path)
    assert r.returncode == 0 and r.stdout.startswith(f"recovered {bag}: "), r.stderr
    assert not folder.exists()
    actions = [json.loads(m.data)["tick"] for t, m in _mcap_topics(bag) if t == "/homeo/action"]
    assert len(actions) >= 50 and actions == list(range(len(actions)))
    r = subprocess.run([sys.executable, "-m", "homeo_record.replay", bag, "--json"], capture_output=True, text=True,
                       timeout=120)
    # the world's result of the last recorded status: the ticks the unbounded run had reached when it was killed
    assert r.returncode == 0 and 0 < json.loads(r.stdout)["iterations"] <= len(actions), r.stderr


@settings(max_examples=100, deadline=None)
@given(text=st.text(max_size=30))
def test_any_data_dir_text_is_a_result_or_a_one_line_error(text):
    import contextlib
    import io

    from homeo_launch.cli import main

    out, err = io.StringIO(), io.StringIO()
    with tempfile.TemporaryDirectory() as d, contextlib.chdir(d), contextlib.redirect_stdout(out), \
            contextlib.redirect_stderr(err):
        code = main(["recover", "--data-dir", text])
    if code == 0:
        assert out.getvalue().startswith("nothing to recover in ") and err.getvalue() == ""
    else:  # the empty name, one with a NUL, a folder that is not there (argparse: a value starting with -)
        assert code == 2 and len(err.getvalue().splitlines()) <= 2 and "Traceback" not in err.getvalue()


def test_a_process_is_named_by_pid_and_start_and_a_zombie_no_longer_runs():
    """proc(5): /proc/PID/stat field 22 is the start time; state Z is a process that has ended but
    not been reaped (a killed launcher whose parent has not yet waited for it)."""
    p = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        start = record.proc_start(p.pid)
        assert isinstance(start, int) and start >= record.proc_start(os.getpid())  # started after this process
        p.kill()
        end = time.monotonic() + 10
        while Path(f"/proc/{p.pid}/stat").read_text().rpartition(")")[2].split()[0] != "Z":
            assert time.monotonic() < end
            time.sleep(0.01)
        assert record.proc_start(p.pid) is None  # a zombie: /proc still has it, it runs no more
    finally:
        p.kill()
        p.wait()
    assert record.proc_start(p.pid) is None  # reaped: gone (unless the pid was given again meanwhile)


_FULL_DISK = """
import os, resource, signal, sys
from pathlib import Path
sys.path.insert(0, {tests!r})
from test_recover import _left_folder
from homeo_record import record
from homeo_launch.watch import merge_recording
tmp = Path({tmp!r})
folder = _left_folder(tmp, tmp / "bag", [os.getpid(), record.proc_start(os.getpid()) + 1])
signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails with EFBIG, as on a full disk
resource.setrlimit(resource.RLIMIT_FSIZE, (300, resource.RLIM_INFINITY))
merge_recording(folder)
"""


def test_the_bag_a_launch_file_could_not_write_leaves_no_half_bag_and_recover_writes_it_later(tmp_path):
    """``homeo-launch watch`` (under ros2 launch) merges the recording when the run ends; when the bag
    cannot be written (here a file-size limit: EFBIG, as a full disk's ENOSPC) it says so in one line and
    keeps the folder, and leaves no half bag, which would make ``homeo-launch recover`` refuse
    ("its bag already exists")."""
    r = subprocess.run([sys.executable, "-c", _FULL_DISK.format(tests=str(Path(__file__).parent), tmp=str(tmp_path))],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and r.stderr.count("\n") == 1, r.stderr
    assert "the recording stays: " in r.stderr and "writing" in r.stderr and "File too large" in r.stderr, r.stderr
    assert not (tmp_path / "bag").exists()
    (folder,) = tmp_path.glob(record.SPOOL_PREFIX + "*")
    r = _cli("recover", "--data-dir", tmp_path)
    assert r.returncode == 0 and r.stdout == f"recovered {tmp_path / 'bag'}: 3 messages (from {folder.name})\n", r

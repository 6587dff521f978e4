"""Recording at the writers (``homeo_msgs_py.spool``, ``homeo_record.record.WriterBag``).

The spool is our own scratch format: its bytes are checked against a record packed by hand, and its
reader against torn and arbitrary files. The bag merged from spools is read back with the
independent ``mcap`` reader and its ROS 2 CDR decoder. The graph parts: a node refuses a spool
folder outside its data directory on one line, and a person's words (the one topic the graph takes
from outside) reach a bag recorded at the writers.
"""

from __future__ import annotations

import json
import struct
import subprocess
import sys
import time

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from homeo_msgs_py.spool import CDR, TEXT, Record, SpoolWriter, read_spool, read_spools


def test_a_record_is_the_documented_bytes(tmp_path):
    w = SpoolWriter(tmp_path, "homeo_decision")
    w.text("/homeo/action", "hé", stamp_ns=5)
    w.cdr("/diagnostics", b"\x00\x01\x00\x00", stamp_ns=-1)
    w.close()
    (f,) = tmp_path.glob("homeo_decision-*.spool")
    # int64 stamp | uint8 kind | uint16 topic length | uint32 payload length | topic | payload, little-endian
    want = (b"\x05\x00\x00\x00\x00\x00\x00\x00" b"\x00" b"\x0d\x00" b"\x03\x00\x00\x00" b"/homeo/action" b"h\xc3\xa9"
            + b"\xff" * 8 + b"\x01" b"\x0c\x00" b"\x04\x00\x00\x00" b"/diagnostics" b"\x00\x01\x00\x00")
    assert f.read_bytes() == want
    assert read_spool(f) == ([Record(5, "/homeo/action", TEXT, "hé".encode()), Record(-1, "/diagnostics", CDR,
                                                                                       b"\x00\x01\x00\x00")], 0)
    w.text("/homeo/x", "lost")  # after close: nothing written, nothing raised
    assert f.read_bytes() == want


def test_a_torn_last_record_is_dropped_and_counted(tmp_path):
    w = SpoolWriter(tmp_path, "n")
    w.text("/t", "one", stamp_ns=1)
    w.text("/t", "two", stamp_ns=2)
    w.close()
    (f,) = tmp_path.glob("*.spool")
    whole = f.read_bytes()
    f.write_bytes(whole[:-2])  # the disk filled in the middle of the second record
    recs, torn = read_spool(f)
    assert [r.payload for r in recs] == [b"one"] and torn == len(whole) - 2 - (struct.calcsize("<qBHI") + 2 + 3)


_records = st.lists(st.tuples(st.integers(-2**63, 2**63 - 1), st.text(max_size=40), st.sampled_from([TEXT, CDR]),
                              st.binary(max_size=300)), max_size=20)


@settings(max_examples=100, deadline=None)
@given(_records)
def test_any_records_read_back_as_written(tmp_path_factory, recs):
    d = tmp_path_factory.mktemp("s")
    w = SpoolWriter(d, "n")
    for stamp, topic, kind, payload in recs:
        w.add(kind, topic, payload, stamp)
    w.close()
    got, torn = read_spool(w.path)
    assert torn == 0
    assert [(r.stamp_ns, r.kind, r.payload) for r in got] == [(s, k, p) for s, _, k, p in recs]
    assert [r.topic for r in got] == [t for _, t, _, _ in recs]


@settings(max_examples=200, deadline=None)
@given(st.binary(max_size=400))
def test_any_file_reads_to_records_and_a_torn_count_never_an_error(tmp_path_factory, data):
    f = tmp_path_factory.mktemp("g") / "x.spool"
    f.write_bytes(data)
    recs, torn = read_spool(f)
    assert 0 <= torn <= len(data)
    assert all(r.kind in (TEXT, CDR) for r in recs)


def test_spools_merge_in_the_order_sent_and_a_tie_keeps_one_files_order(tmp_path):
    a, b = SpoolWriter(tmp_path, "a"), SpoolWriter(tmp_path, "b")
    a.text("/t", "a1", 10)
    a.text("/t", "a2", 30)
    a.text("/t", "a3", 30)
    b.text("/t", "b1", 20)
    b.text("/t", "b2", 40)
    a.close()
    b.close()
    recs, torn = read_spools(tmp_path)
    assert [r.payload.decode() for r in recs] == ["a1", "b1", "a2", "a3", "b2"] and torn == 0


def test_the_merged_bag_reads_back_with_an_independent_reader(tmp_path):
    """Spools of two nodes (texts of std_msgs/String, a CDR DiagnosticArray) and a message the tap
    took, merged by WriterBag: mcap + mcap_ros2 decode every one, in the order sent."""
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    from rclpy.serialization import serialize_message

    from homeo_record.record import WriterBag
    from homeo_record.tap import tapped_topics

    topics = tapped_topics()
    bag = WriterBag(tmp_path / "bag", {"graph": "sim"}, topics)
    spool = bag.prepare(str(tmp_path / "data"))
    assert spool.startswith(str(tmp_path / "data"))
    sim, dec = SpoolWriter(spool, "homeo_world"), SpoolWriter(spool, "homeo_decision")
    sim.text("/homeo/world", '{"tick": 0}', 100)
    dec.text("/homeo/action", '{"tick": 0, "action": "Chat"}', 200)
    arr = DiagnosticArray(status=[DiagnosticStatus(name="homeo_decision: inputs", message="ok")])
    dec.cdr("/diagnostics", serialize_message(arr), 150)
    sim.text("/homeo/not_ours", "{}", 120)  # a topic outside the bag's list is left out
    human = next(t for t in topics if t.key == "human_input")
    bag.write(human, 300, bytes(serialize_message(__import__("std_msgs.msg").msg.String(data='{"feedback": "praise"}'))))
    bag.write(topics[0], 400, b"ignored: only the outside topics come from the tap")
    sim.close()
    dec.close()
    bag.close()
    assert not list((tmp_path / "data").iterdir())  # the spools are gone once merged
    (f,) = (tmp_path / "bag").glob("*.mcap")
    with open(f, "rb") as fh:
        got = [(ch.topic, m.log_time, msg) for _s, ch, m, msg in
               make_reader(fh, decoder_factories=[DecoderFactory()]).iter_decoded_messages()]
    assert [(t, s) for t, s, _ in got] == [("/homeo/world", 100), ("/diagnostics", 150), ("/homeo/action", 200),
                                           ("/homeo/human_input", 300)]
    assert json.loads(got[2][2].data) == {"tick": 0, "action": "Chat"}
    assert got[1][2].status[0].name == "homeo_decision: inputs"
    assert json.loads(got[3][2].data) == {"feedback": "praise"}


@pytest.mark.ros
def test_a_node_refuses_a_spool_folder_it_cannot_open_on_one_line(tmp_path):
    from rosgraph import fresh_domain

    from homeo_launch.processes import graph_env

    r = subprocess.run([sys.executable, "-m", "homeo_decision.drives_node", "--ros-args", "-p",
                        f"data_dir:={tmp_path}", "-p", "record_spool:=gone"], env=graph_env(fresh_domain()),
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and r.stderr.strip() == "error: record_spool gone: No such file or directory", r.stderr


@pytest.mark.ros
def test_a_node_sends_its_first_status_before_its_first_diagnostics_period(tmp_path):
    """A run shorter than the /diagnostics period (1 s) still has each node's status in its bag: the
    first one goes out (and into the spool) on the node's first turn, not a period later."""
    import rclpy
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.parameter import Parameter

    from rosgraph import fresh_domain

    from homeo_msgs_py.node_base import HomeoNode

    (tmp_path / "spool").mkdir()
    ctx = Context()
    rclpy.init(context=ctx, domain_id=fresh_domain())
    node = None
    try:
        node = HomeoNode("first_status", context=ctx, parameter_overrides=[
            Parameter("data_dir", value=str(tmp_path)), Parameter("record_spool", value="spool")])
        ex = SingleThreadedExecutor(context=ctx)
        ex.add_node(node)
        for _ in range(3):
            ex.spin_once(timeout_sec=0.0)
        assert node._diag_timer.time_until_next_call() > 0  # the periodic one has not fired: not its message
        node.spool.close()
        (spool,) = (tmp_path / "spool").iterdir()
        records, torn = read_spool(spool)
        assert torn == 0 and [r.topic for r in records] == ["/diagnostics"] and records[0].kind == CDR
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown(context=ctx)


@pytest.mark.ros
def test_a_persons_words_reach_a_bag_recorded_at_the_writers(tmp_path):
    """``--human person --record``: the nodes keep what they send; the launcher's tap takes the
    person's ``homeo/human_input`` (written by no node) into the same bag."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    from rosgraph import Probe, fresh_domain

    from homeo_launch.processes import graph_env

    d, bag = fresh_domain(), tmp_path / "bag"
    proc = subprocess.Popen([sys.executable, "-m", "homeo_launch.cli", "sim", "--human", "person", "--intention", "oracle",
                             "--iterations", "2", "--human-timeout", "1", "--quiet", "--json", "--record", str(bag),
                             "--data-dir", str(tmp_path)], env=graph_env(d), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    probe = Probe(d)
    try:
        status = probe.collect("/homeo/run_status")
        say = probe.publisher("/homeo/human_input")
        end = time.monotonic() + 90
        said_at = 0.0
        while not (status and status[-1]["state"] in ("running", "finishing", "done")):
            assert time.monotonic() < end and proc.poll() is None, "the run never started"
            if status and status[-1]["state"] == "starting" and time.monotonic() - said_at > 1.0:
                say(json.dumps({"intention": "light"}))  # again until heard, as a person would
                said_at = time.monotonic()
            probe.spin_until(lambda: False, 0.1)
    finally:
        probe.close()
    out, err = proc.communicate(timeout=90)
    assert proc.returncode == 0, err
    assert json.loads(out)["iterations"] == 2
    assert not list(tmp_path.glob(".homeo-record-*"))  # the spools are merged and gone
    (f,) = bag.glob("*.mcap")
    ticks: dict = {}
    with open(f, "rb") as fh:
        for _s, ch, _m, msg in make_reader(fh, decoder_factories=[DecoderFactory()]).iter_decoded_messages():
            if ch.topic != "/diagnostics":
                ticks.setdefault(ch.topic, []).append(json.loads(msg.data))
    assert {"intention": "light"} in ticks["/homeo/human_input"]
    assert [m["tick"] for m in ticks["/homeo/action"]] == [0, 1, 2]
    assert ticks["/homeo/run_status"][-1]["done"] is True


@pytest.mark.ros
def test_ctrl_c_keeps_every_message_sent_until_then_in_the_bag(tmp_path):
    """An unbounded recorded run stopped with Ctrl-C (SIGINT to the whole process group, as a
    terminal sends it): the bag holds each tick's action from tick 0 on, none twice, and the spools
    are gone."""
    import os
    import signal

    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    from rosgraph import fresh_domain, wait_spooled_actions

    from homeo_launch.processes import graph_env

    bag = tmp_path / "bag"
    proc = subprocess.Popen([sys.executable, "-m", "homeo_launch.cli", "sim", "--iterations", "0", "--rate", "100",
                             "--quiet", "--json", "--record", str(bag), "--data-dir", str(tmp_path)],
                            env=graph_env(fresh_domain()), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    try:
        wait_spooled_actions(tmp_path, proc, 50)
        os.killpg(proc.pid, signal.SIGINT)
        out, err = proc.communicate(timeout=90)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
    # an unbounded run's summary counts the ticks that ran (at least the 50 actions waited for)
    assert proc.returncode == 0 and json.loads(out)["iterations"] >= 50, err[-2000:]
    assert not list(tmp_path.glob(".homeo-record-*"))
    (f,) = bag.glob("*.mcap")
    with open(f, "rb") as fh:
        actions = [json.loads(msg.data)["tick"] for _s, ch, _m, msg in
                   make_reader(fh, decoder_factories=[DecoderFactory()]).iter_decoded_messages()
                   if ch.topic == "/homeo/action"]
    assert len(actions) >= 50 and actions == list(range(len(actions)))

"""``homeo-launch sim --record DIR`` and ``homeo-replay``: the bag is read back with an independent
reader (the ``mcap`` library and its ROS 2 CDR decoder, not ``rosbags`` that wrote it), and the
replay prints exactly what the run printed. One recorded graph run (module scope) serves every test.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from collections import defaultdict
from pathlib import Path

import pytest
import yaml

from rosgraph import fresh_domain

from homeo_launch.processes import graph_env

pytestmark = pytest.mark.ros

TICKS, SEED = 60, 3
PER_TICK = ("observation", "world", "intention", "drives", "action")  # ticks 0..N (N: the final tick)
HOMEO = ("world", "observation", "intention", "drives", "action", "outcome", "run_status")


def _run(module: str, *args, env=None, timeout=180.0):
    return subprocess.run([sys.executable, "-m", module, *map(str, args)], capture_output=True, text=True,
                          env=env, timeout=timeout)


@pytest.fixture(scope="module", params=["writers", "tap"])
def recorded(request, tmp_path_factory):
    """One recorded run per way of recording (``--record-from``): every test holds for both."""
    d = tmp_path_factory.mktemp("rec")
    bag = d / "bag"
    # 3 s at 20 ticks a second: several /diagnostics periods (1 s), for the tap to hear some
    p = _run("homeo_launch.cli", "sim", "--iterations", TICKS, "--rate", 20, "--seed", SEED, "--json", "--quiet",
             "--record", bag, "--record-from", request.param, "--save-q", d / "q.json", "--data-dir", d,
             env=graph_env(fresh_domain()))
    assert p.returncode == 0, p.stderr
    return bag, p.stdout, d


def _independent_read(bag: Path):
    """Every message through mcap + mcap_ros2 (CDR decoded from the schema stored in the file)."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    (mcap_file,) = bag.glob("*.mcap")
    out = defaultdict(list)
    with open(mcap_file, "rb") as f:
        for schema, channel, message, decoded in make_reader(f, decoder_factories=[DecoderFactory()]).iter_decoded_messages():
            out[channel.topic].append((schema.name, channel.message_encoding, decoded))
            out["log_times"].append(message.log_time)
    return out


def test_the_bag_holds_every_topic_one_message_per_tick_as_cdr_std_msgs_string(recorded):
    from homeo_decision import codec
    from homeo_decision.scenario import load_scenario
    from homeo_msgs_py.schemas import decode

    bag, _, _ = recorded
    meta = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert meta["version"] == 9 and meta["storage_identifier"] == "mcap"
    types = {t["topic_metadata"]["name"]: t["topic_metadata"]["type"] for t in meta["topics_with_message_count"]}
    assert types == {**{f"/homeo/{k}": "std_msgs/msg/String" for k in HOMEO + ("device", "last_action", "human_input")},
                     "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray"}
    latched = {t["topic_metadata"]["name"]: t["topic_metadata"]["offered_qos_profiles"][0]["durability"]
               for t in meta["topics_with_message_count"]}
    assert latched["/homeo/drives"] == "transient_local" and latched["/homeo/action"] == "volatile"

    got = _independent_read(bag)
    counts = {t["topic_metadata"]["name"]: t["message_count"] for t in meta["topics_with_message_count"]}
    stamps = got.pop("log_times")
    assert {t: len(v) for t, v in got.items()} == {t: n for t, n in counts.items() if n}
    t0 = meta["starting_time"]["nanoseconds_since_epoch"]
    assert min(stamps) == t0 and max(stamps) - t0 < 120e9 and abs(t0 / 1e9 - time.time()) < 600  # wall-clock stamps
    assert counts["/homeo/human_input"] == 0  # the simulated human does not write it
    voc = codec.vocabulary(load_scenario())
    ticks = {}
    for key in HOMEO:
        msgs = got[f"/homeo/{key}"]
        assert msgs, key
        for schema, enc, m in msgs:
            assert (schema, enc) == ("std_msgs/msg/String", "cdr")
        ticks[key] = [decode(m.data, voc, f"homeo/{key}") for _, _, m in msgs]  # valid homeo JSON, or raises
    for key in PER_TICK:
        assert [m.tick for m in ticks[key]] == list(range(TICKS + 1)), key  # tick 0 included, none twice
    for key in ("world", "drives", "action"):  # the final tick says so
        assert [bool(m.fields.get("final")) for m in ticks[key]] == [False] * TICKS + [True], key
    assert [m.tick for m in ticks["outcome"]] == list(range(TICKS))
    assert ticks["run_status"][-1].fields["done"] is True
    diag = got["/diagnostics"]
    assert diag and all(s == "diagnostic_msgs/msg/DiagnosticArray" for s, _, _ in diag)
    assert any(st.name.endswith(": inputs") for _, _, arr in diag for st in arr.status)


def test_replay_json_is_exactly_the_runs_json_and_the_curves_end_at_its_metrics(recorded):
    from homeo_record.bag import load_run
    from homeo_record.replay import series

    bag, printed, _ = recorded
    r = _run("homeo_record.replay", bag, "--json")
    assert r.returncode == 0, r.stderr
    assert r.stdout == printed  # byte for byte
    m = json.loads(printed)["metrics"]
    t, s = series(load_run(bag))
    assert len(t) == TICKS
    assert s["CDA"]["NAch"][-1] == pytest.approx(m["CDA"]["NAch"]["mean"])
    assert s["CEDA"]["all"][-1] == pytest.approx(m["CEDA"]["all"]["mean"])
    assert s["RSR"][-1] == pytest.approx(m["RSR"]["mean"])
    assert s["HSR"][-1] == pytest.approx(m["HSR"]["mean"])


def test_replay_text_log_and_plots(recorded, tmp_path):
    bag, _, _ = recorded
    r = _run("homeo_record.replay", bag, "--log", "--plots", tmp_path / "figs")
    assert r.returncode == 0, r.stderr
    assert "HSR" in r.stdout and "interaction: 60 ticks" in r.stdout
    assert sum(1 for line in r.stdout.splitlines() if " -> " in line) == TICKS
    for f in ("drives.png", "hsr_rsr.png"):
        assert (tmp_path / "figs" / f).stat().st_size > 10_000


def test_policy_scores_a_table_on_the_recorded_choices(recorded, tmp_path):
    from homeo_decision.objectq import ObjectQ
    from homeo_decision.qtable_io import save
    from homeo_record.bag import load_run

    bag, _, d = recorded
    run = load_run(bag)
    uniform = tmp_path / "uniform.json"
    save(ObjectQ(run.sc), uniform)
    r = _run("homeo_record.replay", bag, "--policy", uniform, "--json")
    assert r.returncode == 0, r.stderr
    res = json.loads(r.stdout)
    # a table of equal values: every valid action equally likely, so the robot's choice has 1/|valid|
    from homeo_decision import codec

    inv = [1 / len(run.sc.c.valid[codec.perception_from_fields(run.sc, f)[0][0]])
           for k, f in sorted(run.by_tick("drives").items()) if run.by_tick("action")[k]["action"] is not None]
    assert res["ticks"] == len(inv)
    assert res["p_robot_choice"] == pytest.approx(sum(inv) / len(inv))
    learned = json.loads(_run("homeo_record.replay", bag, "--policy", d / "q.json", "--json", "--dod", "0.25").stdout)
    assert 0 <= learned["agreement"] <= 1 and learned["rewarded_ticks"] > TICKS // 2
    assert learned["p_robot_choice"] > res["p_robot_choice"]  # the table the robot learned favours its own choices


@pytest.mark.parametrize("args,words", [
    (["--dod", "0.3"], "--dod needs --policy"),
    (["--policy", "/nonexistent.json"], "not found"),
    (["--json", "--log"], "without --json"),
])
def test_replay_user_mistakes_are_one_line_errors(recorded, args, words):
    bag, _, _ = recorded
    r = _run("homeo_record.replay", bag, *args)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert len(r.stderr.splitlines()) == 1 and words in r.stderr, r.stderr


def bag_problems(bag: Path) -> list[str]:
    """What is wrong with ``bag`` read by rosbags' reader (metadata.yaml, QoS, CDR by its type store), its
    counts held against the MCAP file as mcap's reader reads it; empty when all agree. (The run's settings in
    custom_data are homeo-replay's to read: the replay tests.)"""
    from rosbags.rosbag2 import Reader, ReaderError
    from rosbags.typesys import Stores, get_typestore

    in_file = {t: len(v) for t, v in _independent_read(bag).items() if t != "log_times"}
    store, bad = get_typestore(Stores.ROS2_JAZZY), []
    try:
        with Reader(bag) as r:
            counts = {c.topic: c.msgcount for c in r.connections}
            if {t: n for t, n in counts.items() if n} != in_file:
                bad.append(f"topic counts {counts} are not the file's {in_file}")
            if r.message_count != sum(in_file.values()):
                bad.append(f"message_count {r.message_count} is not the file's {sum(in_file.values())}")
            for c in r.connections:
                policies = [getattr(q, k).name for q in c.ext.offered_qos_profiles
                            for k in ("history", "reliability", "durability", "liveliness")]
                if not policies or "UNKNOWN" in policies:
                    bad.append(f"{c.topic}: QoS {policies}")
            read = sum(1 for c, _t, raw in r.messages() if store.deserialize_cdr(raw, c.msgtype) is not None)
            if read != sum(in_file.values()):
                bad.append(f"rosbags read {read} messages")
    except ReaderError as exc:
        bad.append(f"rosbags: {exc}")
    return bad


def test_the_bag_reads_with_rosbags_as_the_mcap_file_holds_it(recorded, tmp_path):
    import shutil

    bag = recorded[0]
    assert bag_problems(bag) == []
    # the check can fail: a count that does not add up, a QoS policy no ROS 2 knows, a version rosbag2 never wrote
    for name, breaks in (("count", lambda t0, info: t0.update(message_count=t0["message_count"] + 1)),
                         ("qos", lambda t0, info: t0["topic_metadata"]["offered_qos_profiles"][0].update(history="some")),
                         ("version", lambda t0, info: info.update(version=99))):
        broken = tmp_path / name
        shutil.copytree(bag, broken)
        meta = yaml.safe_load((broken / "metadata.yaml").read_text())
        info = meta["rosbag2_bagfile_information"]
        breaks(info["topics_with_message_count"][0], info)
        (broken / "metadata.yaml").write_text(yaml.safe_dump(meta))
        assert bag_problems(broken), name

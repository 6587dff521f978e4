"""``homeo-sim`` as a user runs it: one-line errors, the --json layout, --trace, --save-q / --load-q."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

from homeo_sim.runner import RunConfig, run_episode

SCRIPT = Path(sys.executable).parent / "homeo-sim"
TRACE_KEYS = {"tick", "drives", "intensities", "m_dom", "intention", "action", "feedback", "proposal", "reward"}
DRIVE_KEYS = {"NAch", "NSoc", "NRes", "NEng", "all"}


def cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "homeo_sim.cli", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, timeout=120)


def assert_one_line_error(proc, *words):
    assert proc.returncode == 2, (proc.returncode, proc.stderr)
    lines = proc.stderr.splitlines()
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith("homeo-sim: error:"), lines[0]
    assert "Traceback" not in proc.stderr
    for w in words:
        assert w in lines[0], lines[0]


# -- errors ----------------------------------------------------------------------------------

def test_dod_out_of_range():
    assert_one_line_error(cli("run", "--dod", "1.5", "--iterations", "10"), "1.5")


def test_negative_iterations():
    assert_one_line_error(cli("run", "--iterations", "-1"), "-1")


def test_missing_scenario(tmp_path):
    assert_one_line_error(cli("run", "--iterations", "10", "--scenario", tmp_path / "nope.json"), "nope.json")


def test_malformed_scenario(tmp_path):
    p = tmp_path / "bad.json"
    p.write_text("{ this is not json")
    assert_one_line_error(cli("run", "--iterations", "10", "--scenario", p), "JSON")


def test_scenario_action_on_unknown_object(tmp_path, thesis_raw):
    thesis_raw["actions"][0]["object"] = "fridge"
    p = tmp_path / "s.json"
    p.write_text(json.dumps(thesis_raw))
    assert_one_line_error(cli("run", "--iterations", "10", "--scenario", p), "fridge")


def test_scenario_with_wrong_json_type(tmp_path, thesis_raw):
    thesis_raw["actions"].append(42)
    p = tmp_path / "s.json"
    p.write_text(json.dumps(thesis_raw))
    assert_one_line_error(cli("run", "--iterations", "10", "--scenario", p))


def test_corrupt_q_table(tmp_path):
    p = tmp_path / "q.json"
    p.write_text("garbage, not a table")
    assert_one_line_error(cli("run", "--iterations", "10", "--load-q", p), "q.json")


def test_missing_q_table(tmp_path):
    assert_one_line_error(cli("run", "--iterations", "10", "--load-q", tmp_path / "none.json"), "none.json")


def test_unknown_open_choice_via_set():
    assert_one_line_error(cli("run", "--iterations", "10", "--set", "human_mood=1"), "human_mood")


# -- output ---------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def json_run():
    proc = cli("run", "--iterations", 200, "--seeds", 2, "--json", "--quiet")
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)


def check_metric(m, n_seeds):
    assert set(m) == {"mean", "ci95", "per_seed"}
    assert len(m["per_seed"]) == n_seeds
    assert m["mean"] == pytest.approx(sum(m["per_seed"]) / n_seeds)
    lo, hi = m["ci95"]
    assert lo <= m["mean"] <= hi


def test_json_layout(json_run):
    assert set(json_run) == {"iterations", "seeds", "metrics"}
    assert json_run["iterations"] == 200
    assert json_run["seeds"] == [0, 1]
    m = json_run["metrics"]
    assert set(m) == {"HSR", "RSR", "CDA", "CEDA"}
    for key in ("HSR", "RSR"):
        check_metric(m[key], 2)
        assert all(0.0 <= v <= 1.0 for v in m[key]["per_seed"])
    for key in ("CDA", "CEDA"):
        assert set(m[key]) == DRIVE_KEYS
        for d in DRIVE_KEYS:
            check_metric(m[key][d], 2)


def test_json_all_is_mean_of_drives(json_run):
    # Eq 4.3 / 4.5 per seed
    for key in ("CDA", "CEDA"):
        m = json_run["metrics"][key]
        for s in range(2):
            drives = [m[d]["per_seed"][s] for d in ("NAch", "NSoc", "NRes", "NEng")]
            assert m["all"]["per_seed"][s] == pytest.approx(sum(drives) / 4)


def test_json_matches_in_process_runs(json_run):
    for s in (0, 1):
        ref = run_episode(RunConfig(iterations=200, seed=s)).metrics
        assert json_run["metrics"]["HSR"]["per_seed"][s] == pytest.approx(ref["HSR"])
        assert json_run["metrics"]["CDA"]["NEng"]["per_seed"][s] == pytest.approx(ref["CDA"]["NEng"])


def test_table_output_mentions_thesis_values():
    proc = cli("run", "--iterations", 50, "--quiet")
    assert proc.returncode == 0, proc.stderr
    assert "HSR" in proc.stdout and "0.82" in proc.stdout  # Table 4.5 printed beside ours


def test_trace(tmp_path):
    t = tmp_path / "trace.jsonl"
    proc = cli("run", "--iterations", 60, "--seed", 1, "--trace", t, "--quiet", "--json")
    assert proc.returncode == 0, proc.stderr
    lines = [json.loads(x) for x in t.read_text().splitlines()]
    assert len(lines) == 60
    assert [x["tick"] for x in lines] == list(range(60))
    for x in lines:
        assert TRACE_KEYS <= set(x), set(x)
        assert set(x["drives"]) == {"NAch", "NSoc", "NRes", "NEng"}
        assert set(x["intensities"]) == {"Serving", "Social", "Relaxative", "Survival"}
        assert x["feedback"] in (-1, 0, 1)


def test_save_then_load_q(tmp_path):
    q = tmp_path / "out" / "q.json"
    proc = cli("run", "--iterations", 150, "--seed", 0, "--save-q", q, "--quiet", "--json")
    assert proc.returncode == 0, proc.stderr
    raw = json.loads(q.read_text())
    assert raw["schema"] == "homeo-qtable"
    assert any(v != 0.0 for t in raw["tables"].values() for row in t.values() for v in row.values())  # learned
    q2 = tmp_path / "out" / "q2.json"
    proc = cli("run", "--iterations", 1, "--seed", 1, "--load-q", q, "--save-q", q2, "--quiet")
    assert proc.returncode == 0, proc.stderr
    assert "loaded Q-table" in proc.stderr
    # one tick learns at most a few entries (its update, the pseudo update): every other learned value is the loaded one
    learned = {(o, s, a): v for o, t in raw["tables"].items() for s, row in t.items() for a, v in row.items() if v}
    again = json.loads(q2.read_text())["tables"]
    kept = sum(again[o][s][a] == v for (o, s, a), v in learned.items())
    assert kept >= len(learned) - 3 and len(learned) > 20, (kept, len(learned))


def test_installed_script():
    if not SCRIPT.exists():
        pytest.skip("homeo-sim console script not installed next to this interpreter")
    proc = subprocess.run([str(SCRIPT), "run", "--dod", "1.5"], capture_output=True, text=True, timeout=60)
    assert_one_line_error(proc, "1.5")


def test_json_is_strict_json_without_intentions():
    proc = cli("run", "--iterations", 20, "--set", "human_no_intention_prob=1", "--json", "--quiet")
    assert proc.returncode == 0, proc.stderr

    def reject(name):
        raise ValueError(f"non-standard JSON constant {name}")

    json.loads(proc.stdout, parse_constant=reject)


@pytest.mark.parametrize("args,runs", [(["run", "--seeds", "400"], 400), (["sweep", "dod", "--seeds", "40"], 440)])
def test_ctrl_c_stops_workers_and_says_so(args, runs):
    # Ctrl-C in the middle of a parallel run: exit 130, how many runs had finished, and no worker left behind
    import os
    import signal
    import time

    proc = subprocess.Popen([sys.executable, "-m", "homeo_sim.cli", *args, "--quiet"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    while not _children(proc.pid) and time.monotonic() < deadline:  # wait until the pool is up
        time.sleep(0.05)
    kids = _children(proc.pid)
    assert kids, "no worker processes started"
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    said = err.strip().splitlines()
    assert said[1:] == ["homeo-sim: interrupted"], err
    assert re.fullmatch(rf"interrupted: \d+ of {runs} runs finished \(none kept: --out DIR keeps them\)", said[0]), err
    for pid in kids:
        for _ in range(100):
            if not os.path.exists(f"/proc/{pid}") or "Z" in _state(pid):
                break
            time.sleep(0.05)
        assert not os.path.exists(f"/proc/{pid}") or "Z" in _state(pid), f"worker {pid} still running"


def _children(pid: int) -> list[int]:
    try:
        with open(f"/proc/{pid}/task/{pid}/children") as fh:
            return [int(x) for x in fh.read().split()]
    except OSError:
        return []


def _state(pid: int) -> str:
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0]
    except OSError:
        return "X"


# -- the scenario as data: the reference column and the rule baseline come from the scenario -------

def test_table_has_the_reference_column_only_when_the_scenario_has_one():
    thesis = cli("run", "--iterations", 50, "--quiet")
    garden = cli("run", "--iterations", 50, "--quiet", "--scenario", "garden")
    assert thesis.returncode == 0 and garden.returncode == 0, thesis.stderr + garden.stderr
    head_t = thesis.stdout.splitlines()[1]
    head_g = garden.stdout.splitlines()[1]
    assert head_t.split() == ["metric", "drive", "ours", "thesis"]
    assert head_g.split() == ["metric", "drive", "ours"]
    cda_t = next(x for x in thesis.stdout.splitlines() if x.startswith("CDA") and "NAch" in x)
    assert cda_t.rstrip().endswith("1.73")  # Table 4.5, from the scenario's reference block
    assert "Duty" in garden.stdout and "NAch" not in garden.stdout


def test_format_table_reference_cells():
    from homeo_sim.cli import format_table

    d = {"mean": 0.5, "ci95": [0.5, 0.5]}
    out = {"iterations": 10, "seeds": [0], "metrics": {"HSR": d, "RSR": d, "CDA": {"A": d, "all": d},
                                                       "CEDA": {"A": d, "all": d}}}
    with_ref = format_table(out, ["A"], "s", {"HSR": 0.25, "CDA": {"A": 7.0}})
    lines = with_ref.splitlines()
    assert lines[2].rstrip().endswith("0.25") and lines[3].rstrip().endswith("0.500")  # RSR: no published value
    assert lines[4].rstrip().endswith("7.00")
    assert "thesis" not in format_table(out, ["A"], "s", None)


@pytest.mark.parametrize("intention", ["oracle", "bayes"])
def test_run_on_the_second_scenario(intention):
    proc = cli("run", "--scenario", "garden", "--iterations", 200, "--seeds", 2, "--json", "--quiet",
               "--intention", intention, "--workers", 1)
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert set(out["metrics"]["CDA"]) == {"Duty", "Heat", "Power", "all"}
    assert ("intention_accuracy" in out) == (intention == "bayes")


def test_rule_policy_on_the_second_scenario_and_without_a_block(tmp_path, toy_raw):
    proc = cli("run", "--scenario", "garden", "--iterations", 200, "--policy", "rule", "--json", "--quiet")
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["metrics"]["RSR"]["mean"] > 0.5
    p = tmp_path / "toy.json"
    p.write_text(json.dumps(toy_raw()))
    assert_one_line_error(cli("run", "--scenario", p, "--iterations", 20, "--policy", "rule"), "rule_policy", "toy.json")


# -- --first-seed (issue 15: seeds that choose kept apart from seeds that confirm) ---------------

def _json(proc):
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)


def test_first_seed_runs_seeds_n_to_n_plus_k_minus_1():
    out = _json(cli("run", "--seeds", "2", "--first-seed", "3", "--iterations", "60", "--json", "--quiet", "--workers", "1"))
    assert out["seeds"] == [3, 4]
    one = _json(cli("run", "--seed", "4", "--iterations", "60", "--json"))
    assert out["metrics"]["RSR"]["per_seed"][1] == one["metrics"]["RSR"]["mean"]
    sw = _json(cli("sweep", "pseudo", "--seeds", "2", "--first-seed", "3", "--iterations", "60", "--json", "--quiet",
                   "--workers", "1"))
    assert sw["points"][0]["metrics"]["RSR"]["per_seed"] == out["metrics"]["RSR"]["per_seed"]


@pytest.mark.parametrize("args, words", [
    (("run", "--seeds", "2", "--first-seed", "-1"), ("--first-seed", "-1")),
    (("run", "--seeds", "2", "--first-seed", "x"), ("--first-seed",)),
    (("run", "--seed", "2", "--first-seed", "3"), ("--first-seed", "--seed")),
    (("sweep", "xi", "--first-seed", "-2"), ("--first-seed",)),
    (("report", "--out", "/tmp/never-written", "--first-seed", "1.5"), ("--first-seed",)),
])
def test_bad_first_seed_is_a_one_line_error(args, words):
    assert_one_line_error(cli(*args, "--iterations", "10"), *words)

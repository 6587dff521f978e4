"""Intention recognition in the simulation: the human's observations, the bayes loop, the CLI."""

from __future__ import annotations

import json
import subprocess
import sys
from collections import Counter

import pytest

from homeo_decision.scenario import load_scenario
from homeo_sim.human import SimHuman
from homeo_sim.metrics import accuracy_curve, accuracy_ends
from homeo_sim.runner import RunConfig, Simulation, run_episode


def test_observations_leave_the_human_stream_alone(thesis):
    # the oracle results depend on the "human" stream only: observing must not move it
    a, b = SimHuman(thesis, 3), SimHuman(thesis, 3)
    code = 0
    for t in range(300):
        a.advance(code)
        b.advance(code)
        b.observe()
        assert (a.intention, a.present) == (b.intention, b.present)
        assert a.respond(t % 12) == b.respond(t % 12)


def test_observations_follow_the_habits(thesis):
    h = SimHuman(thesis, 0)
    h.intention = thesis.intention_names.index("no_light")
    kw = Counter(h.observe()["keyword"] for _ in range(2000))
    assert kw["dark"] / 2000 == pytest.approx(0.99 + 0.01 / 9, abs=0.02)  # this user says "dark"
    h.intention = thesis.intention_names.index("come")
    g = Counter(h.observe()["gesture"] for _ in range(2000))
    assert g["beckon"] / 2000 > 0.95  # and beckons
    assert set(h.observe(with_intention=True)) == {"gesture", "movement", "keyword", "intention"}


def test_clarified_follows_the_reveal_rule(thesis):
    sc = thesis
    h = SimHuman(sc, 0)
    h.intention = sc.intention_names.index("light")
    wrong, right = sc.action_index("Play"), sc.action_index("LightOn")
    assert h.respond(wrong).clarified == h.intention  # a proposal reveals the intention
    assert h.respond(right).clarified is None  # praise does not, under "proposal"
    hf = SimHuman(load_scenario(overrides={"intention_reveal": "feedback"}), 0)
    hf.intention = 1
    assert hf.respond(right).clarified == 1
    hn = SimHuman(load_scenario(overrides={"intention_reveal": "never"}), 0)
    hn.intention = 1
    assert hn.respond(wrong).clarified is None and hn.respond(wrong).proposal is not None


def test_the_bayes_loop_with_an_oracle_part_equals_the_oracle_loop(thesis):
    """One loop: the same run with the recognition part swapped for the oracle (and the cues
    drawn) gives the oracle run's metrics, and a perfect recognition accuracy."""
    from homeo_decision.robot import OracleRecognition, Robot

    fast = run_episode(RunConfig(iterations=1500, seed=4), thesis)
    sim = Simulation(thesis, RunConfig(iterations=1500, seed=4, intention="bayes"))
    sim.recognition = OracleRecognition(thesis)
    sim.robot = Robot(thesis, sim.policy, sim.recognition)
    slow = sim.run(1500)
    acc = slow.metrics.pop("intention_accuracy")
    assert slow.metrics == fast.metrics
    assert acc == {"first_500": 1.0, "last_500": 1.0}


def test_bayes_run_is_deterministic_and_learns(thesis):
    a = run_episode(RunConfig(iterations=1500, seed=2, intention="bayes"), thesis)
    b = run_episode(RunConfig(iterations=1500, seed=2, intention="bayes"), thesis)
    assert a.metrics == b.metrics and a.intention_hits == b.intention_hits
    curve = accuracy_curve(a.intention_hits, 500)
    assert curve[-1] > curve[0]


def test_accuracy_helpers():
    hits = [False] * 500 + [True] * 500
    assert accuracy_ends(hits) == {"first_500": 0.0, "last_500": 1.0}
    assert accuracy_ends([True, False]) == {"first_500": 0.5, "last_500": 0.5}
    assert accuracy_curve(hits, 250) == [0.0, 0.0, 1.0, 1.0]


def _cli(*args, timeout=300):
    return subprocess.run([sys.executable, "-m", "homeo_sim.cli", *args], capture_output=True, text=True,
                          timeout=timeout)


def test_cli_bayes_json_and_model_files(tmp_path):
    p = _cli("run", "--intention", "bayes", "--iterations", "600", "--seeds", "2", "--json", "--quiet",
             "--workers", "1")
    assert p.returncode == 0, p.stderr
    out = json.loads(p.stdout)
    for k in ("first_500", "last_500"):
        m = out["intention_accuracy"][k]
        assert set(m) == {"mean", "ci95", "per_seed"} and len(m["per_seed"]) == 2
    model = tmp_path / "m.json"
    p = _cli("run", "--intention", "bayes", "--iterations", "300", "--save-intention", str(model), "--quiet")
    assert p.returncode == 0, p.stderr
    assert model.is_file() and "accuracy" in p.stdout
    acc = {}
    for name, extra in (("fresh", ()), ("loaded", ("--load-intention", str(model)))):
        p = _cli("run", "--intention", "bayes", "--iterations", "300", *extra, "--json", "--quiet")
        assert p.returncode == 0, p.stderr
        acc[name] = json.loads(p.stdout)["intention_accuracy"]["first_500"]["mean"]
    # the same seed's 300 ticks, recognised by a model that has already learned 300 (0.70) and by a new one (0.44)
    assert acc["loaded"] > acc["fresh"] + 0.15, acc


def test_cli_errors_are_one_line(tmp_path):
    p = _cli("run", "--save-intention", str(tmp_path / "m.json"), "--iterations", "10")
    assert p.returncode == 2 and "needs --intention bayes" in p.stderr
    p = _cli("run", "--intention", "bayes", "--load-intention", str(tmp_path / "missing.json"), "--iterations", "10")
    assert p.returncode == 2 and "intention model file not found" in p.stderr
    (tmp_path / "bad.json").write_text("{}")
    p = _cli("run", "--intention", "bayes", "--load-intention", str(tmp_path / "bad.json"), "--iterations", "10")
    assert p.returncode == 2 and "not an intention-model file" in p.stderr and len(p.stderr.strip().splitlines()) == 1
    p = _cli("run", "--intention", "psychic")
    assert p.returncode == 2 and "invalid choice" in p.stderr


@pytest.mark.slow
def test_issue_4_acceptance_bayes_against_oracle():
    # issue 4: homeo-sim run --intention bayes --iterations 5000 --seeds 10 --json
    args = ["run", "--iterations", "5000", "--seeds", "10", "--json", "--quiet"]
    p = _cli(*args, "--intention", "bayes", timeout=1200)
    assert p.returncode == 0, p.stderr
    bayes = json.loads(p.stdout)
    p = _cli(*args, timeout=1200)
    assert p.returncode == 0, p.stderr
    oracle = json.loads(p.stdout)
    first = bayes["intention_accuracy"]["first_500"]["mean"]
    last = bayes["intention_accuracy"]["last_500"]["mean"]
    assert last >= 0.90
    assert last >= first + 0.20
    assert abs(bayes["metrics"]["HSR"]["mean"] - oracle["metrics"]["HSR"]["mean"]) <= 0.05


def test_the_intention_bench_times_the_run_it_would_have_run():
    """``homeo-sim bench --intention bayes``: its timing wrapper leaves the recogniser's learning as it is (the
    same EM runs as a plain bayes run of as many ticks), and its figures are the ones it prints."""
    from homeo_msgs_py.graph import BAYES
    from homeo_sim.intention_bench import bench_intention, format_bench

    r = bench_intention(300, repeats=1)
    sim = Simulation(load_scenario(), RunConfig(iterations=300, intention=BAYES))
    sim.run(300)
    assert r["em_runs"] == sim.recognition.model.em_runs > 0
    assert r["em_iterations_per_run"] == sim.recognition.model.em_iterations / sim.recognition.model.em_runs
    assert r["bayes_over_oracle_time"] == r["oracle_iterations_per_s"] / r["bayes_iterations_per_s"]
    assert all(r[k] > 0 for k in ("recognise_us", "recognise_in_loop_us", "learn_per_tick_us", "em_run_us",
                                  "pgmpy_query_us"))
    text = format_bench(r)
    assert f"({r['em_runs']} EM runs in 300 ticks" in text and f"{r['bayes_over_oracle_time']:.2f}x" in text
    p = _cli("bench", "--intention", "bayes", "--iterations", "100", "--json")
    assert p.returncode == 0, p.stderr
    assert json.loads(p.stdout)["iterations"] == 100

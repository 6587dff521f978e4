"""Sweeps (Figs 4.3-4.5) and the report: worker-count independence, the --json layout, the files written."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from homeo_sim.runner import RunConfig, run_seeds
from homeo_sim.stats import aggregate
from homeo_sim.sweep import SWEEPS, learning_speed, median_time, run_jobs, sweep, window_rates


def cli(*args):
    return subprocess.run([sys.executable, "-m", "homeo_sim.cli", *map(str, args)], capture_output=True, text=True,
                          timeout=120)


def test_sweep_values_are_the_thesis_grids():
    assert SWEEPS["xi"] == (0.0, 0.25, 0.5, 0.75, 1.0, 1.5, 2.0)
    assert SWEEPS["dod"] == (0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0)
    assert SWEEPS["pseudo"] == (True, False)


def test_sweep_identical_for_one_and_two_workers():
    base = RunConfig(iterations=150)
    one, _ = sweep("dod", base, [0, 1], workers=1)
    two, _ = sweep("dod", base, [0, 1], workers=2)
    assert json.dumps(one) == json.dumps(two)
    # and the points really differ (the sweep is not returning one run eleven times)
    hsr = [p["metrics"]["HSR"]["per_seed"] for p in one["points"]]
    assert len({tuple(h) for h in hsr}) > 1


def test_sweep_point_equals_homeo_sim_run():
    # xi = 1 is the scenario's default run: the sweep point must be exactly `homeo-sim run`'s numbers
    out, _ = sweep("xi", RunConfig(iterations=200), [0, 1], workers=1)
    point = next(p for p in out["points"] if p["value"] == 1.0)
    ref = aggregate([r.metrics for r in run_seeds(RunConfig(iterations=200), [0, 1], workers=1)],
                    ["NAch", "NSoc", "NRes", "NEng"])
    assert point["metrics"] == ref


def test_duplicate_configurations_run_once_and_share_results():
    from tqdm import tqdm

    cfg = RunConfig(iterations=100, xi=1.0)
    with tqdm(total=2, disable=False, file=open(os.devnull, "w")) as bar:
        out = run_jobs([cfg, RunConfig(iterations=100, xi=0.0), cfg], [3], workers=1, bar=bar)
        assert bar.n == 2
    assert out[0][0] is out[2][0] and out[0][0].metrics != out[1][0].metrics


def test_sweep_json_layout():
    proc = cli("sweep", "xi", "--seeds", "2", "--iterations", "100", "--json", "--quiet")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert set(out) == {"param", "points"} and out["param"] == "xi"
    assert [p["value"] for p in out["points"]] == list(SWEEPS["xi"])
    for p in out["points"]:
        assert set(p) == {"value", "metrics"}
        m = p["metrics"]
        assert set(m) == {"HSR", "RSR", "CDA", "CEDA"}
        for s in [m["HSR"], m["RSR"], *m["CDA"].values(), *m["CEDA"].values()]:
            assert set(s) == {"mean", "ci95", "per_seed"}
            assert len(s["ci95"]) == 2 and len(s["per_seed"]) == 2
            assert s["ci95"][0] <= s["mean"] <= s["ci95"][1]
        assert set(m["CDA"]) == {"NAch", "NSoc", "NRes", "NEng", "all"}


def test_sweep_text_and_out_dir(tmp_path):
    proc = cli("sweep", "pseudo", "--seeds", "2", "--iterations", "200", "--out", tmp_path / "o", "--quiet")
    assert proc.returncode == 0, proc.stderr
    assert "on" in proc.stdout and "off" in proc.stdout
    files = {p.name for p in (tmp_path / "o").iterdir()}
    assert {"sweep-pseudo.json", "fig4_4_pseudo.png", "fig4_4_pseudo_early.png"} <= files


@pytest.mark.parametrize("args, word", [
    (("sweep", "gamma"), "gamma"),
    (("sweep", "xi", "--seeds", "0"), "0"),
    (("report",), "--out"),
])
def test_cli_errors_are_one_line(args, word):
    proc = cli(*args)
    assert proc.returncode == 2, proc.stderr
    assert len(proc.stderr.splitlines()) == 1 and proc.stderr.startswith("homeo-sim: error:")
    assert word in proc.stderr and "Traceback" not in proc.stderr


def test_report_out_is_a_file(tmp_path):
    f = tmp_path / "file"
    f.write_text("x")
    proc = cli("report", "--out", f, "--seeds", "2", "--iterations", "50", "--quiet")
    assert proc.returncode == 2 and proc.stderr.startswith("homeo-sim: error:") and "not a directory" in proc.stderr


def test_window_rates_and_learning_speed_by_hand():
    expressed = np.array([1, 1, 0, 1, 1, 1], bool)
    satisfied = np.array([0, 1, 0, 1, 1, 1], bool)
    secure = np.array([1, 0, 1, 1, 1, 1], bool)
    h, r = window_rates(expressed, satisfied, secure, 3)
    # windows: [0], [0,1], [0,1,2], [1,2,3], [2,3,4], [3,4,5]
    assert list(h) == pytest.approx([0.0, 0.5, 0.5, 1.0, 1.0, 1.0])
    assert list(r) == pytest.approx([1.0, 0.5, 2 / 3, 2 / 3, 1.0, 1.0])
    # only full windows (t >= 3) count: HSR >= 0.8 first at t = 4, RSR >= 0.85 at t = 5
    assert learning_speed(h, r, window=3) == {"HSR": 4, "RSR": 5, "both": 5}
    assert learning_speed(h, r * 0, window=3)["both"] is None


def test_median_time_counts_never_as_late():
    assert median_time([10, None, 30]) == {"median": 30, "reached": 2, "of": 3, "per_seed": [10, None, 30]}
    assert median_time([None, None, 5])["median"] is None


def test_report_writes_pngs_and_markdown(tmp_path):
    from homeo_sim.report import build_report

    data = build_report(tmp_path, seeds=2, iterations=300, workers=2, quiet=True)
    files = {p.name for p in tmp_path.iterdir()}
    pngs = {"fig4_1_drives.png", "fig4_2_hsr_rsr.png", "fig4_3_xi.png", "fig4_4_pseudo.png", "fig4_4_pseudo_early.png",
            "fig4_5_dod.png", "baselines.png", "baselines_learning.png", "adaptive_dod.png"}
    assert pngs | {"report.md", "results.json"} <= files
    for p in pngs:
        assert (tmp_path / p).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    md = (tmp_path / "report.md").read_text()
    for needle in ("Table 4.5", "Fig 4.3", "Fig 4.4", "Fig 4.5", "Baselines", "adaptive DoD", "Trend checks",
                   "| HSR | | ", " 0.82 |", "Wall time", "## Fidelity score", "| HSR | ", "statements per 2-seed set: ",
                   "Goals (issue 25)"):
        assert needle in md, needle
    assert len(data["checks"]) == 9 and all(isinstance(c["ok"], bool) for c in data["checks"])
    assert all(c["why"] for c in data["checks"] if not c["ok"])  # a failing check always says why
    res = json.loads((tmp_path / "results.json").read_text())
    f = res["fidelity"]  # the fidelity score: 12 numbers of Table 4.5 and issue 31's 30 claims
    assert f["table_total"] == 12 and f["statements_total"] == 30 and len(res["statements"]) == 30
    assert f["summary"].startswith("Table 4.5 over 2 seeds: mean |error| ") and f"**{f['summary']}.**" in md
    assert f["summary"].endswith("statements per 2-seed set: %d of 30" % f["statements_per_set"][0])
    # a run of 300 iterations has no iterations 4001-5000: the claims on that stage say so and do not hold
    late = {st["id"]: st for st in res["statements"]}["still_growing"]
    assert late["ours"] == "not measured: these runs have no base@4000-5000" and not late["agrees"]
    assert f["errors"]["mean_abs_error"] == pytest.approx(sum(abs(r["error"]) for r in f["table"]) / 12)
    assert f["table_inside"] == sum(r["inside"] for r in f["table"])
    assert all(st["of"] == 1 for st in res["statements"])  # two seeds: one set
    assert res["policies"]["rule"]["metrics"]["HSR"]["per_seed"] == data["policies"]["rule"]["metrics"]["HSR"]["per_seed"]


# -- a scenario other than the thesis's: its own drive names, no reference block ---------------------

@pytest.mark.parametrize("param", ["dod", "xi", "pseudo"])
def test_sweeps_on_the_second_scenario(tmp_path, param):
    proc = cli("sweep", param, "--scenario", "garden", "--seeds", "2", "--iterations", "60", "--quiet", "--workers", "1",
               "--out", tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "CDA Duty" in proc.stdout.splitlines()[1] and "NAch" not in proc.stdout
    data = json.loads((tmp_path / f"sweep-{param}.json").read_text())
    assert [p["value"] for p in data["points"]] == list(SWEEPS[param])
    assert set(data["points"][0]["metrics"]["CDA"]) == {"Duty", "Heat", "Power", "all"}
    assert any(p.suffix == ".png" for p in tmp_path.iterdir())


def test_report_on_the_second_scenario_skips_the_thesis_comparisons(tmp_path):
    proc = cli("report", "--scenario", "garden", "--seeds", "2", "--iterations", "300", "--quiet", "--workers", "2",
               "--out", tmp_path)
    assert proc.returncode == 0, proc.stderr
    md = (tmp_path / "report.md").read_text()
    assert "no reference block" in md and "The thesis says" not in md and "What the thesis says" not in md
    assert "| thesis |" not in md and "CDA Duty" in md and "Baselines" in md and "threshold rules" in md
    res = json.loads((tmp_path / "results.json").read_text())
    assert res["statements"] == [] and res["scenario"] == "garden" and res["fidelity"]["table"] == []
    assert "Fidelity score" not in md
    assert set(res["policies"]) == {"objectq", "random", "rule", "flatq", "nofeedback", "adaptive"}
    assert "CDA_Duty@500" in res["pseudo_early"]["on"]
    for png in ("fig4_1_drives.png", "fig4_4_pseudo.png", "fig4_5_dod.png", "baselines.png"):
        assert (tmp_path / png).read_bytes()[:4] == b"\x89PNG"


def test_report_without_a_rule_policy_skips_the_rule_baseline(tmp_path):
    from homeo_decision.scenario import load_scenario, scenario_from_dict
    from homeo_decision.scenarios import SCENARIO_DIR
    from homeo_sim.report import baselines_for, report_configs
    from homeo_sim.runner import RunConfig as RC

    raw = json.loads((SCENARIO_DIR / "garden.json").read_text())
    raw.pop("rule_policy")
    sc = scenario_from_dict(raw)
    assert baselines_for(sc) == ("random", "flatq", "nofeedback")
    cfgs = report_configs(RC(iterations=10), baselines_for(sc))
    assert "policy=rule" not in cfgs and "policy=flatq" in cfgs
    assert "policy=rule" in report_configs(RC(iterations=10), baselines_for(load_scenario()))

"""The issues' acceptance figures, run as the user runs them (regression guards, not fits).

Every number here comes from running the calibrated thesis scenario; the thresholds are the
issues' targets, not our results. A change to an equation, the simulated human or the scenario
that breaks Table 4.5's targets or the thesis's trends fails here.
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from homeo_sim.runner import RunConfig, run_seeds
from homeo_sim.stats import aggregate

pytestmark = pytest.mark.slow


def test_table_4_5_targets_over_20_seeds():
    # issue 2: homeo-sim run --iterations 5000 --seeds 20 --json
    proc = subprocess.run([sys.executable, "-m", "homeo_sim.cli", "run", "--iterations", "5000", "--seeds", "20",
                           "--json", "--quiet"], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    m = json.loads(proc.stdout)["metrics"]
    assert m["HSR"]["mean"] >= 0.78
    assert m["RSR"]["mean"] >= 0.85  # issue 2's target; seeds 0-19 give 0.891 with issue 31's block (thesis 0.90)
    assert m["CEDA"]["all"]["mean"] <= 6.0
    assert m["CDA"]["NAch"]["mean"] <= 5.0


def test_issue_31_table_goals_on_the_confirmation_seeds():
    # issue 31: over 100 seeds that no search used (23000-23099, its confirmation, docs/FIDELITY.md), the mean
    # absolute relative error of the 12 numbers of Table 4.5 at most 5%, each within 15%. Measured: 4.9%, the
    # largest CEDA NEng +15.0%. On two sets measured afterwards CEDA NEng is past 15% (5000-5099: +15.3%,
    # 24000-24099: +22.5%; MAE 4.5% and 4.8%): "each within 15%" holds on this set, not on every set. (The claims
    # on the five 20-seed sets need the sweeps: homeo-sim report --seeds 100 --first-seed 23000.)
    from homeo_decision.scenario import load_scenario
    from homeo_sim.report.fidelity import error_summary, relative_errors

    proc = subprocess.run([sys.executable, "-m", "homeo_sim.cli", "run", "--seeds", "100", "--first-seed", "23000",
                           "--json", "--quiet"], capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert out["seeds"] == list(range(23000, 23100))
    rows = relative_errors(out["metrics"], load_scenario().reference.metrics)
    e = error_summary(rows)
    assert e["mean_abs_error"] <= 0.05 and e["goals"]["each_error"], [(r["metric"], round(r["error"], 3)) for r in rows]
    assert all(abs(x) <= 0.05 for x in e["headline_errors"].values())  # HSR -2.4%, RSR -4.3%


def _mean(cfg: RunConfig, seeds=range(10)) -> dict:
    res = run_seeds(cfg, seeds)
    return aggregate([r.metrics for r in res], ["NAch", "NSoc", "NRes", "NEng"])


def test_thesis_trends_over_10_seeds():
    # issue 6: the trends of Figs 4.3-4.5
    d0, d1 = _mean(RunConfig(dod=0.0)), _mean(RunConfig(dod=1.0))
    assert d1["HSR"]["mean"] - d0["HSR"]["mean"] >= 0.10
    assert d0["RSR"]["mean"] - d1["RSR"]["mean"] >= 0.20
    assert d0["HSR"]["mean"] >= 0.5
    x0, x2 = _mean(RunConfig(xi=0.0)), _mean(RunConfig(xi=2.0))
    assert x2["RSR"]["mean"] - x0["RSR"]["mean"] >= 0.20
    on, off = _mean(RunConfig()), _mean(RunConfig(pseudo_update=False))
    # issue 6 also asked a whole-run HSR gain of the pseudo update >= 0.05: not met (+0.037 over seeds 0-9 since
    # issue 15's block; issue 31 measured +3.0% over 23000-23099, the thesis says "about 10%"), so it is no test
    # here: homeo-sim report counts it among the thesis's claims, and docs/FIDELITY.md says why. What the thesis
    # says of it, "especially in the early stage", is checked below.
    assert on["HSR"]["mean"] > off["HSR"]["mean"]
    assert on["CDA"]["NAch"]["mean"] < off["CDA"]["NAch"]["mean"]


def test_pseudo_update_gain_is_early_over_10_seeds():
    # Sec 4.2.4: "resulting in higher HSR, especially in the early stage": the gain in cumulative HSR after 500
    # iterations larger than over the whole run (measured over seeds 0-9: +0.19 at 500, +0.04 at 5000).
    import numpy as np

    from homeo_sim.sweep import run_jobs

    on, off = run_jobs([RunConfig(pseudo_update=True), RunConfig(pseudo_update=False)], range(10), curves=True)

    def hsr_at(rs, t):
        i = int(np.searchsorted(rs[0].curves["t"], t, side="right")) - 1
        return float(np.mean([r.curves["HSR"][i] for r in rs]))

    assert hsr_at(on, 500) - hsr_at(off, 500) > hsr_at(on, 5000) - hsr_at(off, 5000) > 0

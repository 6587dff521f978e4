"""Issue 25's search tool (tools/error_search.py): its objective by hand, the seeds it keeps apart, and
its inputs (seed sets, changes, a trials file, any argument list): a value or one line, exit 2."""

from __future__ import annotations

import importlib
import json
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

TOOLS = Path(__file__).resolve().parents[1] / "tools"
FAST = settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                         HealthCheck.function_scoped_fixture])


def _es():
    if str(TOOLS) not in sys.path:
        sys.path.insert(0, str(TOOLS))
    return importlib.import_module("error_search")


def _point(errors, met, text=0, n_sets=2):
    names = ["HSR", "RSR", "CDA.NAch", "CDA.NSoc", "CDA.NRes", "CDA.NEng", "CDA.all",
             "CEDA.NAch", "CEDA.NSoc", "CEDA.NRes", "CEDA.NEng", "CEDA.all"]
    errs = dict(zip(names, errors))
    return {"errors": errs, "mae": sum(abs(e) for e in errors) / 12, "met_per_set": met, "n_sets": n_sets,
            "text_distance": text}


def test_the_objective_by_hand():
    es = _es()
    # every error 5%: MAE 5 points; nothing beyond 15%; HSR, RSR at 5% (not beyond); 10 and 9 statements:
    # 3 x 9.5 = 28.5, no shortfall; one text departure: -1
    e = _point([0.05] * 12, [10, 9], text=1)
    assert es.score(e) == pytest.approx(-5 + 28.5 - 1)
    # CEDA NEng at +35% (20 beyond 15: -40), RSR at -9% (4 beyond 5 and it is a headline rate: -16),
    # sets 7 and 10 (mean 8.5: +25.5; shortfall 2 below 9: -6)
    errors = [0.0] * 12
    errors[10], errors[1] = 0.35, -0.09
    e = _point(errors, [7, 10])
    assert es.score(e) == pytest.approx(-100 * 0.44 / 12 - 40 - 16 + 25.5 - 6)
    # statements not run (above the gate): as if none held on either set
    e = _point([0.0] * 12, None)
    assert es.score(e) == pytest.approx(0 - 3 * 9 * 2)


def test_text_distance_adds_the_readings_of_issue_25():
    es = _es()
    start = es.current_open()
    base = es.text_distance(start)
    assert es.text_distance({**start, "ongoing_effects": "every_tick"}) == base + 1
    assert es.text_distance({**start, "activation_boundary": "above", "drive_growth": {"NEng": "not_lowered"}}) == base + 2


def test_select_prefers_the_text_among_near_best_points():
    es = _es()
    pts = [{"score": 10.0, "text_distance": 3}, {"score": 8.5, "text_distance": 1}, {"score": 7.0, "text_distance": 0}]
    assert es.select(pts) is pts[1]  # 7.0 is more than 2 below the best
    assert es.select(pts, slack=5) is pts[2]


def test_a_suggested_point_is_a_valid_open_block():
    optuna = pytest.importorskip("optuna")  # a tool dependency (make calibrate-setup)
    from homeo_decision.scenario import load_scenario

    es = _es()
    start = es.current_open()
    o = es.suggest(optuna.trial.FixedTrial(es.params(start)), start)
    assert o == start  # the current default round-trips through the search's parameters
    load_scenario(overrides={**start, **es.suggest(optuna.trial.FixedTrial(
        {**es.params(start), "ongoing_effects": "every_tick", "growth_NEng": "not_lowered"}), start)})


def test_the_seeds_it_validates_on_must_be_apart_from_the_search(tmp_path):
    es = _es()
    e = {"open": es.current_open(), "score": 1.0, "table_seeds": [2000, 2099], "statement_seeds": [2000, 2039]}
    f = tmp_path / "trials.jsonl"
    f.write_text(json.dumps(e) + "\n")
    proc = subprocess.run([sys.executable, str(TOOLS / "error_search.py"), "validate", "--from", str(f),
                           "--seeds", "2090-2109"], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.strip() == "error_search.py: error: --seeds overlap the seeds the search used"


@pytest.mark.parametrize("args, says", [
    (["confirm", "--seeds", "x-y"], "not a seed set"),
    (["confirm", "--change", "initial_q"], "not KEY=JSON"),
    (["confirm", "--change", "no_such=1"], "not a searched open choice"),
    (["confirm", "--change", "ongoing_effects=\"sometimes\""], "ongoing_effects"),
    (["search", "--trials", "0"], "below the minimum"),
    (["validate", "--from", "/no/such/file.jsonl"], "No such file"),
    (["nothing"], "invalid choice"),
])
def test_a_bad_input_is_one_line_and_exit_2(args, says):
    proc = subprocess.run([sys.executable, str(TOOLS / "error_search.py"), *args], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 2 and proc.stdout == "", proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and says in lines[0] and "Traceback" not in proc.stderr


JSON = st.recursive(st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=10),
                    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=8), inner, max_size=3),
                    max_leaves=8)


@FAST
@given(args=st.lists(st.text(max_size=12) | st.sampled_from(
    ["search", "validate", "confirm", "--trials", "--seeds", "--change", "--gate", "--best", "--workers", "--from",
     "--search-seeds", "--statement-seeds", "--sampler-seed", "-1", "1e9", "nan", "=", "initial_q=", "2000-1999"]),
    max_size=6))
def test_any_argument_list_parses_or_is_one_line(args):
    from homeo_msgs_py.cli_args import UserError

    if any(a.startswith("-h") or a.startswith("--h") for a in args):
        return  # help prints and exits 0
    try:
        _es().build_parser().parse_args(args)
    except UserError as exc:
        assert "\n" not in str(exc)


@FAST
@given(spec=st.text(max_size=40) | st.builds(lambda k, v: f"{k}={json.dumps(v)}",
                                              st.sampled_from(["initial_q", "ongoing_effects", "drive_growth",
                                                               "activation_boundary", "tie_break", "nope"]), JSON))
def test_a_change_is_a_valid_point_or_one_line(spec):
    from homeo_msgs_py.cli_args import UserError

    es = _es()
    start = es.current_open()
    try:
        got = es.change_arg(spec, start)
    except UserError as exc:
        assert "\n" not in str(exc) and str(exc)
        return
    assert set(got) <= set(start)


@FAST
@given(lines=st.lists(st.text(max_size=40) | JSON.map(json.dumps), max_size=4))
def test_a_trials_file_is_read_or_one_line(tmp_path, lines):
    from homeo_msgs_py.cli_args import UserError

    f = tmp_path / "trials.jsonl"
    f.write_text("\n".join(lines), encoding="utf-8", errors="surrogatepass")
    try:
        got = _es().read_trials(str(f))
    except UserError as exc:
        assert "\n" not in str(exc) and str(exc).startswith(str(f))
        return
    assert got and all(isinstance(e["open"], dict) for e in got)

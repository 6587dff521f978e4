"""The third stage of issue 15's calibration tools (tools/joint_search.py refine/validation,
tools/heldout_check.py): the neighbourhood it scores and the inputs it refuses."""

from __future__ import annotations

import importlib
import subprocess
import sys
from pathlib import Path

import pytest

TOOLS = Path(__file__).resolve().parents[1] / "tools"


def _tool(name):
    if str(TOOLS) not in sys.path:
        sys.path.insert(0, str(TOOLS))
    return importlib.import_module(name)


def test_the_neighbourhood_moves_one_searched_choice_one_step():
    pytest.importorskip("optuna")  # a tool dependency (make calibrate-setup), not the runtime's
    j = _tool("joint_search")
    # around issue 15's block (hand-counted there; issue 25 moved the scenario's)
    start = {**j.current_open(), "initial_q": 15.0, "tie_break": "first", "value_max_over": "all",
             "metrics_sample": "end", "human_no_intention_prob": 0.35, "human_proposal_prob": 0.8}
    got = j.neighbours(start)
    # hand count around that block: initial_q 15 +-0.5, +-1 (4); scold 2 +-1 (2); serving_growth (2);
    # reward_span, tie_break, value_max_over, metrics_sample (1 each); p_none 0.35 +-0.05 (2); leave prob
    # 0 -> 0.02, 0.05, 0.1 (3); proposal choice (2); proposal prob 0.8 +-0.1 (2); invalid_actions (1);
    # always-valid (3); time_increase (1); NSoc, NRes growth (2 + 2); no_activated_motivation (1). The
    # human never leaves, so human_return_prob and on_leave_effects are not moved.
    assert len(got) == 4 + 2 + 2 + 4 + 2 + 3 + 2 + 2 + 1 + 3 + 1 + 4 + 1 == 31
    for o in got:
        moved = [k for k in j.SEARCHED if o[k] != start[k]]
        assert len(moved) == 1, moved
        assert moved[0] not in ("human_return_prob", "on_leave_effects")
    assert sorted(o["initial_q"] for o in got if o["initial_q"] != start["initial_q"]) == [
        start["initial_q"] - 1, start["initial_q"] - 0.5, start["initial_q"] + 0.5, start["initial_q"] + 1]


def test_validation_seeds_must_stay_apart():
    j = _tool("joint_search")
    assert j._validation(("300-301", 3), [100, 101], [200, 201]) == ([300, 301], 3)
    assert j._validation(("300-301", 0), [100], [200]) is None
    with pytest.raises(SystemExit, match="overlap"):
        j._validation(("200-210", 3), [100], [200])
    with pytest.raises(SystemExit, match="overlap"):
        j._validation(("100-101", 3), [100], [200])


@pytest.mark.parametrize("args, says", [
    (["x-y"], "bad seed set"),
    (["1-2", "--change", "initial_q"], "bad seed set or change"),
    (["1-2", "--change", "initial_q=notjson"], "bad seed set or change"),
    (["1-2", "--change", "no_such_choice=1"], "not a searched open choice: no_such_choice"),
])
def test_heldout_check_refuses_a_bad_input_on_one_line(args, says):
    proc = subprocess.run([sys.executable, str(TOOLS / "heldout_check.py"), *args], capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 2 and proc.stdout == ""
    err = proc.stderr.strip().splitlines()
    assert says in err[-1] and "Traceback" not in proc.stderr


from hypothesis import given, settings, strategies as st  # noqa: E402


@settings(max_examples=200, deadline=None)
@given(spec=st.text(max_size=12) | st.from_regex(r"\A-?[0-9]{1,3}(-[0-9]{0,3})?\Z"))
def test_a_seed_set_is_a_range_or_a_one_line_refusal(spec):
    """--search-seeds / --confirm-seeds / --validate-seeds and heldout_check's sets (our own A-B form)."""
    j = _tool("joint_search")
    try:
        got = j._seeds(spec)
    except j.SeedSetError as exc:
        assert "\n" not in str(exc)
        return
    a, _, b = spec.partition("-")
    assert got == list(range(int(a), int(b or a) + 1)) and got and got[0] >= 0


@pytest.mark.parametrize("spec, want", [("3", [3]), ("2-4", [2, 3, 4]), ("4-2", None), ("-1", None), ("a-b", None),
                                        ("1-", None), ("", None), ("1-2-3", None)])
def test_seed_sets_by_hand(spec, want):
    j = _tool("joint_search")
    if want is None:
        with pytest.raises(j.SeedSetError):
            j._seeds(spec)
    else:
        assert j._seeds(spec) == want


def test_calibrate_refuses_a_bad_seed_set_on_one_line():
    proc = subprocess.run([sys.executable, str(TOOLS / "calibrate.py"), "--joint", "--refine", "--validate-seeds", "9-1"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert proc.stderr.strip().splitlines() == ["calibrate: not a seed set A-B with 0 <= A <= B: '9-1'"]

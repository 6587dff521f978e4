"""Same seed, same run; different seeds, different runs; worker count does not matter."""

from __future__ import annotations

import pytest

from homeo_sim.runner import RunConfig, run_episode, run_seeds

N = 300


@pytest.fixture(scope="module")
def seed3():
    return run_episode(RunConfig(iterations=N, seed=3), keep_actions=True)


def test_same_seed_same_actions_and_metrics(seed3):
    again = run_episode(RunConfig(iterations=N, seed=3), keep_actions=True)
    assert len(seed3.actions) == N
    assert again.actions == seed3.actions
    assert again.metrics == seed3.metrics


def test_same_seed_with_shared_scenario_object(thesis, seed3):
    # passing a pre-loaded scenario (as the CLI does) changes nothing
    again = run_episode(RunConfig(iterations=N, seed=3), thesis, keep_actions=True)
    assert again.actions == seed3.actions


def test_different_seeds_differ(seed3):
    other = run_episode(RunConfig(iterations=N, seed=4), keep_actions=True)
    assert other.actions != seed3.actions


def test_run_seeds_independent_of_worker_count():
    cfg = RunConfig(iterations=200)
    one = run_seeds(cfg, [0, 1, 2], workers=1)
    two = run_seeds(cfg, [0, 1, 2], workers=2)
    assert [r.seed for r in one] == [r.seed for r in two] == [0, 1, 2]
    assert [r.metrics for r in one] == [r.metrics for r in two]
    assert one[0].metrics != one[1].metrics


def test_run_seeds_matches_single_episodes():
    cfg = RunConfig(iterations=200)
    many = run_seeds(cfg, [2, 0], workers=1)
    assert [r.seed for r in many] == [2, 0]
    assert many[0].metrics == run_episode(RunConfig(iterations=200, seed=2)).metrics
    assert many[1].metrics == run_episode(RunConfig(iterations=200, seed=0)).metrics


def test_trace_is_reproducible(tmp_path):
    a, b = tmp_path / "a.jsonl", tmp_path / "b.jsonl"
    run_episode(RunConfig(iterations=100, seed=7, trace=str(a)))
    run_episode(RunConfig(iterations=100, seed=7, trace=str(b)))
    assert a.read_text() == b.read_text()
    assert len(a.read_text().splitlines()) == 100


def test_float_sums_are_the_same_bits_on_python_3_11_and_3_12():
    """Python 3.12's ``sum`` compensates rounding; 3.11's adds left to right. The core sums left to
    right on both (``homeo_decision.numeric.left_sum``), so a seed's run prints the same numbers:
    1e16 + 1 rounds back to 1e16 (the spacing of doubles there is 2), so the sum is 0, not 1."""
    from homeo_decision.numeric import left_sum
    from homeo_decision.objectq import softmax_probs
    from homeo_sim.stats import describe

    assert left_sum([1e16, 1.0, -1e16]) == 0.0
    assert describe([1e16, 1.0, -1e16])["mean"] == 0.0
    p = softmax_probs([0.0, -1e-300, 0.0], 1.0)
    assert p == [1 / left_sum([1.0, 1.0, 1.0])] * 3

"""Small cases of the intention recogniser computed by hand (Section 2.3: Eq 2.10 and the EM updates), written for
the mutants ``make mutation`` found alive in ``homeo_intention.model`` and ``homeo_intention.em``
(tools/mutation.py): each assertion fails under one of them. No pgmpy: fast and ROS-free."""

from __future__ import annotations

import re

import numpy as np
import pytest

from homeo_decision.scenario import scenario_from_dict
from homeo_intention import IntentionModel, IntentionModelError
from test_intention_core import toy_observations  # the same toy CPDs


def refused(message: str, error=ValueError):
    """The whole one-line message: a part of it would let a message with anything added pass."""
    return pytest.raises(error, match=f"^{re.escape(message)}$")


@pytest.fixture
def sc(toy_raw):
    """The toy scenario (conftest.py: intentions none, on, come) with observations whose CPDs are easy to multiply:
    P(I) = 0.5, 0.3, 0.2; P(gesture | I) and P(keyword | I) as test_intention_core.toy_observations gives them (the
    unlisted symbol takes the rest); movement
    has no prior given: 1/3 for each of its symbols."""
    raw = toy_raw()
    raw["observations"] = {k: v for k, v in toy_observations().items() if k != "habits"}  # the model needs no habits
    return scenario_from_dict(raw)


# Eq 2.10 with movement unobserved: P(I) P(gesture | I) P(keyword | I)
# (point, on): none 0.5*0.1*0.05 = 0.0025, on 0.3*0.7*0.7 = 0.147, come 0.2*0.1*0.1 = 0.002: on
POINT_ON = {"gesture": "point", "keyword": "on"}
# (none, none): none 0.5*0.8*0.9 = 0.36, on 0.3*0.2*0.2 = 0.012, come 0.2*0.3*0.3 = 0.018: none
NONE_NONE = {"gesture": "none", "keyword": "none"}


# -- homeo_intention.model -----------------------------------------------------------------------------------
def test_the_settings_are_checked_at_their_bounds(sc):
    assert IntentionModel(sc, threshold=1.0).threshold == 1.0  # [0, 1] is closed: "none unless certain" is allowed
    with refused("threshold must be in [0, 1], got 1.5"):
        IntentionModel(sc, threshold=1.5)
    with refused("prior_strength must be >= 0, got -1.0"):
        IntentionModel(sc, prior_strength=-1)


def test_unlabelled_cues_are_counted_without_em(sc):
    m = IntentionModel(sc)
    assert (m.em_runs, m.em_iterations) == (0, 0)  # nothing seen, nothing run
    assert m.learn(POINT_ON, None) == 0 and m.learn(POINT_ON, None) == 0  # not revealed: counted, no EM (0 iterations)
    assert m.unlabelled[m.coder.cell(POINT_ON)] == 2.0 and m.unlabelled.sum() == 2.0  # one count per tick: 1 + 1
    assert (m.em_runs, m.em_iterations) == (0, 0)


def test_a_label_is_an_intention_index_from_none_to_the_last(sc):
    m = IntentionModel(sc)
    assert m.recognise(NONE_NONE).intention == 0
    assert m.learn(NONE_NONE, 0) == 0  # 'none' (index 0) is a label; it agrees with the recognition: counted, no EM
    assert m.labelled[0, m.coder.cell(NONE_NONE)] == 1.0 and m.labelled.sum() == 1.0
    with refused("label must be an intention index in [0, 2] or None, got 3"):  # K = 3 intentions: 0, 1, 2
        m.learn(NONE_NONE, 3)


def test_each_correction_runs_em_and_the_runs_add_up(sc):
    m = IntentionModel(sc)
    assert m.recognise(POINT_ON).intention == 1
    # a correction (label 'come' where 'on' was recognised) runs EM. With labelled counts only, the M-step does not
    # read the parameters: the first iteration moves them to the MAP estimate, the second moves nothing (0 <= 1e-6):
    # 2 iterations
    assert m.learn(POINT_ON, 2) == 2
    assert m.recognise(NONE_NONE).intention == 0  # still none after one 'come' label on another cell
    assert m.learn(NONE_NONE, 1) == 2  # a second correction: again 2
    assert (m.em_runs, m.em_iterations) == (2, 2 + 2)


def test_a_run_stops_after_max_iter_iterations(sc):
    # atol -1: no move is ever <= -1, so EM runs until max_iter: the default, 100, or the one given
    assert IntentionModel(sc, atol=-1.0).learn(POINT_ON, 2) == 100
    assert IntentionModel(sc, max_iter=3, atol=-1.0).learn(POINT_ON, 2) == 3


def test_a_model_as_json_keeps_its_meta_and_takes_the_settings_given(sc):
    m = IntentionModel(sc)
    raw = m.to_json({"user": "ann"})
    assert raw["meta"]["user"] == "ann" and raw["meta"]["threshold"] == 0.0
    m2 = IntentionModel.from_json(sc, raw, threshold=0.5, prior_strength=2.0)
    assert (m2.threshold, m2.strength) == (0.5, 2.0)
    # a refusal names where the model came from: "<memory>" unless told
    schema = "not an intention-model file (schema must be 'homeo-intention-model')"
    with refused(f"<memory>: {schema}", IntentionModelError):
        IntentionModel.from_json(sc, {"schema": "other"})
    with refused(f"a.json: {schema}", IntentionModelError):
        IntentionModel.from_json(sc, {"schema": "other"}, "a.json")


# -- homeo_intention.em: run_em on counts built by hand ---------------------------------------------------------
# P(gesture | I) rows of the prior (none, point, beckon), P(keyword | I) rows (none, on, come; come takes the rest)
G0 = [[0.8, 0.1, 0.1], [0.2, 0.7, 0.1], [0.3, 0.1, 0.6]]
W0 = [[0.9, 0.05, 0.05], [0.2, 0.7, 0.1], [0.3, 0.1, 0.6]]
THIRDS = [[1 / 3] * 3] * 3  # movement: no prior given, 1/3 each


def _counts(m, rows):
    """labelled (K x cells) and unlabelled (cells) counts of ``rows``: (observation, label or None)."""
    lab, unl = np.zeros_like(m.labelled), np.zeros_like(m.unlabelled)
    for obs, label in rows:
        if label is None:
            unl[m.coder.cell(obs)] += 1.0
        else:
            lab[label, m.coder.cell(obs)] += 1.0
    return lab, unl


def _close(p, pi, rho, likes):
    assert p.pi.tolist() == pytest.approx(pi, abs=1e-12) and p.rho.tolist() == pytest.approx(rho, abs=1e-12)
    for got, want in zip(p.likes, likes):
        assert got.tolist() == [pytest.approx(r, abs=1e-12) for r in want]


def test_ml_em_keeps_what_no_count_speaks_of(sc):
    from homeo_intention.em import run_em
    from homeo_intention.model import prior_params

    m, prior = IntentionModel(sc), prior_params(sc)
    lab, unl = _counts(m, [(POINT_ON, 1)])  # one tick: (point, -, on) revealed as 'on'
    p, n = run_em(prior, lab, unl, m.coder.shape, prior, 0.0)
    # strength 0 (maximum likelihood), labelled counts only: P(I) = counts / total = (0, 1, 0) / 1;
    # rho_k = revealed_k / n_k: 'on' 1 / 1 = 1, 'none' and 'come' 0 / 0: no count, kept at 0.5;
    # P(s | on) = its counts: point 1 of 1, keyword on 1 of 1; every other row (and movement, never seen): kept
    _close(p, [0.0, 1.0, 0.0], [0.5, 1.0, 0.5],
           [[G0[0], [0.0, 1.0, 0.0], G0[2]], THIRDS, [W0[0], [0.0, 1.0, 0.0], W0[2]]])
    assert n == 2  # the counts alone fix the M-step: the second iteration moves nothing
    p, n = run_em(prior, lab * 0, unl, m.coder.shape, prior, 0.0)  # no count at all: every parameter kept
    _close(p, [0.5, 0.3, 0.2], [0.5, 0.5, 0.5], [G0, THIRDS, W0])
    assert n == 1  # the first iteration moves nothing


def test_em_over_an_unlabelled_tick_with_unobserved_channels(sc):
    from homeo_intention.em import run_em
    from homeo_intention.model import prior_params

    m, prior = IntentionModel(sc), prior_params(sc)
    lab, unl = _counts(m, [({"gesture": "point"}, None)])  # movement and keyword unobserved: they drop out
    p, n = run_em(prior, lab, unl, m.coder.shape, prior, 0.0)
    # E-step: w_k proportional to P(k) (1 - rho_k) P(point | k) = 0.5*0.5*0.1 = 0.025, 0.3*0.5*0.7 = 0.105,
    # 0.2*0.5*0.1 = 0.01; sum 0.14: w = 5/28, 21/28, 2/28. M-step (strength 0): P(I) = w; rho = 0 / w_k = 0;
    # P(point | k) = w_k / w_k = 1; movement and keyword have no counts: kept.
    # Iteration 2: w_k proportional to P(k) * 1 * 1 = w_k again: nothing moves
    w = [5 / 28, 21 / 28, 2 / 28]
    _close(p, w, [0.0, 0.0, 0.0], [[[0.0, 1.0, 0.0]] * 3, THIRDS, W0])
    assert n == 2


def test_a_tick_no_intention_explains_keeps_the_prior_as_its_posterior(sc):
    from homeo_intention.em import Params, run_em
    from homeo_intention.model import prior_params

    m, prior = IntentionModel(sc), prior_params(sc)
    start = Params(prior.pi, [np.array([[1.0, 0.0, 0.0]] * 3), *prior.likes[1:]])  # every intention gestures 'none'
    lab, unl = _counts(m, [({"gesture": "point"}, None)])
    p, n = run_em(start, lab, unl, m.coder.shape, prior, 0.0)
    # P(point | k) = 0 for every k: zero evidence, the tick's weights are P(I) = 0.5, 0.3, 0.2 themselves;
    # M-step: P(I) = those; rho = 0; P(point | k) = 1. Iteration 2: w proportional to P(k) * 1: nothing moves
    _close(p, [0.5, 0.3, 0.2], [0.0, 0.0, 0.0], [[[0.0, 1.0, 0.0]] * 3, THIRDS, W0])
    assert n == 2


def test_when_an_em_run_stops(sc):
    from homeo_intention.em import run_em
    from homeo_intention.model import prior_params

    m, prior = IntentionModel(sc), prior_params(sc)
    lab, unl = _counts(m, [(POINT_ON, 1), (NONE_NONE, 0)])
    shape = m.coder.shape
    # labelled counts only: iteration 1 reaches the MAP estimate, iteration 2 moves exactly 0
    assert run_em(prior, lab, unl, shape, prior, 10.0)[1] == 2  # 0 <= the default atol 1e-6
    assert run_em(prior, lab, unl, shape, prior, 10.0, atol=0.0)[1] == 2  # a move of 0 is within atol 0
    assert run_em(prior, lab, unl, shape, prior, 10.0, atol=-1.0)[1] == 100  # never within: the default max_iter
    p, n = run_em(prior, lab, unl, shape, prior, 10.0, max_iter=0)  # no iteration: the start, 0 iterations
    assert n == 0
    _close(p, [0.5, 0.3, 0.2], [0.5, 0.5, 0.5], [G0, THIRDS, W0])

"""The intention recogniser's core (Section 2.3, Eq 2.10): posterior, errors, EM against pgmpy, files."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

from homeo_decision.scenario import ScenarioError, scenario_from_dict
from homeo_intention import IntentionModel, IntentionModelError, UnknownObservation
from homeo_intention.em import Params, run_em
from homeo_intention.network import INTENTION, posterior_table

with warnings.catch_warnings():
    warnings.simplefilter("ignore", FutureWarning)
    import pandas as pd
    from pgmpy.factors.discrete import TabularCPD
    from pgmpy.inference import VariableElimination
    from pgmpy.models import DiscreteBayesianNetwork
    from pgmpy.parameter_estimator import DiscreteBayesianEstimator, DiscreteEM

CH = ("gesture", "movement", "keyword")


def toy_observations() -> dict:
    """Intentions none / on / come; prior P(I) = 0.5 / 0.3 / 0.2 and exact CPDs (hand-checkable)."""
    return {
        "gesture": ["none", "point", "beckon"],
        "movement": ["still", "approaching", "leaving"],
        "keyword": ["none", "on", "come"],
        "prior": {
            "intention": {"none": 0.5, "on": 0.3, "come": 0.2},
            "none": {"gesture": {"none": 0.8, "point": 0.1, "beckon": 0.1}, "keyword": {"none": 0.9, "on": 0.05}},
            "on": {"gesture": {"none": 0.2, "point": 0.7, "beckon": 0.1}, "keyword": {"none": 0.2, "on": 0.7}},
            "come": {"gesture": {"none": 0.3, "point": 0.1, "beckon": 0.6}, "keyword": {"none": 0.3, "on": 0.1}},
        },
        "habits": {
            "none": {"gesture": {"none": 1.0}, "keyword": {"none": 1.0}},
            "on": {"gesture": {"point": 1.0}, "keyword": {"on": 1.0}},
            "come": {"gesture": {"beckon": 1.0}, "keyword": {"none": 1.0}},
        },
    }


@pytest.fixture
def toy_obs_raw(toy_raw):
    def build():
        raw = toy_raw()
        raw["observations"] = toy_observations()
        return raw
    return build


@pytest.fixture
def toy_sc(toy_obs_raw):
    return scenario_from_dict(toy_obs_raw())


# -- Eq 2.10: the posterior ------------------------------------------------------------------

def test_posterior_hand_computed_on_two_features(toy_sc):
    # movement unobserved: a two-feature network, gesture and keyword.
    # z = (point, on): none 0.5*0.1*0.05 = 0.0025, on 0.3*0.7*0.7 = 0.147, come 0.2*0.1*0.1 = 0.002
    m = IntentionModel(toy_sc)
    r = m.recognise({"gesture": "point", "keyword": "on"})
    z = 0.0025 + 0.147 + 0.002
    assert r.posterior == pytest.approx([0.0025 / z, 0.147 / z, 0.002 / z], abs=1e-12)
    assert r.intention == 1 and r.confidence == pytest.approx(0.147 / z)
    # z = (beckon, none): none 0.5*0.1*0.9 = 0.045, on 0.3*0.1*0.2 = 0.006, come 0.2*0.6*0.3 = 0.036
    r = m.recognise({"gesture": "beckon", "keyword": "none"})
    z = 0.045 + 0.006 + 0.036
    assert r.posterior == pytest.approx([0.045 / z, 0.006 / z, 0.036 / z], abs=1e-12)
    assert r.intention == 0  # arg-max: none (Eq 2.10)


def test_threshold_turns_an_unsure_recognition_into_none(toy_sc):
    obs = {"gesture": "beckon", "keyword": "come"}
    r = IntentionModel(toy_sc).recognise(obs)
    assert r.intention == 2 and r.confidence < 0.95
    assert IntentionModel(toy_sc, threshold=0.95).recognise(obs).intention == 0
    # the boundary: "below the threshold" is none, a confidence exactly at it is recognised
    assert IntentionModel(toy_sc, threshold=r.confidence).recognise(obs).intention == 2
    assert IntentionModel(toy_sc, threshold=float(np.nextafter(r.confidence, 1.0))).recognise(obs).intention == 0


def test_posterior_table_equals_pgmpy_exact_inference(thesis):
    m = IntentionModel(thesis)
    ve = VariableElimination(m.network())
    rng = np.random.default_rng(0)
    for _ in range(25):  # random full and partial observations
        obs = {ch: (None if rng.random() < 0.25 else str(rng.choice(thesis.observations.alphabets[ch]))) for ch in CH}
        ev = {k: v for k, v in obs.items() if v is not None}
        q = ve.query([INTENTION], evidence=ev, show_progress=False) if ev else ve.query([INTENTION], show_progress=False)
        exact = [q.get_value(**{INTENTION: n}) for n in thesis.intention_names]
        assert m.recognise(obs).posterior == pytest.approx(exact, abs=1e-12)


def test_unknown_symbols_are_rejected_with_the_known_ones(toy_sc):
    m = IntentionModel(toy_sc)
    with pytest.raises(UnknownObservation, match=r"unknown gesture 'wave'; known: none, point, beckon"):
        m.recognise({"gesture": "wave", "movement": "still", "keyword": "on"})
    with pytest.raises(UnknownObservation, match=r"unknown keyword 'dark'; known: none, on, come"):
        m.learn({"gesture": "none", "keyword": "dark"}, None)
    with pytest.raises(ValueError, match="label must be an intention index"):
        m.learn({"gesture": "none"}, 7)
    assert isinstance(UnknownObservation("x"), ValueError)


def test_oracle_returns_the_true_intention(toy_sc):
    from homeo_decision.environment import Observation
    from homeo_decision.robot import OracleRecognition

    o = OracleRecognition(toy_sc)
    r = o.tick(Observation(0, (), 2, {"gesture": "none"}), None)
    assert (r.intention, r.posterior, r.confidence) == (2, [0.0, 0.0, 1.0], 1.0)
    with pytest.raises(ValueError, match="needs the intention"):
        o.check(Observation(0, (), None, {"gesture": "none"}))


# -- the scenario's observations block ------------------------------------------------------

@pytest.mark.parametrize("edit, message", [
    (lambda o: o["prior"]["on"].update(keyword={"off": 0.5}), "prior.on.keyword: unknown symbol 'off'"),
    (lambda o: o["prior"]["on"].update(gesture={"point": 0.9, "none": 0.3}), "sum to 1.2, more than 1"),
    (lambda o: o["prior"].pop("come"), "lacks intention"),
    (lambda o: o["prior"].update(dance={}), "unknown intention 'dance'"),
    (lambda o: o.update(keyword=[]), "observations.keyword must be a non-empty list"),
    (lambda o: o.update(gesture=["none", "none"]), "declared twice"),
    (lambda o: o.update(smell=["x"]), "unknown key"),
    (lambda o: o.pop("prior"), "missing 'prior'"),
    (lambda o: o["habits"]["on"].update(keyword={"on": 0.5, "none": 0.5, "come": 0.1}), "more than 1"),
])
def test_bad_observation_blocks_are_rejected(toy_obs_raw, edit, message):
    raw = toy_obs_raw()
    edit(raw["observations"])
    with pytest.raises(ScenarioError, match=message):
        scenario_from_dict(raw)


def test_scenario_without_observations_cannot_recognise(toy):
    with pytest.raises(ScenarioError, match="no 'observations' block"):
        IntentionModel(toy)


# -- EM against pgmpy ---------------------------------------------------------------------------

def _frame(rows):
    return pd.DataFrame(rows, columns=[INTENTION, *CH])


def _counts(m, rows):
    """Feed (intention name or None, g, m, w) rows to a model's counts (no EM)."""
    for it, g, mv, w in rows:
        c = m.coder.cell({"gesture": g, "movement": mv, "keyword": w})
        if it is None:
            m.unlabelled[c] += 1
        else:
            m.labelled[m.names.index(it), c] += 1


def _cpd_values(cpds, var, states, parent_states=None):
    c = next(c for c in cpds if c.variable == var)
    rows = [c.state_names[var].index(s) for s in states]
    v = c.values[rows]
    if parent_states is not None:
        v = v[:, [c.state_names[INTENTION].index(s) for s in parent_states]]
    return np.asarray(v, float)


def _sample_rows(sc, n, seed, labelled_share):
    """Rows drawn from the scenario's habits; a share of them labelled."""
    from homeo_sim.human import SimHuman

    h = SimHuman(sc, seed)
    rng = np.random.default_rng(seed)
    rows = []
    for _ in range(n):
        h.intention = int(rng.integers(len(sc.intention_names)))
        o = h.observe()
        it = sc.intention_names[h.intention] if rng.random() < labelled_share else None
        rows.append((it, o["gesture"], o["movement"], o["keyword"]))
    return rows


def test_labelled_em_is_pgmpys_map_estimate(thesis):
    # all rows labelled: one M-step = pgmpy's Bayesian estimator with the textbook prior as pseudo counts
    m = IntentionModel(thesis, prior_strength=5.0)
    rows = _sample_rows(thesis, 400, 1, 1.0)
    _counts(m, rows)
    m.fit()
    names = thesis.intention_names
    K = len(names)
    bn = DiscreteBayesianNetwork([(INTENTION, ch) for ch in CH])
    pseudo = {INTENTION: (5.0 * K * m.prior.pi).reshape(-1, 1)}
    for ch, L0 in zip(CH, m.prior.likes):
        pseudo[ch] = 5.0 * L0.T
    states = {INTENTION: names} | {ch: list(thesis.observations.alphabets[ch]) for ch in CH}
    est = DiscreteBayesianEstimator(prior_type="dirichlet", pseudo_counts=pseudo, state_names=states)
    cpds = est.fit(bn, _frame(rows)).parameters_
    assert m.params.pi == pytest.approx(_cpd_values(cpds, INTENTION, names).ravel(), abs=1e-12)
    for ch, L in zip(CH, m.params.likes):
        assert L.T == pytest.approx(_cpd_values(cpds, ch, states[ch], names), abs=1e-12)


def test_unlabelled_em_matches_pgmpy_discrete_em(toy_sc):
    # nothing labelled, no pseudo counts: our EM over counts = pgmpy's DiscreteEM from the same start
    m = IntentionModel(toy_sc, prior_strength=0.0)
    rows = [(None, g, mv, w) for (_, g, mv, w) in _sample_rows(toy_sc, 300, 2, 0.0)]
    rows += [(None, "point", "still", "none"), (None, "beckon", "leaving", "on")] * 5  # some mixed signals
    _counts(m, rows)
    start = Params(np.array([0.4, 0.35, 0.25]), [L * 0.8 + 0.2 / L.shape[1] for L in m.prior.likes])
    ours5, _ = run_em(start, m.labelled, m.unlabelled, m.coder.shape, m.prior, 0.0, max_iter=5, atol=0.0)
    ours, n = run_em(start, m.labelled, m.unlabelled, m.coder.shape, m.prior, 0.0, max_iter=500, atol=1e-10)
    ids = [0, 1, 2]  # pgmpy names a latent variable's states 0..K-1
    states = {INTENTION: ids} | {ch: list(toy_sc.observations.alphabets[ch]) for ch in CH}
    init = {INTENTION: TabularCPD(INTENTION, 3, start.pi.reshape(-1, 1), state_names={INTENTION: ids})}
    for ch, L in zip(CH, start.likes):
        init[ch] = TabularCPD(ch, L.shape[1], L.T, evidence=[INTENTION], evidence_card=[3],
                              state_names={ch: states[ch], INTENTION: ids})
    bn = DiscreteBayesianNetwork([(INTENTION, ch) for ch in CH], latents={INTENTION})
    data = pd.DataFrame([r[1:] for r in rows], columns=list(CH))
    # five iterations exactly (pgmpy has not converged yet), then both run to convergence; pgmpy
    # stops at a relative change of 1e-5, so the converged estimates agree to about that
    for iters, ref, tol in ((5, ours5, 1e-10), (500, ours, 1e-4)):
        em = DiscreteEM(latent_card={INTENTION: 3}, state_names=states, init_cpds=init, max_iter=iters,
                        atol=1e-10, show_progress=False)
        cpds = em.fit(bn, data).parameters_
        assert ref.pi == pytest.approx(_cpd_values(cpds, INTENTION, ids).ravel(), abs=tol)
        for ch, L in zip(CH, ref.likes):
            assert L.T == pytest.approx(_cpd_values(cpds, ch, states[ch], ids), abs=tol)
    assert n < 500


def _reference_em(sc, rows, start: Params, prior: Params, strength: float, iters: int):
    """EM for labelled + unlabelled rows built from pgmpy's parts: exact inference (VE) on the network
    with the 'revealed' child for the E-step, pgmpy's weighted Dirichlet estimator for the M-step."""
    names = sc.intention_names
    K = len(names)
    states = {INTENTION: names, "revealed": ["no", "yes"]} | {ch: list(sc.observations.alphabets[ch]) for ch in CH}
    edges = [(INTENTION, ch) for ch in (*CH, "revealed")]
    pseudo = {INTENTION: (strength * K * prior.pi).reshape(-1, 1),
              "revealed": strength * np.vstack([1 - prior.rho, prior.rho])}
    for ch, L0 in zip(CH, prior.likes):
        pseudo[ch] = strength * L0.T
    p = start
    for _ in range(iters):
        bn = DiscreteBayesianNetwork(edges)
        cpds = [TabularCPD(INTENTION, K, p.pi.reshape(-1, 1), state_names={INTENTION: names}),
                TabularCPD("revealed", 2, np.vstack([1 - p.rho, p.rho]), evidence=[INTENTION], evidence_card=[K],
                           state_names={"revealed": ["no", "yes"], INTENTION: names})]
        for ch, L in zip(CH, p.likes):
            cpds.append(TabularCPD(ch, L.shape[1], L.T, evidence=[INTENTION], evidence_card=[K],
                                   state_names={ch: states[ch], INTENTION: names}))
        bn.add_cpds(*cpds)
        ve = VariableElimination(bn)
        data, weights = [], []
        for it, g, mv, w in rows:
            if it is not None:
                data.append((it, g, mv, w, "yes"))
                weights.append(1.0)
                continue
            q = ve.query([INTENTION], evidence={"gesture": g, "movement": mv, "keyword": w, "revealed": "no"},
                         show_progress=False)
            for n in names:
                data.append((n, g, mv, w, "no"))
                weights.append(q.get_value(**{INTENTION: n}))
        frame = pd.DataFrame(data, columns=[INTENTION, *CH, "revealed"])
        est = DiscreteBayesianEstimator(prior_type="dirichlet", pseudo_counts=pseudo, state_names=states)
        out = est.fit(DiscreteBayesianNetwork(edges), frame, sample_weight=np.array(weights)).parameters_
        rho = _cpd_values(out, "revealed", ["yes"], names).ravel()
        p = Params(_cpd_values(out, INTENTION, names).ravel(),
                   [_cpd_values(out, ch, states[ch], names).T for ch in CH], rho)
    return p


def test_mixed_em_matches_an_em_built_from_pgmpy(thesis):
    m = IntentionModel(thesis, prior_strength=3.0)
    rows = _sample_rows(thesis, 120, 3, 0.3)
    _counts(m, rows)
    ours, n = run_em(m.prior, m.labelled, m.unlabelled, m.coder.shape, m.prior, 3.0, max_iter=8, atol=0.0)
    assert n == 8
    ref = _reference_em(thesis, rows, m.prior, m.prior, 3.0, 8)
    assert ours.pi == pytest.approx(ref.pi, abs=1e-9)
    assert ours.rho == pytest.approx(ref.rho, abs=1e-9)
    for a, b in zip(ours.likes, ref.likes):
        assert a == pytest.approx(b, abs=1e-9)


def test_learning_moves_the_cpds_towards_this_user(thesis):
    # the textbook reads "dark" as 'light'; this user says "dark" for 'no_light'
    m = IntentionModel(thesis, prior_strength=10.0)
    dark = {"gesture": "none", "movement": "still", "keyword": "dark"}
    names = thesis.intention_names
    light, no_light = names.index("light"), names.index("no_light")
    kw = thesis.observations.alphabets["keyword"].index("dark")
    before = m.params.likes[2][no_light, kw]
    assert m.recognise(dark).posterior[light] > 5 * m.recognise(dark).posterior[no_light]
    for _ in range(30):
        m.learn(dark, no_light)  # clarified: 'no_light'
        m.learn({"gesture": "none", "movement": "still", "keyword": "none"}, None)  # and idle ticks
    # EM ran on the corrections, until the recognition of "dark" had turned; later labels agree
    # and are only counted, until the next EM run
    assert m.recognise(dark).intention == no_light
    assert 1 <= m.em_runs < 30 and m.labelled.sum() == 30
    assert m.params.likes[2][no_light, kw] > before + 0.1
    m.fit()
    assert m.params.likes[2][no_light, kw] > 0.6
    assert m.params.likes[2][light, kw] < thesis.observations.prior["keyword"][light][kw]


def test_agreeing_labels_are_counted_without_em(thesis):
    m = IntentionModel(thesis)
    obs = {"gesture": "point_up", "movement": "still", "keyword": "light"}
    assert m.recognise(obs).intention == 1
    assert m.learn(obs, 1) == 0 and m.em_runs == 0 and m.labelled.sum() == 1
    m.reset()
    assert m.labelled.sum() == 0 and m.params.max_diff(m.prior) == 0


# -- files ----------------------------------------------------------------------------------------

def test_save_load_round_trip(tmp_path, thesis):
    m = IntentionModel(thesis)
    for _ in range(5):
        m.learn({"gesture": "beckon", "movement": "still", "keyword": "none"}, 5)
    m.learn({"gesture": "wave", "movement": "leaving"}, None)  # a missing channel survives the file too
    m.save(tmp_path / "m.json", meta={"note": "t"})
    raw = json.loads((tmp_path / "m.json").read_text())
    assert raw["schema"] == "homeo-intention-model" and raw["version"] == 1 and raw["meta"]["note"] == "t"
    m2 = IntentionModel(thesis)
    m2.load(tmp_path / "m.json")
    assert m2.params.max_diff(m.params) < 1e-12
    assert (m2.labelled == m.labelled).all() and (m2.unlabelled == m.unlabelled).all()
    obs = {"gesture": "beckon", "movement": "still", "keyword": "none"}
    assert m2.recognise(obs) == m.recognise(obs)
    m3 = IntentionModel.from_json(thesis, m.to_json())
    assert m3.recognise(obs) == m.recognise(obs)


def test_incompatible_or_corrupt_files_are_rejected(tmp_path, thesis, thesis_raw):
    m = IntentionModel(thesis)
    path = tmp_path / "m.json"
    m.save(path)
    thesis_raw["observations"]["keyword"].append("please")
    other = scenario_from_dict(thesis_raw)
    with pytest.raises(IntentionModelError, match="incompatible scenario.*keyword differ"):
        IntentionModel(other).load(path)
    raw = json.loads(path.read_text())
    raw["cpds"]["gesture"]["light"]["point_up"] = 2.0
    (tmp_path / "bad.json").write_text(json.dumps(raw))
    with pytest.raises(IntentionModelError, match=r"P\(gesture \| light\)"):
        m.load(tmp_path / "bad.json")
    (tmp_path / "junk.json").write_text("{")
    with pytest.raises(IntentionModelError, match="not JSON"):
        m.load(tmp_path / "junk.json")
    with pytest.raises(IntentionModelError, match="not found"):
        m.load(tmp_path / "none.json")
    (tmp_path / "q.json").write_text(json.dumps({"schema": "homeo-qtable"}))
    with pytest.raises(IntentionModelError, match="not an intention-model file"):
        m.load(tmp_path / "q.json")


def test_posterior_table_keeps_the_prior_for_impossible_evidence():
    pi = np.array([0.6, 0.4])
    likes = [np.array([[1.0, 0.0], [1.0, 0.0]])] * 3  # symbol 1 impossible for both
    post = posterior_table(pi, likes)
    assert np.isfinite(post).all() and post.sum(axis=0) == pytest.approx(1.0)

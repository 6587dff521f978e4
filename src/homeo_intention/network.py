"""The Bayesian network of Section 2.3 (Fig 2.3): hidden intention -> gesture, movement, keyword.

Parameters are plain arrays: ``pi[k] = P(I = k)`` and, per channel, ``L[k, s] = P(symbol s | I = k)``.
The posterior over every observation cell is one table (``posterior_table``), recomputed when the
parameters change; recognition is then a lookup. ``to_pgmpy`` gives the same network as a pgmpy
``DiscreteBayesianNetwork``: tests check the table against pgmpy's exact inference on it.
"""

from __future__ import annotations

import warnings

import numpy as np

from homeo_decision.scenario import OBS_CHANNELS

INTENTION = "intention"  # name of the hidden node in the pgmpy network


def extended(L: np.ndarray) -> np.ndarray:
    """``L`` with one more column of ones: the likelihood of an unobserved channel."""
    return np.concatenate([L, np.ones((L.shape[0], 1))], axis=1)


def joint_table(pi: np.ndarray, likes: list[np.ndarray]) -> np.ndarray:
    """``J[k, g, m, w] = P(I=k) P(g|k) P(m|k) P(w|k)`` over extended cells (naive Bayes factorisation)."""
    Lg, Lm, Lw = (extended(L) for L in likes)
    return pi[:, None, None, None] * Lg[:, :, None, None] * Lm[:, None, :, None] * Lw[:, None, None, :]


def posterior_table(pi: np.ndarray, likes: list[np.ndarray]) -> np.ndarray:
    """``P(I | z)`` for every cell z, shape (K, n_cells): Bayes' rule on the joint, the
    distribution whose arg-max is Eq 2.10. A cell of zero evidence gets the prior."""
    J = joint_table(pi, likes).reshape(len(pi), -1)
    z = J.sum(axis=0)
    out = np.divide(J, z, out=np.repeat(pi[:, None], J.shape[1], axis=1), where=z > 0)
    return out


def to_pgmpy(intention_names, alphabets, pi, likes):
    """The network as pgmpy's DiscreteBayesianNetwork (CPDs with state names)."""
    with warnings.catch_warnings():  # pgmpy warns about its own deprecated modules on import
        warnings.simplefilter("ignore", FutureWarning)
        from pgmpy.factors.discrete import TabularCPD
        from pgmpy.models import DiscreteBayesianNetwork

    names = list(intention_names)
    bn = DiscreteBayesianNetwork([(INTENTION, ch) for ch in OBS_CHANNELS])
    cpds = [TabularCPD(INTENTION, len(names), np.asarray(pi, float).reshape(-1, 1), state_names={INTENTION: names})]
    for ch, alpha, L in zip(OBS_CHANNELS, alphabets, likes):
        cpds.append(TabularCPD(ch, len(alpha), np.asarray(L, float).T, evidence=[INTENTION], evidence_card=[len(names)],
                               state_names={ch: list(alpha), INTENTION: names}))
    bn.add_cpds(*cpds)
    bn.check_model()
    return bn


def from_pgmpy(bn, intention_names, alphabets) -> tuple[np.ndarray, list[np.ndarray]]:
    """``(pi, likes)`` of a pgmpy network in our state orders (pgmpy may reorder states)."""
    def ordered(cpd, var, states):
        names = cpd.state_names[var]
        return [names.index(s) for s in states]

    c = bn.get_cpds(INTENTION)
    pi = c.values.reshape(-1)[ordered(c, INTENTION, intention_names)]
    likes = []
    for ch, alpha in zip(OBS_CHANNELS, alphabets):
        c = bn.get_cpds(ch)
        v = c.values[ordered(c, ch, alpha)][:, ordered(c, INTENTION, intention_names)]
        likes.append(np.asarray(v, float).T)
    return np.asarray(pi, float), likes

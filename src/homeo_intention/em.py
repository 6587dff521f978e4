"""Expectation-Maximisation for the intention network over aggregated counts (Section 2.3, [45]).

Everything the robot has seen is kept as counts per observation cell: ``labelled[k, cell]``
(the user revealed intention k) and ``unlabelled[cell]``.

Whether a tick gets a label depends on the intention itself (a human who wants nothing never
clarifies anything), so the labels are not missing at random and plain EM would let the
intentions absorb the unlabelled "nothing wanted" ticks (measured: accuracy *falls* while it
learns; docs/INTENTION.md). The network therefore has a fourth child of the intention, the
observed binary ``revealed`` (a label came with this tick): rho[k] = P(revealed | I = k). Given
``revealed`` the labels are missing at random and EM is sound. Recognition happens before the
response, so ``revealed`` is unobserved then and drops out of Eq 2.10.

One EM iteration is
  E-step: for unlabelled cells, w[k, cell] = P(I = k | cell, not revealed) * unlabelled[cell],
          proportional to P(k) (1 - rho[k]) prod_channel P(s | k);
          completed counts C = labelled + w;
  M-step: P(I) proportional to sum_cell C + a_I; rho[k] = (labelled_k + a_rho) / (sum_cell C[k] + 2 a_rho)
          and P(s | k) for each channel proportional to the completed counts of (k, s) over cells
          where the channel was observed + a_channel[k, s].
With zero pseudo counts this is maximum-likelihood EM, the batch estimate pgmpy's ``DiscreteEM``
computes (pgmpy cannot mix labelled and unlabelled rows; the tests build the same iteration from
pgmpy's inference and weighted estimator and compare). With pseudo counts ``a`` it is MAP-EM with
a Dirichlet prior, i.e. pgmpy's ``DiscreteBayesianEstimator(prior_type="dirichlet")`` as M-step.
Cells with a missing channel add nothing to that channel's counts: the full EM would add
P(s | k) itself there, which moves no fixed point, only slows convergence.

The labelled part of the counts does not change during a run of EM, so it is summed once; the
E-step touches only the cells with unlabelled counts (a run's cost is O(iterations x K x cells seen)).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np



RHO0 = 0.5  # prior P(revealed | intention): no opinion


@dataclass
class Params:
    pi: np.ndarray  # P(I), shape (K,)
    likes: list  # per channel P(s | I), shape (K, S_channel)
    rho: np.ndarray | None = None  # P(revealed | I), shape (K,); None = RHO0 for every intention

    def __post_init__(self):
        if self.rho is None:
            self.rho = np.full(len(self.pi), RHO0)

    def copy(self) -> "Params":
        return Params(self.pi.copy(), [L.copy() for L in self.likes], self.rho.copy())

    def max_diff(self, other: "Params") -> float:
        d = float(np.abs(self.pi - other.pi).max())
        d = max(d, float(np.abs(self.rho - other.rho).max()))
        for a, b in zip(self.likes, other.likes):
            d = max(d, float(np.abs(a - b).max()))
        return d


def channel_sums(C: np.ndarray, shape: tuple) -> list[np.ndarray]:
    """Counts of (intention, symbol) per channel from counts over cells, shape (K, S) each
    (the "unobserved" state dropped)."""
    C = C.reshape(C.shape[0], *shape)
    return [s[:, :-1] for s in (C.sum(axis=(2, 3)), C.sum(axis=(1, 3)), C.sum(axis=(1, 2)))]


class EMData:
    """The counts of one EM run, laid out for cheap iterations.

    The parameters travel as one flat vector theta = [P(I) (K), rho (K), CPD table (S x K)], the
    table holding the three channels' P(s | k) one under the other (S = S_g + S_m + S_w rows), so
    an iteration is a few whole-array operations and convergence one max over theta.
    """

    def __init__(self, labelled: np.ndarray, unlabelled: np.ndarray, shape: tuple, prior: Params, strength: float):
        K = self.K = labelled.shape[0]
        self.sizes = [n - 1 for n in shape]
        S = self.S = sum(self.sizes)
        self.starts = np.cumsum([0] + self.sizes[:-1])
        self.lab_pi = labelled.sum(axis=1)
        self.lab_cat = np.concatenate(channel_sums(labelled, shape), axis=1).T
        self.strength = float(strength)
        self.a_pi = strength * K * prior.pi  # the prior is worth `strength` textbook observations per intention
        self.a_cat = strength * np.concatenate(prior.likes, axis=1).T
        self.a_rho = strength * prior.rho
        # with positive pseudo counts no total can be 0: skip the guarded divisions
        self.safe = strength > 0 and (prior.pi > 0).all() and (prior.rho > 0).all() and (self.a_cat > 0).all()
        cells = np.flatnonzero(unlabelled)
        self.n = unlabelled[cells][:, None]
        # row of each unlabelled cell's symbol in the table; an unobserved channel points at one of
        # three rows of ones appended below it
        self.rows = []
        onehot = np.zeros((S, len(cells)))  # symbol x cell: the cell shows that symbol
        for c, (i, size, start) in enumerate(zip(np.unravel_index(cells, shape), self.sizes, self.starts)):
            seen = i < size
            self.rows.append(np.where(seen, start + i, S + c))
            onehot[(start + i)[seen], np.flatnonzero(seen)] = 1.0
        self.onehot = onehot
        self.block = np.zeros((S, S))  # block @ x: each row's channel total, for the normalisation
        for start, size in zip(self.starts, self.sizes):
            self.block[start:start + size, start:start + size] = 1.0
        self.ext = np.ones((S + 3, K))

    def pack(self, p: Params) -> np.ndarray:
        return np.concatenate([p.pi, p.rho, np.concatenate(p.likes, axis=1).T.ravel()])

    def unpack(self, theta: np.ndarray) -> Params:
        K = self.K
        cat = theta[2 * K:].reshape(self.S, K)
        likes = [cat[a:a + n].T.copy() for a, n in zip(self.starts, self.sizes)]
        return Params(theta[:K].copy(), likes, theta[K:2 * K].copy())


def _divide(x: np.ndarray, tot: np.ndarray, old: np.ndarray, safe: bool) -> np.ndarray:
    if safe:
        return x / tot
    return np.divide(x, tot, out=np.broadcast_to(old, x.shape).copy(), where=tot > 0)  # no counts: keep old


def em_step(theta: np.ndarray, d: EMData) -> np.ndarray:
    """One E-step and M-step (module docstring); returns the new theta."""
    K, S = d.K, d.S
    pi, rho, cat = theta[:K], theta[K:2 * K], theta[2 * K:].reshape(S, K)
    new = np.empty_like(theta)
    lab_pi = d.lab_pi
    x = d.lab_cat + d.a_cat
    if d.n.size:
        # E-step: w[cell, k] = P(k | cell, not revealed) * count, P proportional to P(k)(1 - rho_k) prod P(s|k)
        ext = d.ext
        ext[:S] = cat
        J = ext[d.rows[0]]
        J *= ext[d.rows[1]]
        J *= ext[d.rows[2]]
        J *= pi * (1.0 - rho)
        z = J.sum(axis=1, keepdims=True)
        J = _divide(J, z, pi, bool(z.all()))  # a cell of zero evidence keeps the prior
        J *= d.n
        n_k = lab_pi + J.sum(axis=0)
        x += d.onehot @ J
    else:
        n_k = lab_pi
    # M-step: normalised completed counts plus pseudo counts
    y = n_k + d.a_pi
    new[:K] = _divide(y, y.sum(), pi, d.safe)
    new[K:2 * K] = _divide(lab_pi + d.a_rho, n_k + d.strength, rho, d.safe)
    new[2 * K:] = _divide(x, d.block @ x, cat, d.safe).ravel()
    return new


def run_em(start: Params, labelled: np.ndarray, unlabelled: np.ndarray, shape: tuple, prior: Params,
           strength: float, max_iter: int = 100, atol: float = 1e-6) -> tuple[Params, int]:
    """Iterate E and M steps from ``start`` until no parameter moves more than ``atol`` (or
    ``max_iter``); returns the parameters and the number of iterations run."""
    d = EMData(labelled, unlabelled, shape, prior, strength)
    theta = d.pack(start)
    n = 0
    for n in range(1, max_iter + 1):
        new = em_step(theta, d)
        moved = np.abs(new - theta).max()
        theta = new
        if moved <= atol:
            break
    return d.unpack(theta), n

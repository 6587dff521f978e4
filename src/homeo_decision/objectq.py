"""Object Q-learning over reduced states (Eq 3.10-3.17, 3.23).

Each object o (and the ``null`` object) has its own table Q^o over its reduced state
s_o = m_dom x S_hum x S_o (Eq 3.11, 3.13) and its own actions A_o. A reduced state is an
integer: ``(m_dom * n_hum + hum) * n_states_o + object_state``.
"""

from __future__ import annotations

import math
from bisect import bisect_right
from itertools import accumulate
from dataclasses import dataclass
from typing import Sequence

from .numeric import left_sum
from .scenario import Scenario


@dataclass(frozen=True)
class Phase:
    start: int
    alpha: float
    tau: float


def schedule_from(learning: dict) -> tuple[Phase, ...]:
    """The alpha/tau schedule (Section 4.2.1: 0.3/4.0, then 0.1/2.0 from iteration 1000)."""
    return tuple(Phase(int(s["from"]), float(s["alpha"]), float(s["tau"])) for s in learning["schedule"])


def phase_at(schedule: Sequence[Phase], t: int) -> Phase:
    cur = schedule[0]
    for ph in schedule:
        if t >= ph.start:
            cur = ph
    return cur


def softmax_probs(values: Sequence[float], tau: float) -> list[float]:
    """Eq 3.17: P(a) = exp(Q(a)/tau) / sum exp(Q/tau), shifted by the max against overflow."""
    top = max(values)
    ex = [math.exp((v - top) / tau) for v in values]
    z = left_sum(ex)
    return [e / z for e in ex]


def softmax_pick(values: Sequence[float], actions: Sequence[int], tau: float, u: float) -> int:
    """Eq 3.17 sampling: the action whose cumulative softmax weight first exceeds ``u`` in [0, 1).

    Shifting every value by the maximum leaves the probabilities unchanged and avoids overflow.
    The cumulative weights are summed left to right (``accumulate``), as a loop would.
    """
    top = max(values)
    exp = math.exp
    cum = list(accumulate([exp((v - top) / tau) for v in values]))
    i = bisect_right(cum, u * cum[-1])
    return actions[i] if i < len(actions) else actions[-1]


class ObjectQ:
    """The Q-tables of all objects and the Object Q-learning rules."""

    def __init__(self, sc: Scenario, initial_q: float | None = None):
        c = sc.c
        self.sc = sc
        self.initial_q = float(sc.open.initial_q if initial_q is None else initial_q)
        self.n_obj = len(sc.object_names)
        self.n_motiv = len(sc.internal_states)  # m_dom's values (Eq 3.6)
        self.n_hum = c.n_hum
        self.n_os = [len(lbl) for lbl in c.obj_state_labels]
        self.stride = [self.n_hum * n for n in self.n_os]
        self.act_obj = c.act_obj
        self.act_local = c.act_local
        # base[code][o] = hum * n_os[o] + os[o]; add m_dom * stride[o] for the reduced state
        self.base = [tuple(c.hum[code] * self.n_os[o] + c.obj_state[code][o] for o in range(self.n_obj)) for code in range(sc.n_codes)]
        self.valid_local = c.valid_local
        # per world code: (object, local index) of each valid action, in order (the softmax's hot path)
        self._valid_pairs = [tuple((c.act_obj[a], c.act_local[a]) for a in v) for v in c.valid]
        self._valid = c.valid
        self.max_over_valid = sc.open.value_max_over == "valid"
        self.others = tuple(tuple(m for m in range(self.n_obj) if m != o) for o in range(self.n_obj))
        # every reduced-state tuple, precomputed: states() is on the per-tick path
        self._states = [[tuple(m * self.stride[o] + b[o] for o in range(self.n_obj)) for b in self.base]
                        for m in range(self.n_motiv)]
        self.reset()

    def reset(self) -> None:
        q0 = self.initial_q
        acts = self.sc.c.obj_actions
        self.q = [[[q0] * len(acts[o]) for _ in range(self.n_motiv * self.stride[o])] for o in range(self.n_obj)]

    # -- states --------------------------------------------------------------
    def states(self, m_dom: int, code: int) -> tuple[int, ...]:
        """Eq 3.11-3.12: the reduced state of every object for this m_dom and world,
        ``(m_dom * n_hum + hum) * n_states_o + object_state``."""
        return self._states[m_dom][code]

    def value(self, action: int, states: Sequence[int]) -> float:
        o = self.act_obj[action]
        return self.q[o][states[o]][self.act_local[action]]

    # -- selection (Eq 3.17) --------------------------------------------------
    def probabilities(self, states: Sequence[int], valid: Sequence[int], tau: float) -> list[float]:
        """Eq 3.17: softmax over the valid actions of all objects, each in its own reduced state."""
        q, ao, al = self.q, self.act_obj, self.act_local
        return softmax_probs([q[ao[a]][states[ao[a]]][al[a]] for a in valid], tau)

    def select(self, states: Sequence[int], valid: Sequence[int], tau: float, u: float) -> int:
        """Draw an action from Eq 3.17 with the uniform ``u`` in [0, 1)."""
        q, ao, al = self.q, self.act_obj, self.act_local
        return softmax_pick([q[ao[a]][states[ao[a]]][al[a]] for a in valid], valid, tau, u)

    def select_in(self, states: Sequence[int], code: int, tau: float, u: float) -> int:
        """``select`` over the valid actions of world ``code`` (Table 3.3), from precomputed indices."""
        q = self.q
        return softmax_pick([q[o][states[o]][j] for o, j in self._valid_pairs[code]], self._valid[code], tau, u)

    # -- learning (Eq 3.14-3.16, 3.23) ---------------------------------------
    def _max(self, o: int, s: int, code: int) -> float:
        row = self.q[o][s]
        if self.max_over_valid:
            loc = self.valid_local[code][o]
            if loc:
                return max(row[j] for j in loc)
        return max(row)

    def collateral_value(self, o_i: int, s: Sequence[int], s2: Sequence[int], code: int, code2: int) -> float:
        """Eq 3.15-3.16: V^{o_i}(s, s') = max_a Q^{o_i}(s', a) + sum_{m != i} dQmax^{o_m}(s, s')."""
        if self.max_over_valid:
            mx = self._max
            v = mx(o_i, s2[o_i], code2)
            for m in self.others[o_i]:
                v += mx(m, s2[m], code2) - mx(m, s[m], code)
            return v
        q = self.q
        v = max(q[o_i][s2[o_i]])
        for m in self.others[o_i]:
            sm, sm2 = s[m], s2[m]
            if sm != sm2:  # an object whose reduced state did not change adds exactly 0
                qm = q[m]
                v += max(qm[sm2]) - max(qm[sm])
        return v

    def update(self, action: int, s: Sequence[int], r: float, s2: Sequence[int], alpha: float, gamma: float, code: int, code2: int) -> float:
        """Eq 3.14: Q^{o_i}(s, a) <- (1 - alpha) Q^{o_i}(s, a) + alpha (r + gamma V^{o_i}(s, s')). Returns the new value."""
        o = self.act_obj[action]
        row = self.q[o][s[o]]
        j = self.act_local[action]
        target = r + gamma * self.collateral_value(o, s, s2, code, code2)
        row[j] = (1.0 - alpha) * row[j] + alpha * target
        return row[j]

    def pseudo_update(self, proposal: int, s: Sequence[int], r_drives: float, f: float, s_dag: Sequence[int], alpha: float, gamma: float, code: int) -> float:
        """Eq 3.23: Q^{o_j}(s, a+) <- (1 - alpha) Q + alpha (r+_drives + f + gamma V^{o_j}(s, s+))."""
        return self.update(proposal, s, r_drives + f, s_dag, alpha, gamma, code, code)

"""Baseline decision makers to compare Object Q-learning with (docs/EXPERIMENTS.md).

Every policy offers DecisionCore's interface, so the runner drives them all alike:

    perceive(drives, code) -> Percept
    select(p, t) -> action id
    learn(p, action, after, feedback, proposal, p_next, t) -> Learned

and a ``q`` attribute only when it keeps a Q-table. The policies:

``RandomPolicy``
    a uniformly random valid action (Table 3.3 constraints), from the ``policy`` stream.
``RulePolicy``
    fixed-priority threshold rules, the usual behaviour-tree answer, written as data in the
    scenario's ``rule_policy`` block (the thesis scenario's: charge when the battery need
    reaches its threshold and keep charging down to a low mark, else serve the expressed
    intention with the action the user wants, else rest, else socialise, else idle). It
    knows the intention -> action mapping (a programmer wrote it down) and never learns.
``FlatQ``
    standard Q-learning (Eq 2.9) over the full Cartesian state of Eq 3.5/3.8,
    m_dom x S_hum x prod_o S_o, with no state reduction and no collateral term; the same
    reward (Eq 3.18-3.22, DoD weights and motivation factor), softmax (Eq 3.17) and
    alpha/tau schedule as Object-Q; no proposals (no pseudo update).

The purely homeostatic robot of the earlier works is ``DecisionCore(..., feedback=False)``
(no feedback reward, no proposals); ``make_policy`` builds any of them by name.

Every percept still carries the intensities and the dominant motivation (Eq 3.2-3.3), and
``learn`` returns the reward of Eq 3.18 for the trace, even for policies that ignore it.
"""

from __future__ import annotations

from typing import Sequence

from homeo_msgs_py.learning import DOD, GAMMA, XI

from .agent import DecisionCore, Learned, Perceiving, Percept
from .motivation import dod_weights
from .objectq import phase_at, schedule_from, softmax_pick, softmax_probs
from .reward import reward
from .rng import UniformStream
from .scenario import NULL_OBJECT, RuleSpec, Scenario, holds

POLICIES = ("objectq", "random", "rule", "flatq", "nofeedback")


class _Perceiving(Perceiving):
    """Shared settings and the trace reward (Eq 3.18) for baselines."""

    def __init__(self, sc: Scenario, seed: int, dod: float | None, xi: float | None):
        L = sc.learning
        self.sc = sc
        self._init_perception(sc)
        self.serving = sc.serving
        self.dod = float(L[DOD.name] if dod is None else dod)
        self.xi = float(L[XI.name] if xi is None else xi)
        self.weights = dod_weights(self.dod, len(sc.drives), sc.serving)
        self.f = sc.feedback_value
        self.pseudo_update = False
        self.reseed(seed)

    def reseed(self, seed: int) -> None:
        self.seed = int(seed)
        self.rng = UniformStream(self.seed, "policy")

    def learn(self, p: Percept, action: int, after: Sequence[float], feedback: int, proposal: int | None,
              p_next: Percept, t: int) -> Learned:
        return Learned(reward(p.drives, after, self.weights, self.bonus_drive(p), self.xi, feedback, self.f), None)


class RandomPolicy(_Perceiving):
    """A uniformly random valid action."""

    def __init__(self, sc: Scenario, seed: int = 0, *, dod: float | None = None, xi: float | None = None):
        super().__init__(sc, seed, dod, xi)

    def select(self, p: Percept, t: int) -> int:
        valid = self.valid[p.code]
        return valid[self.rng.index(len(valid))]


class RulePolicy(_Perceiving):
    """Fixed-priority rules read from the scenario's ``rule_policy`` block (a behaviour-tree selector).

    Rules are tried in order (``homeo_decision.scenario.rule_policy`` documents the block). A rule
    fires when its drive is at or above its ``at`` (by default the drive's activation threshold,
    Table 3.1: the rule acts on a need exactly when the homeostatic robot's motivation for it
    would be active), or while its hysteresis condition holds, and its world condition holds. A
    ``serve`` rule picks the first valid desired action of the expressed intention; any other
    the first valid candidate whose condition holds. A rule that picks nothing falls through;
    when no rule picks, the first valid action.
    """

    def __init__(self, sc: Scenario, seed: int = 0, *, dod: float | None = None, xi: float | None = None):
        super().__init__(sc, seed, dod, xi)
        if sc.rule_policy is None:
            raise ValueError(f"--policy rule: scenario {sc.source} has no 'rule_policy' block (docs/EXPERIMENTS.md)")
        self.rules = sc.rule_policy
        c = sc.c
        self.desired = [tuple(c.action_ids[a] for a in it.desired) for it in sc.intentions]
        self.views = c.views
        self.intention_of = c.intention_of

    def _fires(self, rule: RuleSpec, d: Sequence[float], view: dict) -> bool:
        if rule.when and not holds(rule.when, view):
            return False
        if rule.drive is None:
            return True
        x = d[rule.drive]
        if x >= rule.at:
            return True
        # hysteresis: keep going (e.g. keep charging) while the world is so and the drive above a low mark
        return rule.keep_when is not None and x > rule.keep_above and holds(rule.keep_when, view)

    def select(self, p: Percept, t: int) -> int:
        view = self.views[p.code]
        valid = self.valid[p.code]
        for rule in self.rules:
            if not self._fires(rule, p.drives, view):
                continue
            if rule.serve:
                it = self.intention_of[p.code]
                for act in self.desired[it - 1] if it else ():
                    if act in valid:
                        return act
                continue
            for cand in rule.candidates:
                if cand.action in valid and (not cand.when or holds(cand.when, view)):
                    return cand.action
        return valid[0]


class FlatQ(_Perceiving):
    """Standard Q-learning (Eq 2.9) over the full Cartesian state m_dom x S_hum x prod_o S_o.

    ``q[s][a]`` over all actions of the scenario; the softmax (Eq 3.17) runs over the
    valid ones; V(s') = max_a' Q(s', a') over all actions (or the valid ones, following the
    scenario's open choice ``value_max_over``, as Object-Q does).
    """

    def __init__(self, sc: Scenario, seed: int = 0, *, dod: float | None = None, xi: float | None = None,
                 gamma: float | None = None, feedback_value: float | None = None):
        super().__init__(sc, seed, dod, xi)
        c = sc.c
        self.gamma = float(sc.learning[GAMMA.name] if gamma is None else gamma)
        if feedback_value is not None:
            self.f = float(feedback_value)
        self.schedule = schedule_from(sc.learning)
        self.initial_q = float(sc.open.initial_q)
        objs = [k for k, o in enumerate(sc.object_names) if o != NULL_OBJECT]
        n_os = [len(c.obj_state_labels[k]) for k in objs]
        n_ext = 1
        for n in n_os:
            n_ext *= n
        self.n_ext = c.n_hum * n_ext  # |S_hum x prod_o S_o|
        self.n_states = len(sc.internal_states) * self.n_ext
        self.n_actions = len(sc.actions)
        base = []
        for code in range(sc.n_codes):
            s = c.hum[code]
            for k, n in zip(objs, n_os):
                s = s * n + c.obj_state[code][k]
            base.append(s)
        self.base = base
        self.max_over_valid = sc.open.value_max_over == "valid"
        self.reset()

    def reset(self) -> None:
        self.q = [[self.initial_q] * self.n_actions for _ in range(self.n_states)]

    def _states(self, m_dom: int, code: int) -> tuple:
        return (m_dom * self.n_ext + self.base[code],)

    def probabilities(self, p: Percept, t: int) -> list[float]:
        tau = phase_at(self.schedule, t).tau
        row = self.q[p.states[0]]
        return softmax_probs([row[a] for a in self.valid[p.code]], tau)

    def select(self, p: Percept, t: int) -> int:
        tau = phase_at(self.schedule, t).tau
        row = self.q[p.states[0]]
        valid = self.valid[p.code]
        return softmax_pick([row[a] for a in valid], valid, tau, self.rng.random())

    def value(self, s: int, code: int) -> float:
        row = self.q[s]
        if self.max_over_valid:
            return max(row[a] for a in self.valid[code])
        return max(row)

    def learn(self, p: Percept, action: int, after: Sequence[float], feedback: int, proposal: int | None,
              p_next: Percept, t: int) -> Learned:
        """Eq 2.9: Q(s, a) <- (1 - alpha) Q(s, a) + alpha (r + gamma max_a' Q(s', a'))."""
        alpha = phase_at(self.schedule, t).alpha
        r = reward(p.drives, after, self.weights, self.bonus_drive(p), self.xi, feedback, self.f)
        row = self.q[p.states[0]]
        row[action] = (1.0 - alpha) * row[action] + alpha * (r + self.gamma * self.value(p_next.states[0], p_next.code))
        return Learned(r, None)


def make_policy(name: str, sc: Scenario, seed: int = 0, *, dod: float | None = None, xi: float | None = None,
                pseudo_update: bool | None = None):
    """A decision maker by name (one of ``POLICIES``)."""
    if name == "objectq":
        return DecisionCore(sc, seed, dod=dod, xi=xi, pseudo_update=pseudo_update)
    if name == "nofeedback":
        return DecisionCore(sc, seed, dod=dod, xi=xi, pseudo_update=pseudo_update, feedback=False)
    if name == "random":
        return RandomPolicy(sc, seed, dod=dod, xi=xi)
    if name == "rule":
        return RulePolicy(sc, seed, dod=dod, xi=xi)
    if name == "flatq":
        return FlatQ(sc, seed, dod=dod, xi=xi)
    raise ValueError(f"unknown policy {name!r}; known: {', '.join(POLICIES)}")

"""The decision maker of Algorithm 1: softmax choice (Eq 3.17) and Object-Q learning (Eq 3.14, 3.23).

A policy turns a perception (world code, drives, intensities, m_dom: ``homeo_decision.robot``'s
``Perception`` computes them once per tick) into a :class:`Percept` with its own states, selects
an action, and learns from the outcome. ``DecisionCore`` is the thesis's Object-Q robot; the
baselines (``homeo_decision.baselines``) offer the same interface.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

from homeo_msgs_py.learning import DOD, LEARNING, check_learning

from .motivation import dod_weights, motivational_state
from .objectq import ObjectQ, phase_at, schedule_from
from .reward import drive_reward, pseudo_drives, reward
from .rng import UniformStream
from .scenario import Scenario


@dataclass(slots=True)
class Percept:
    """What the robot knows at decision time (the state s of Algorithm 1)."""

    code: int  # perceived world (recognised intention, relation, object states)
    drives: tuple  # drive values
    intensities: list  # Eq 3.2
    m_dom: int  # Eq 3.3
    states: tuple  # reduced state per object, Eq 3.11


@dataclass(slots=True)
class Learned:
    reward: float
    pseudo_reward: float | None  # r+_drives + f of Eq 3.23 when a pseudo update ran


class Perceiving:
    """What every policy shares: Eq 3.2-3.3 for a standalone ``perceive`` and the percept of a
    perception computed elsewhere; a policy adds its own states (``_states``)."""

    def _init_perception(self, sc: Scenario) -> None:
        self.thresholds = sc.activation_thresholds  # Eq 3.2 (open choice activation_boundary)
        self.tie_break = sc.open.tie_break
        self.none_state = sc.none_state
        self.stim = sc.c.stim
        self.valid = sc.c.valid
        self.bonus_activated = sc.open.motivation_bonus == "activated"

    def bonus_drive(self, p: Percept) -> int:
        """Eq 3.21's k: the drive of m_dom; under the open choice motivation_bonus = activated, none (-1)
        while m_dom is not activated (Definition 6: its intensity is 0)."""
        m = p.m_dom
        return m if not self.bonus_activated or (m < len(p.intensities) and p.intensities[m] > 0.0) else -1

    def _states(self, m_dom: int, code: int) -> tuple:
        return ()

    def percept(self, code: int, drives: Sequence[float], inten: list, m_dom: int) -> Percept:
        """The Percept of a perception made by ``robot.Perception`` (or the drives node)."""
        return Percept(code, drives, inten, m_dom, self._states(m_dom, code))

    def perceive(self, drives: Sequence[float], code: int) -> Percept:
        """Algorithm 1 lines 2-10 on their own: stimuli, intensities (Eq 3.2), m_dom (Eq 3.3), states."""
        inten, m = motivational_state(drives, self.thresholds, self.stim[code], self.tie_break, self.none_state)
        return Percept(code, tuple(drives), inten, m, self._states(m, code))


class DecisionCore(Perceiving):
    """Object Q-learning with motivation factor, DoD weights and pseudo updates."""

    def __init__(self, sc: Scenario, seed: int = 0, *, dod: float | None = None, xi: float | None = None,
                 gamma: float | None = None, pseudo_update: bool | None = None, feedback_value: float | None = None,
                 feedback: bool | None = None):
        self.sc = sc
        self._init_perception(sc)
        self.schedule = schedule_from(sc.learning)
        self.q = ObjectQ(sc)
        self.serving = sc.serving
        self.praise = sc.praise_change
        given = dict(dod=dod, xi=xi, gamma=gamma, pseudo_update=pseudo_update, feedback=feedback)
        # the scenario's learning block (its defaults filled from the declaration), then what is given
        self.set_params(**{s.name: sc.learning[s.name] if given[s.name] is None else given[s.name] for s in LEARNING},
                        feedback_value=sc.feedback_value if feedback_value is None else feedback_value)
        self._phase_from, self._phase_until, self._phase = 0, -1, self.schedule[0]  # empty: computed at first use
        # ticks learned before this run (a robot that resumes from a checkpoint): the schedule of
        # tick t is the scenario's at t + tick_offset, so it goes on rather than starting again
        self.tick_offset = 0
        self.reseed(seed)

    def set_params(self, *, feedback_value=None, **params) -> None:
        """Change tunables between ticks (the node's live parameters): the learning parameters by
        their declared names (``homeo_msgs_py.learning``; None: unchanged) and the feedback value f.
        All are checked before any changes, so a refused call (ValueError, one line) leaves the core
        as it was."""
        new = check_learning({k: v for k, v in params.items() if v is not None})
        if feedback_value is not None and not feedback_value >= 0:
            raise ValueError(f"feedback value must be >= 0, got {feedback_value}")
        if DOD.name in new:
            self.weights = dod_weights(new[DOD.name], len(self.sc.drives), self.serving)
        for name, value in new.items():  # the attributes bear the declared names
            setattr(self, name, value)
        if feedback_value is not None:
            self.f = float(feedback_value)

    def params(self) -> dict:
        """The learning parameters in force, by name, in the declaration's order."""
        return {s.name: getattr(self, s.name) for s in LEARNING}

    def phase(self, t: int):
        """The alpha/tau phase of tick t, cached over the ticks it spans (learning asks for t-1 and
        selection for t, every tick)."""
        t += self.tick_offset
        if not self._phase_from <= t < self._phase_until:
            ph = self._phase = phase_at(self.schedule, t)
            later = [p.start for p in self.schedule if p.start > ph.start]
            self._phase_from = ph.start if t >= ph.start else t  # before the first phase: that tick only
            self._phase_until = min(later) if later else float("inf")
        return self._phase

    def set_tick_offset(self, offset: int) -> None:
        if offset < 0:
            raise ValueError(f"tick offset must be >= 0, got {offset}")
        self.tick_offset = int(offset)
        self._phase_from, self._phase_until = 0, -1  # the cached phase is of other ticks

    def reseed(self, seed: int) -> None:
        self.seed = int(seed)
        self.rng = UniformStream(self.seed, "decision")

    def reset(self, seed: int | None = None) -> None:
        self.q.reset()
        self.reseed(self.seed if seed is None else seed)

    # -- Algorithm 1 -----------------------------------------------------------
    def _states(self, m_dom: int, code: int) -> tuple:
        """Eq 3.11: the reduced state of every object."""
        return self.q.states(m_dom, code)

    def percept(self, code: int, drives: Sequence[float], inten: list, m_dom: int) -> Percept:
        # Perceiving.percept with the reduced states looked up directly: once per tick
        return Percept(code, drives, inten, m_dom, self.q._states[m_dom][code])

    def select(self, p: Percept, t: int) -> int:
        """Lines 11-17: softmax (Eq 3.17) over the valid actions, at the temperature of tick t."""
        tau = self.phase(t).tau
        return self.q.select_in(p.states, p.code, tau, self.rng.random())

    def learn(self, p: Percept, action: int, after: Sequence[float], feedback: int, proposal: int | None,
              p_next: Percept, t: int) -> Learned:
        """Lines 19-24: the Object-Q update (Eq 3.14) and, for a proposal, the pseudo update (Eq 3.23)."""
        alpha = self.phase(t).alpha
        fb = feedback if self.feedback else 0
        k = self.bonus_drive(p)
        r = reward(p.drives, after, self.weights, k, self.xi, fb, self.f)
        self.q.update(action, p.states, r, p_next.states, alpha, self.gamma, p.code, p_next.code)
        r_dag = None
        if self.pseudo_update and self.feedback and proposal is not None and proposal != action:
            o = self.sc.open
            d_dag = pseudo_drives(p.drives, self.serving, self.praise if o.pseudo_serving == "praise" else -100.0)
            r_dag = drive_reward(p.drives, d_dag, self.weights, k if o.pseudo_reward == "eq_3_20" else -1, self.xi)
            # s+ differs from s only in m_dom, from the pseudo drives and unchanged stimuli
            m_dag = motivational_state(d_dag, self.thresholds, self.stim[p.code], self.tie_break, self.none_state)[1]
            s_dag = self.q.states(m_dag, p.code)
            self.q.pseudo_update(proposal, p.states, r_dag, self.f, s_dag, alpha, self.gamma, p.code)
            r_dag += self.f
        return Learned(r, r_dag)

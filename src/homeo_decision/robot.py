"""One robot: recognition, perception and decision, stepped once per tick (Algorithm 1).

The robot has three parts, each also hosted alone by one node of the graph:

- recognition (the intention node): learns from the previous tick's answer, then recognises the
  human's intention (Section 2.3; ``homeo_intention``), or reads it (``OracleRecognition``: the
  thesis's own simulation observes it);
- :class:`Perception` (the drives node): the internal drives across ticks (Table 4.1 effects,
  feedback, Table 4.2 growth), the body drives of this tick, the stimuli of the perceived world,
  the intensities (Eq 3.2) and the dominant motivation (Eq 3.3);
- :class:`Decision` (the decision node): learns from the previous tick (Eq 3.14 and the pseudo
  update Eq 3.23, s' = this tick's percept), then selects this tick's action (Eq 3.17).

Tick t takes the observation of t and the outcome of t-1; at the run's end a *final* tick learns
from the last outcome without choosing. :func:`run_loop` drives a robot in an environment; the
in-process runner, the field test and (split across nodes) the graph all follow it.
"""

from __future__ import annotations

from typing import Callable, Protocol

from .agent import Learned, Percept
from .drives import DriveModel
from .environment import Environment, Observation, Outcome
from .motivation import motivational_state
from .scenario import Scenario


class Recognised(Protocol):
    intention: int  # index into Scenario.intention_names (0 = none)


class Recognition(Protocol):
    """The intention node's part: ``tick(observation, last outcome) -> Recognised``."""

    def tick(self, obs: Observation, out: Outcome | None) -> Recognised: ...

    def restart(self) -> None: ...


class OracleRecognition:
    """The thesis's simulation (Section 4.2.1): the robot observes the human's intention."""

    learns = False

    class _Seen:
        __slots__ = ("intention", "posterior", "confidence")

        def __init__(self, intention: int, n: int):
            self.intention = intention
            self.posterior = [1.0 if i == intention else 0.0 for i in range(n)]
            self.confidence = 1.0

    def __init__(self, sc: Scenario):
        n = len(sc.intention_names)
        self._seen = [self._Seen(i, n) for i in range(n)]  # one record per intention, shared

    def check(self, obs: Observation) -> None:
        """The node's input check, before an observation is taken into a tick."""
        if obs.intention is None:
            raise ValueError("oracle mode needs the intention in the observation")

    def tick(self, obs: Observation, out: Outcome | None):
        return self._seen[obs.intention]

    def restart(self) -> None:
        pass


class Perception:
    """The robot's drives and motivational state, tick by tick (the drives node's part)."""

    def __init__(self, sc: Scenario):
        self.sc = sc
        self.thresholds = sc.activation_thresholds  # Eq 3.2 (open choice activation_boundary)
        self.tie_break = sc.open.tie_break
        self.none_state = sc.none_state
        self.stim = sc.c.stim
        self.with_intention = sc.c.with_intention
        # the drives right after the action are needed by these two open choices only
        self.keep_after = sc.open.reward_span == "action" or sc.open.metrics_sample == "after_action"
        self.time_first = sc.open.time_increase == "before_action"
        self.restart()

    def restart(self, initial=None) -> None:
        """A new episode: drives from the scenario's initial values (or ``initial``)."""
        self.model = DriveModel(self.sc)
        if initial is not None:  # internal drives (body drives come with the first reading)
            self.model.reset(initial)
        self.prev_code: int | None = None
        self.prev_intention = 0
        self.after_action: tuple | None = None
        self.drives: tuple = tuple(self.model.values)

    def tick(self, code: int, recognised: int, body, out: Outcome | None) -> tuple:
        """Tick t: apply what tick t-1 did, read the body, perceive the world ``code`` seen with the
        ``recognised`` intention. Returns ``(perceived code, drives, intensities, m_dom)``."""
        m = self.model
        if out is not None and self.prev_code is not None:
            fb = out.feedback
            # Table 4.2; whether the serving drive grows follows the open choice serving_growth, from
            # what the robot itself can tell: an intention was pending if it recognised one or the
            # human reacted; it was satisfied if the human praised the action. The other drives'
            # growth: drive_growth, from the world the action was taken in
            still = m.still(self.prev_code, out.action) if m.growth_when else ()
            if self.time_first:  # open choice time_increase: the time increase before the action
                m.apply_time(self.prev_intention != 0 or fb != 0, fb > 0, still)
            if out.action is not None:
                m.apply_action(self.prev_code, out.action)  # Table 4.1, in the world the robot perceived
            if fb:
                m.apply_feedback(fb)  # Section 4.2.1: praise -10, a scolding by an open amount
            if self.keep_after:
                if out.body is not None:
                    m.set_body(out.body)
                self.after_action = tuple(m.values)
            if not self.time_first:
                m.apply_time(self.prev_intention != 0 or fb != 0, fb > 0, still)
        m.set_body(body)
        code = self.with_intention[code][recognised]
        drives = self.drives = tuple(m.values)
        inten, m_dom = motivational_state(drives, self.thresholds, self.stim[code], self.tie_break,
                                         self.none_state)
        self.prev_code, self.prev_intention = code, recognised
        return code, drives, inten, m_dom


class Decision:
    """Learn from the previous tick, then choose (the decision node's part)."""

    def __init__(self, policy):
        self.policy = policy
        self.span_action = policy.sc.open.reward_span == "action"
        self.prev: Percept | None = None
        self.learned: Learned | None = None  # what the last learning step computed (for traces)

    def restart(self) -> None:
        """A new episode of the world: forget the pending transition (the Q-table stays)."""
        self.prev = None

    def tick(self, t: int, perceived: tuple, out: Outcome | None, after_action: tuple | None,
             final: bool = False) -> int | None:
        code, drives, inten, m_dom = perceived
        pol = self.policy
        p = pol.percept(code, drives, inten, m_dom)
        self.learned = None
        if self.prev is not None and out is not None and out.action is not None:
            after = after_action if self.span_action and after_action is not None else drives
            self.learned = pol.learn(self.prev, out.action, after, out.feedback, out.proposal, p, t - 1)
        if final:
            self.prev = None
            return None
        self.prev = p
        return pol.select(p, t)


class Robot:
    """Recognition, perception and decision as one object; ``step`` is one tick of Algorithm 1."""

    def __init__(self, sc: Scenario, policy, recognition: Recognition):
        self.sc = sc
        self.recognition = recognition
        self.perception = Perception(sc)
        self.decision = Decision(policy)
        self.policy = policy
        self.recognised = None  # the recognition of the current tick
        # the oracle's recognition is a lookup of the observed intention: done here, per tick
        self._seen = recognition._seen if type(recognition) is OracleRecognition else None

    def restart(self, initial=None) -> None:
        self.recognition.restart()
        self.perception.restart(initial)
        self.decision.restart()

    def step(self, t: int, obs: Observation, out: Outcome | None, final: bool = False) -> int | None:
        seen = self._seen
        r = self.recognised = seen[obs.intention] if seen is not None else self.recognition.tick(obs, out)
        per = self.perception
        perceived = per.tick(obs.code, r.intention, obs.body, out)
        return self.decision.tick(t, perceived, out, per.after_action, final)

    @property
    def percept(self) -> Percept | None:
        """The percept the last action was chosen in (None after a final tick)."""
        return self.decision.prev


TickHook = Callable[[int, Percept, Recognised, int, Outcome], None]


def run_loop(env: Environment, robot: Robot, iterations: int, obs: Observation | None = None,
             on_tick: TickHook | None = None, t0: int = 0, done: Callable[[], bool] | None = None) -> None:
    """Drive ``robot`` in ``env`` for ``iterations`` ticks, then one final (learning) tick.

    ``on_tick(t, percept, recognised, action, outcome)`` runs once the robot has taken in tick t's
    outcome (after the step of t+1, or the final one), so ``robot.perception`` then holds the drives
    after tick t: what the metrics of Section 4.1 record. ``t0`` offsets the tick count (the
    learning schedule of a robot that continues). ``done()``: the environment has no more to give
    (a scripted user is done); checked after each step, it makes the next tick the final one."""
    if obs is None:
        obs = env.observe()
    end = t0 + iterations
    step, env_step, observe = robot.step, env.step, env.observe
    if done is not None and done():
        end = t0
    a = step(t0, obs, None, end == t0)
    dec = robot.decision
    for t in range(t0, end):
        p, r = dec.prev, robot.recognised
        out = env_step(a)
        last = t + 1 == end or (done is not None and done())
        a_next = step(t + 1, observe(), out, last)
        if on_tick is not None:
            on_tick(t, p, r, a, out)
        if last:
            return
        a = a_next

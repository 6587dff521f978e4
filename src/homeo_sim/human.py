"""The simulated human (Algorithm 2, Table 4.3) with the open choices as settings.

Algorithm 2 line 9 reads "intention != null" where the text means "== null": no
intention, no feedback. Settings the thesis leaves open (scenario ``open``):
``human_no_intention_prob`` (a new draw is "no intention"), ``human_leave_prob`` /
``human_return_prob`` (presence), ``human_proposal_choice`` and ``human_proposal_prob``.

For intention recognition (Section 2.3, docs/INTENTION.md) the human also shows what it
wants: ``observe`` emits a gesture, a movement and a spoken keyword drawn from its personal
habits (the scenario's ``observations.habits``, not the network's textbook prior), each
replaced by uniform noise with probability ``<channel>_noise``. These draws use their own
"observation" stream, so the "human" stream, and with it every oracle-mode result, does
not depend on them. ``intention_reveal`` says which responses reveal the true intention
(``Outcome.clarified``).
"""

from __future__ import annotations

from homeo_decision.environment import Outcome
from homeo_decision.rng import UniformStream
from homeo_decision.scenario import OBS_CHANNELS, Scenario, ScenarioError


class SimHuman:
    def __init__(self, sc: Scenario, seed: int = 0):
        self.sc = sc
        o = sc.open
        self.p_none = o.human_no_intention_prob
        self.p_leave = o.human_leave_prob
        self.p_return = o.human_return_prob
        self.p_propose = o.human_proposal_prob
        self.proposal_choice = o.human_proposal_choice  # which desired action a proposal names
        self.desired = sc.c.desired
        self.desired_order = [()] + [tuple(sc.c.action_ids[a] for a in it.desired) for it in sc.intentions]
        self.reasonable = sc.c.reasonable
        self.with_presence = sc.c.with_presence
        self.reveal = o.intention_reveal
        self._habits = _habit_tables(sc)
        self.reset(seed)

    def reset(self, seed: int | None = None) -> None:
        if seed is not None:
            self.seed = int(seed)
        self.rng = UniformStream(self.seed, "human")
        self.obs_rng = UniformStream(self.seed, "observation")
        self.intention = 0  # Algorithm 2 line 1: intention = null
        self.present = True
        self.satisfied = False

    def state(self) -> dict:
        """What the human is and where its two streams stand, as JSON-able data (a checkpoint)."""
        return {"seed": self.seed, "intention": self.intention, "present": self.present, "satisfied": self.satisfied,
                "rng": self.rng.state(), "obs_rng": self.obs_rng.state()}

    def set_state(self, st) -> None:
        """Go on from ``state()``: the same draws follow as had it never stopped. Raises ValueError
        (one line) for anything else, changing nothing."""
        if not isinstance(st, dict):
            raise ValueError("not a human state")
        seed, it = st.get("seed"), st.get("intention")
        if type(seed) is not int or not 0 <= seed <= 2**31 - 1:
            raise ValueError(f"human seed must be an integer in 0..2^31-1, got {seed!r}")
        if type(it) is not int or not 0 <= it < len(self.sc.intention_names):
            raise ValueError(f"human intention must be an index of the scenario's intentions, got {it!r}")
        if type(st.get("present")) is not bool or type(st.get("satisfied")) is not bool:
            raise ValueError("human present and satisfied must be true or false")
        rng, obs = stream_from(seed, "human", st.get("rng")), stream_from(seed, "observation", st.get("obs_rng"))
        self.seed, self.intention, self.present, self.satisfied = seed, it, st["present"], st["satisfied"]
        self.rng, self.obs_rng = rng, obs

    def advance(self, code: int) -> None:
        """Lines 3-6 (and presence): decide what the human wants in the world ``code``."""
        u = self.rng.random()
        if self.present:
            if u < self.p_leave:
                self.present, self.intention = False, 0
                return
        else:
            if u < self.p_return:
                self.present = True
            else:
                return
        if self.satisfied or self.intention == 0:
            self.satisfied = False
            if self.rng.random() < self.p_none:
                self.intention = 0
                return
            # judged in the world as it is with the human present (a returning human can want 'come')
            valid = self.reasonable[self.with_presence[code][0]]
            self.intention = valid[int(self.rng.random() * len(valid))] if valid else 0  # UniformStream.index, inlined

    def respond(self, action: int) -> Outcome:
        """Lines 8-19: feedback (and a proposal on a miss) for the robot's action. The answer is the
        tick's outcome record (the environment adds what the action did to the body), with the
        human's truth for the metrics."""
        it = self.intention
        if it == 0:
            return Outcome(action, 0, None, None, None, 0, False)
        if action in self.desired[it]:
            self.satisfied = True
            return Outcome(action, 1, None, it if self.reveal == "feedback" else None, None, it, True)
        proposal = self.proposal(it)
        # a proposal names a desired action, so it tells the robot what the human meant
        clarified = it if proposal is not None and self.reveal != "never" else None
        return Outcome(action, -1, proposal, clarified, None, it, False)

    def proposal(self, it: int) -> int | None:
        """Line 17: the desired action the human proposes after scolding a miss (None: it says
        nothing more), by the open choices human_proposal_prob and human_proposal_choice."""
        if self.rng.random() >= self.p_propose:
            return None
        options = self.desired_order[it]
        rule = self.proposal_choice
        if len(options) == 1 or rule == "first":
            return options[0]
        if rule == "random":
            return options[self.rng.index(len(options))]
        named = self.sc.c.action_ids[rule]
        return named if named in options else options[0]

    def observe(self, with_intention: bool = False) -> dict:
        """What the robot sees of the human this tick: one symbol per channel (and, for the
        oracle recogniser, the true intention's name)."""
        if self._habits is None:
            raise ScenarioError(f"{self.sc.source}: the scenario has no 'observations' block: the simulated human cannot be observed")
        it = self.intention
        u = self.obs_rng.random
        out = {}
        for ch, symbols, noise, cum in self._habits:
            if u() < noise:
                out[ch] = symbols[int(u() * len(symbols))]
            else:
                x, row = u(), cum[it]
                k = 0
                while k < len(row) - 1 and x >= row[k]:  # inverse CDF of the habit
                    k += 1
                out[ch] = symbols[k]
        if with_intention:
            out["intention"] = self.sc.intention_names[it]
        return out


def stream_from(seed: int, component: str, st) -> UniformStream:
    """A component's stream continued from its saved state; ValueError (one line) for a bad one."""
    if not isinstance(st, dict) or type(st.get("block")) is not int or type(st.get("drawn")) is not int:
        raise ValueError(f"{component} stream: not a random-stream state")
    s = UniformStream(seed, component)
    try:
        s.set_state(st)
    except (KeyError, TypeError, ValueError, OverflowError) as exc:  # numpy's own checks of the generator
        raise ValueError(f"{component} stream: {str(exc).splitlines()[0] if str(exc) else type(exc).__name__}") from None
    return s


def _habit_tables(sc: Scenario):
    """Per channel: (name, symbols, noise, cumulative habit per intention); None without observations."""
    spec = sc.observations
    if spec is None:
        return None
    out = []
    for ch in OBS_CHANNELS:
        cum = []
        for row in spec.habits[ch]:
            acc, c = 0.0, []
            for p in row:
                acc += p
                c.append(acc)
            cum.append(c)
        out.append((ch, spec.alphabets[ch], getattr(sc.open, f"{ch}_noise"), cum))
    return tuple(out)

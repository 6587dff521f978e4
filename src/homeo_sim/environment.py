"""The thesis's simulated home behind the environment boundary (``homeo_decision.environment``).

World, human and body in the order of one iteration of Section 4.2.1: the action's effects on the
world and the body (Table 4.1), the human's answer (Algorithm 2 lines 8-19), the body's time
increase (Table 4.2), the human's next wish and presence (lines 3-6). The in-process runner and
the simulation node both drive this object.
"""

from __future__ import annotations

from homeo_decision.environment import Observation, Outcome
from homeo_decision.scenario import OBS_CHANNELS, Scenario

from .body import SimBody
from .human import SimHuman
from .world import World


class SimEnvironment:
    """``reset`` / ``observe`` / ``step`` over the simulated world, human and body.

    ``cues``: draw what the robot sees of the human (gesture, movement, keyword: the scenario's
    ``observations``) in every observation; they come from the human's own "observation" stream,
    so drawing them or not leaves everything else unchanged. The true intention is always in the
    observation (an oracle reads it; a recogniser ignores it). ``body_after``: report the body
    right after each action in the outcome (default: when the scenario's open choices need it)."""

    def __init__(self, sc: Scenario, seed: int = 0, cues: bool = False, body_after: bool | None = None,
                 human: SimHuman | None = None):
        self.sc = sc
        self.world = World(sc)
        self.human = human if human is not None else SimHuman(sc, seed)  # or a person (person.PersonHuman)
        self.body = SimBody(sc)
        self.cues = cues and sc.observations is not None
        self._unseen = [w[0] for w in sc.c.with_intention]  # the world code with the intention `none`
        # report the body right after the action (in-process only these two open choices need it)
        self.keep_after = body_after if body_after is not None else (
            sc.open.reward_span == "action" or sc.open.metrics_sample == "after_action")
        self.time_first = sc.open.time_increase == "before_action"
        self._start(seed)

    @property
    def seed(self) -> int:
        return self.human.seed

    def reset(self, seed: int | None = None) -> Observation:
        self._start(seed)
        return self.observe()

    def _start(self, seed: int | None) -> None:
        self.world.reset()
        self.human.reset(seed)
        self.body.reset()
        self.tick = 0
        self._advance_human()  # Algorithm 2 lines 1-6: the first intention

    def _advance_human(self) -> None:
        h = self.human
        h.advance(self.world.code)
        self.world.set_human(h.present, h.intention)
        cues = h.observe() if self.cues else None  # how the human shows its wish this tick
        self._obs = Observation(self._unseen[self.world.code], self.body.values, h.intention, cues)

    def start(self) -> None:
        """Before tick 0: a person playing the human now states the first wish (may block)."""
        if hasattr(self.human, "start"):
            self.human.start()
            self._advance_human()

    def state(self) -> dict:
        """World, body, human (and its streams) and the cues of the current observation, as JSON-able
        data (a checkpoint); ``set_state`` goes on from it exactly."""
        st = {"tick": self.tick, "world": self.world.code, "body": list(self.body.values), "human": self.human.state(),
              "cues": dict(self._obs.cues) if self._obs.cues is not None else None}
        if hasattr(self.human, "live"):  # a person: whether the run had started
            st["live"] = self.human.live
        return st

    def set_state(self, st) -> None:
        """Go on from ``state()``; raises ValueError (one line) for anything else, changing nothing."""
        sc = self.sc
        if not isinstance(st, dict):
            raise ValueError("not an environment state")
        tick, code, body = st.get("tick"), st.get("world"), st.get("body")
        if type(tick) is not int or tick < 0:
            raise ValueError(f"environment tick must be an integer >= 0, got {tick!r}")
        if type(code) is not int or not 0 <= code < sc.n_codes:
            raise ValueError(f"world code must be in 0..{sc.n_codes - 1}, got {code!r}")
        if sc.c.with_presence[code][sc.c.presence_of[code]] != code:  # a sensed relation: a robot's world only
            raise ValueError(f"world code {code} is not the simulation's: its human relation is not the one the "
                             f"locations give")
        if not isinstance(body, list) or len(body) != len(sc.drives) or not all(
                type(x) in (int, float) and 0.0 <= x <= 100.0 for x in body):
            raise ValueError(f"body must be {len(sc.drives)} numbers in 0..100")
        cues = st.get("cues")
        if self.cues:
            alpha = sc.observations.alphabets
            if not isinstance(cues, dict) or set(cues) != set(OBS_CHANNELS) or not all(
                    isinstance(v, str) and v in alpha[ch] for ch, v in cues.items()):
                raise ValueError("cues must name one symbol of each channel's alphabet")
        elif cues is not None:
            raise ValueError("cues in the state of an environment that draws none")
        person = hasattr(self.human, "live")
        live = st.get("live", False)
        if type(live) is not bool or (live and not person):
            raise ValueError("live must be true or false, and only for a person")
        self.human.set_state(st.get("human"))  # checks everything before it changes anything
        if person:
            self.human.live, self.human._first = live, False
        self.world.code = code
        self.body.values[:] = [float(x) for x in body]  # in place: the observation holds this list
        self.tick = tick
        o = self._obs
        o.code, o.intention, o.cues = self._unseen[code], self.human.intention, dict(cues) if cues is not None else None

    def observe(self) -> Observation:
        """What the robot can sense now. The record is the environment's own, updated in place by
        ``step`` (the per-tick path), and its body is the live list of readings: take it in (or
        copy it) before the next ``step``."""
        return self._obs

    def step(self, action: int | None) -> Outcome:
        world, body = self.world, self.body
        # the body drives that do not grow this tick (open choice drive_growth; usually none)
        still = body.still(world.code, action) if body.growth_when else ()
        if self.time_first:  # open choice time_increase: the time increase before the action
            body.apply_time(still=still)
        if action is not None:
            before = world.execute(action)
            body.apply_action(before, action)
            out = self.human.respond(action)
        else:  # nothing happened for the human to answer
            out = Outcome(None, 0, None, None, None, self.human.intention, False)
        if self.keep_after:
            out.body = list(body.values)
        if not self.time_first:
            body.apply_time(still=still)
        h = self.human  # _advance_human, inlined: once per tick
        h.advance(world.code)
        world.set_human(h.present, h.intention)
        o = self._obs  # the record of the new tick (see observe)
        o.code, o.intention = self._unseen[world.code], h.intention
        if self.cues:
            o.cues = h.observe()
        self.tick += 1
        return out

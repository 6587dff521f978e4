"""A person plays the human (``homeo-launch sim --human person``), behind the same environment
boundary as the simulated one: ``SimEnvironment`` asks it what it wants (``advance``) and what it
says to the robot's action (``respond``); the answers come from ``homeo/human_input`` messages
(``homeo_msgs_py.human_input``) through ``inbox``.

The run starts when the person first speaks (tick 0's wish is waited for without a bound; a
``None`` in the inbox ends any wait, as silence). Then each tick waits for the person up to
``timeout`` seconds: first for the wish of the tick (silence:
"no intention"), then, when there is a wish, for the answer to the robot's action (praise, scold,
a proposal; silence: no answer). A wish sent together with an answer is the next tick's wish.
What the robot sees of the person's wish (gesture, movement, keyword, for the Bayesian recogniser)
is drawn from the scenario's habits, as for the simulated human.
"""

from __future__ import annotations

import queue

from homeo_decision.environment import Outcome
from homeo_decision.scenario import Scenario

from .human import SimHuman


class PersonHuman(SimHuman):
    def __init__(self, sc: Scenario, seed: int = 0, timeout: float = 10.0, inbox: queue.Queue | None = None):
        self.inbox = inbox if inbox is not None else queue.Queue()
        self.timeout = timeout
        self.silent = 0  # waits that timed out
        super().__init__(sc, seed)

    def reset(self, seed: int | None = None) -> None:
        super().reset(seed)
        self.live = False  # the first wait is in the run's start, not while the world is being built
        self._first = False
        self._next_wish = None

    def start(self) -> None:
        self.live = True
        self._first = True

    def _wait(self):
        first, self._first = self._first, False
        try:
            got = self.inbox.get(timeout=None if first else self.timeout)
        except queue.Empty:
            got = None
        if got is None:
            self.silent += 1
        return got

    def advance(self, code: int) -> None:
        self.present = True
        if not self.live:
            self.intention = 0
            return
        inp, self._next_wish = (self._next_wish, None) if self._next_wish is not None else (self._wait(), None)
        # silence, or an answer that came too late for its tick: no wish this tick
        self.intention = self._index(inp.intention) if inp is not None and inp.stated else 0

    def respond(self, action: int) -> Outcome:
        it = self.intention
        if it == 0:  # no wish, nothing to answer (Algorithm 2 line 9)
            return Outcome(action, 0, None, None, None, 0, False)
        inp = self._wait()
        if inp is None:
            return Outcome(action, 0, None, None, None, it, False)
        if inp.stated:
            self._next_wish = inp  # the wish of the next tick
        fb = inp.feedback
        proposal = self.sc.c.action_ids[inp.proposal] if inp.proposal is not None else None
        reveal = self.reveal
        clarified = it if (fb == 1 and reveal == "feedback") or (proposal is not None and reveal != "never") else None
        self.satisfied = fb == 1
        return Outcome(action, fb, proposal, clarified, None, it, fb == 1)

    def _index(self, name: str | None) -> int:
        return 0 if name is None else self.sc.intention_names.index(name)

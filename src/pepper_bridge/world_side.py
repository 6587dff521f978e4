"""The bridge node's side of the lockstep (``homeo_msgs_py.lockstep.WorldSide``), without ROS.

A :class:`~pepper_bridge.environment.PepperEnvironment` in message fields (``homeo_decision.codec``):
the user's first expression before tick 0, observations out, actions in, outcomes out; and the
interaction log the launcher prints (one row per interaction: what the decision chose it for,
``m_dom`` and the intention, and what the robot did and heard). Every call but ``status`` may
block: the node runs them on a worker thread (``LockstepDriver``'s ``run_async``).
"""

from __future__ import annotations

from homeo_decision import codec

from .environment import MAX_LOG_ROWS, PepperEnvironment

STANDIN_SERVICE = "HomeoStandin"  # the stand-in's control service (not NAOqi; a real robot has none)


class PepperWorldSide:
    def __init__(self, env: PepperEnvironment, end_with_script: bool = False):
        self.env, self.sc = env, env.sc
        self.end_with_script = end_with_script
        self.log: list = []
        self.user_done = False  # the stand-in's scripted user has no more interactions
        self.last_missed = False  # the last step found the robot away: the driver counts a missed tick
        self._standin = None

    def reset(self) -> None:
        self.log = []
        self.user_done = False

    # -- WorldSide ---------------------------------------------------------------------------
    def start(self) -> None:
        self.env.reset()

    def observe(self, final: bool) -> tuple[dict, dict]:
        return codec.observation_messages(self.sc, self.env.observe(), final)

    def check_action(self, fields: dict, tick: int) -> None:
        pass  # any action of the vocabulary will do; the robot refuses what it cannot perform

    def step(self, action_fields: dict | None) -> dict:
        name = action_fields.get("action") if action_fields is not None else None
        out = self.env.step(self.sc.action_index(name) if name is not None else None)
        self._row(action_fields)
        self.last_missed = bool(self.env.last_row.get("missed"))
        if self.end_with_script:
            self.user_done = self._standin_user_done()
        return codec.outcome_fields(self.sc, out)

    def step_failed(self, action_fields: dict | None, reason: str) -> dict:
        name = action_fields.get("action") if action_fields is not None else None
        out = self.env.failed(self.sc.action_index(name) if name is not None else None, reason)
        self._row(action_fields)
        self.last_missed = True
        return codec.outcome_fields(self.sc, out)

    def record(self, action_fields: dict | None) -> None:
        pass  # no metrics on a robot: its user's judgement is the field test's

    def status(self, done: bool) -> dict:
        link = self.env.bridge.status()
        return {"extra": {"log": list(self.log), "interactions_done": self.env.tick,
                          "robot": {k: link.get(k) for k in ("state", "connected", "reason", "url", "connects", "drops", "freezes")},
                          "robot_missed": sum(1 for r in self.log if r.get("missed")), "naoqi": self.env.bridge.naoqi()}}

    # -- helpers ---------------------------------------------------------------------------
    def _row(self, action_fields: dict | None) -> None:
        r = dict(self.env.last_row)
        f = action_fields or {}
        rec = f.get("intention")  # what the decision acted on (the recogniser's), else what the cues named
        r["m_dom"] = f.get("m_dom")
        r["drives"] = f.get("drives")  # the drives the decision chose with (the body's, read this tick)
        r["intention"] = (None if rec == self.sc.intention_names[0] else rec) if rec is not None else r["cue_intention"]
        self.log.append(r)
        del self.log[:-MAX_LOG_ROWS]

    def _standin_user_done(self) -> bool:
        """The stand-in's scripted user is done (on a real robot there is no such service: False)."""
        session = self.env.bridge.link.session
        if session is None:
            return False
        try:
            if self._standin is None or self._standin[0] is not session:
                self._standin = (session, session.service(STANDIN_SERVICE))
            return bool(self._standin[1].state()["user_done"])
        except RuntimeError:
            return False

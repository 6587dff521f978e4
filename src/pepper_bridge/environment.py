"""A Pepper behind the environment boundary (``homeo_decision.environment``), over :class:`PepperBridge`.

- ``reset(seed)``: the user's first expression (the robot listens until a quiet gap or the
  window is over), then the observation of tick 0. The seed is not used: the user is real (or
  the stand-in's, seeded by itself).
- ``observe()``: read the robot: the world code of what the bridge knows (the intention `none`),
  the body drives read from the battery and the joints' temperature (Section 4.3.1, Table 4.6),
  ``readings`` (battery percent, temperature status), ``cues`` (the last gesture, movement and
  keyword the user showed since the last observation; symbols outside the scenario's alphabets
  are left out) and, with ``use_cues``, the intention the config's cues name (an oracle
  recogniser reads it; 0 when none is named). Within a tick it answers the same observation.
  Raises :class:`RobotUnavailable` (robot away) or :class:`NotReady` (no valid body reading yet).
- ``step(action)``: execute the action, collect the user's reaction until ``quiet`` seconds pass
  without an event or ``window`` is over; the outcome carries the feedback (Eq 3.22), the proposal,
  the intention the proposal clarifies and the body right after the action. A refused or failed
  action did nothing: ``Outcome(action=None, failure=reason)``.

Every call may block (qi calls, the reaction's wait): a ROS node runs them on a worker thread.
Robot events are queued on qi threads; :meth:`pump` moves them into the environment (the user's
events) or into :meth:`notices` (link status, rejected values: for the host to report).
"""

from __future__ import annotations

import collections
import threading
import time

from homeo_decision import codec
from homeo_decision.environment import Observation, Outcome
from homeo_decision.scenario import OBS_CHANNELS

from . import events as ev
from .bridge import PepperBridge
from .cues import IntentionCues

MAX_LOG_ROWS = 1000  # the interaction log keeps the newest rows (an unbounded run)


class NotReady(RuntimeError):
    """The robot answered but a body reading has no valid value yet (the observation waits)."""


class PepperEnvironment:
    """``reset`` / ``observe`` / ``step`` on a (stand-in) Pepper; ``log`` has one row per step."""

    def __init__(self, bridge: PepperBridge, *, quiet: float = 0.15, window: float = 3.0, use_cues: bool = True,
                 clock=time.monotonic):
        self.bridge, self.sc, self.cfg = bridge, bridge.sc, bridge.cfg
        self.quiet, self.window, self.use_cues = quiet, window, use_cues
        self.clock = clock
        self.cues = IntentionCues(self.cfg.intention_cues, self.sc.intention_names[1:])
        obs_spec = getattr(self.sc, "observations", None)
        self.alphabets = getattr(obs_spec, "alphabets", None) or {}
        self._lock = threading.Lock()
        self._events: list = []  # the user's events since they were last taken
        self._notices: collections.deque = collections.deque(maxlen=200)
        self._last_event = 0.0
        self.dropped: collections.Counter = collections.Counter()  # symbols outside the alphabets, per channel
        self._start()

    def _start(self) -> None:
        self.tick = 0
        self._obs: Observation | None = None
        self._seen: dict = {}  # what the current observation was made of (for the log)
        self.log: list = []

    # -- events ----------------------------------------------------------------------------
    def pump(self, timeout: float = 0.0) -> int:
        """Move queued robot events in (waiting up to ``timeout`` for the first); the number of user events."""
        got = self.bridge.poll_events(timeout)
        n = 0
        with self._lock:
            for e in got:
                if e.kind in (ev.STATUS, ev.REJECTED):
                    self._notices.append(e)
                else:
                    self._events.append(e)
                    self._last_event = max(self._last_event, e.t)
                    n += 1
        return n

    def notices(self) -> list:
        """Link status changes and rejected values since the last call (thread-safe)."""
        self.pump()
        with self._lock:
            out = list(self._notices)
            self._notices.clear()
        return out

    def _collect(self) -> None:
        """The user's reaction: until ``quiet`` s without an event (after the start) or ``window`` s."""
        start = self.clock()
        while True:
            now = self.clock()
            left = self.window - (now - start)
            calm = self.quiet - (now - max(start, self._last_event))
            if left <= 0 or calm <= 0:
                return
            self.pump(min(left, calm))

    def _take(self, kinds=None) -> list:
        with self._lock:
            if kinds is None:
                out, self._events = self._events, []
            else:
                out = [e for e in self._events if e.kind in kinds]
                self._events = [e for e in self._events if e.kind not in kinds]
        return out

    # -- the boundary ----------------------------------------------------------------------
    def reset(self, seed: int | None = None) -> Observation:
        self._start()
        self._collect()  # the user's first expression (it starts when the robot listens)
        return self.observe()

    def observe(self) -> Observation:
        if self._obs is not None:
            return self._obs
        self.pump()
        sc, cfg = self.sc, self.cfg
        world = self.bridge.read_world()
        body = world["body"]
        missing = [d for d in (cfg.battery_drive, cfg.temperature_drive) if body.get(d) is None]
        if missing:
            raise NotReady(f"no valid reading of {', '.join(missing)} yet")
        raw = ev.observation_of(self._take())
        cue = self.cues(raw)
        seen = {ch: raw.get(ch) for ch in OBS_CHANNELS}
        for ch, v in seen.items():  # the recogniser rejects unknown symbols: one stray word must not cost a tick
            if v is not None and ch in self.alphabets and v not in self.alphabets[ch]:
                seen[ch] = None
                self.dropped[ch] += 1
        intention = sc.intention_names.index(cue) if cue is not None else 0
        self._obs = Observation(codec.world_code(sc, world), codec.body_vector(sc, body),
                                intention if self.use_cues else None, seen,
                                {"battery_percent": body["battery_percent"],
                                 "temperature_status": body["temperature_status"]})
        self._seen = {"world": world, "cue_intention": cue, "observation": raw}
        return self._obs

    def step(self, action: int | None) -> Outcome:
        sc = self.sc
        self.observe()
        name = sc.action_names[action] if action is not None else None
        if name is None:
            res = {"action": None, "ok": True, "reason": None}
        else:
            res = self.bridge.execute(name)
        try:
            after = self.bridge.read_body()
            body = codec.body_vector(sc, after) if all(after.get(d) is not None for d in
                                                      (self.cfg.battery_drive, self.cfg.temperature_drive)) else None
        except Exception:  # noqa: BLE001 - the body after the action is optional (the robot dropped)
            body = None
        self._collect()
        answer = self._take((ev.FEEDBACK, ev.PROPOSAL))  # what stays is the user's next expression
        done = name if res["ok"] else None  # what the world saw: nothing when the action failed
        out = self.bridge.outcome(done, answer)
        idx = lambda names, n: names.index(n) if n is not None else None  # noqa: E731
        outcome = Outcome(action if res["ok"] else None, out["feedback"], idx(sc.action_names, out["proposal"]),
                          idx(sc.intention_names, out["clarified_intention"]), body,
                          failure=None if res["ok"] else (res["reason"] or "failed"))
        seen = self._seen
        wb = seen["world"]["body"]
        self.last_row = {"interaction": self.tick + 1, "cue_intention": seen["cue_intention"], "action": name,
                         "ok": res["ok"], "reason": res["reason"], "missed": bool(res.get("unavailable")),
                         "feedback": out["feedback"],
                         "proposal": out["proposal"], "location": seen["world"]["robot"]["location"],
                         "relation": seen["world"]["human"]["relation"],
                         "battery_percent": wb.get("battery_percent"),
                         "temperature_status": wb.get("temperature_status"), "observation": seen["observation"]}
        self.log.append(self.last_row)
        del self.log[:-MAX_LOG_ROWS]
        self.tick += 1
        self._obs = None
        return outcome

    def failed(self, action: int | None, reason: str) -> Outcome:
        """The outcome of a step that raised (e.g. the robot dropped mid-call): nothing was done."""
        name = self.sc.action_names[action] if action is not None else None
        seen = self._seen or {"world": {"robot": {}, "body": {}}, "cue_intention": None, "observation": {}}
        self.last_row = {"interaction": self.tick + 1, "cue_intention": seen["cue_intention"], "action": name,
                         "ok": False, "reason": reason, "missed": True, "feedback": 0, "proposal": None,
                         "location": seen["world"]["robot"].get("location"),
                         "relation": (seen["world"].get("human") or {}).get("relation"),
                         "battery_percent": seen["world"]["body"].get("battery_percent"),
                         "temperature_status": seen["world"]["body"].get("temperature_status"),
                         "observation": seen["observation"]}
        self.log.append(self.last_row)
        del self.log[:-MAX_LOG_ROWS]
        self.tick += 1
        self._obs = None
        return Outcome(None, 0, None, None, None, failure=reason)

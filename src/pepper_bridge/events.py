"""Events from the robot, as the caller sees them, and the diagnostics of rejected values.

qi delivers memory events on its own threads. :class:`EventParser` turns each raw
(key, value) into :class:`BridgeEvent` objects (or a rejection) and puts them on a
``queue.Queue``; the caller (the ROS node, the field driver) drains the queue on its own
thread. Nothing here calls back into the caller.
"""

from __future__ import annotations

import collections
import queue
import threading
import time
from dataclasses import dataclass, field
from typing import Any, Iterable

from .config import PepperConfig
from .mapping import (EMOTION_EVENT, TOUCH_EVENTS, WORD_EVENT, Rejected, WordMap, emotion_feedback,
                      recognized_phrases, short, touch_feedback)

# kinds of BridgeEvent
FEEDBACK = "feedback"  # value +1 / -1
PROPOSAL = "proposal"  # value: action name
KEYWORD = "keyword"  # value: word symbol
GESTURE = "gesture"
MOVEMENT = "movement"
STATUS = "status"  # value: status dict (connected / disconnected / connecting)
REJECTED = "rejected"  # value: {"source", "value", "reason"}
OBSERVATION_KINDS = (GESTURE, MOVEMENT, KEYWORD)


@dataclass(frozen=True)
class BridgeEvent:
    kind: str
    value: Any
    source: str
    t: float = field(default_factory=time.monotonic)


class Diagnostics:
    """Counted rejections and link incidents, thread-safe; ``snapshot()`` is what /diagnostics shows."""

    def __init__(self, keep: int = 50):
        self._lock = threading.Lock()
        self.rejected: collections.Counter = collections.Counter()  # source -> count
        self.incidents: collections.Counter = collections.Counter()  # name -> count
        self.recent: collections.deque = collections.deque(maxlen=keep)

    def reject(self, r: Rejected) -> None:
        with self._lock:
            self.rejected[r.source] += 1
            self.recent.append({"source": r.source, "value": short(r.value), "reason": r.reason, "t": time.time()})

    def incident(self, name: str, message: str = "") -> None:
        with self._lock:
            self.incidents[name] += 1
            self.recent.append({"source": name, "value": "", "reason": message, "t": time.time()})

    @property
    def rejected_total(self) -> int:
        with self._lock:
            return sum(self.rejected.values())

    def snapshot(self) -> dict:
        with self._lock:
            return {"rejected_total": sum(self.rejected.values()), "rejected_by_source": dict(self.rejected),
                    "incidents": dict(self.incidents), "recent": list(self.recent)}


class EventParser:
    """Raw memory events -> BridgeEvents on ``out`` (runs on qi threads or the poller thread)."""

    def __init__(self, cfg: PepperConfig, words: WordMap, out: queue.Queue, diag: Diagnostics):
        self.cfg, self.words, self.out, self.diag = cfg, words, out, diag

    @property
    def keys(self) -> list[str]:
        return list(TOUCH_EVENTS) + [EMOTION_EVENT, WORD_EVENT, self.cfg.gesture_event, self.cfg.movement_event]

    def __call__(self, key: str, value: Any) -> None:
        try:
            for ev in self.parse(key, value):
                self.out.put(ev)
        except Rejected as r:
            self.diag.reject(r)
            self.out.put(BridgeEvent(REJECTED, {"source": r.source, "value": short(r.value), "reason": r.reason}, key))
        except Exception as exc:  # never let an exception escape into a qi thread
            r = Rejected(key, value, f"unexpected {type(exc).__name__}: {exc}")
            self.diag.reject(r)
            self.out.put(BridgeEvent(REJECTED, {"source": key, "value": short(value), "reason": r.reason}, key))

    def parse(self, key: str, value: Any) -> list[BridgeEvent]:
        if key in TOUCH_EVENTS:
            return [BridgeEvent(FEEDBACK, 1, key)] if touch_feedback(value, key) == 1 else []
        if key == EMOTION_EVENT:
            fb = emotion_feedback(value, self.cfg.anger_level, self.cfg.emotion_scale, key)  # the robot's scale
            return [BridgeEvent(FEEDBACK, -1, key)] if fb else []
        if key == WORD_EVENT:
            phrases = recognized_phrases(value, self.cfg.word_confidence, key)
            if not phrases:
                return []
            kind, sym = self.words.classify(phrases[0])  # the best hypothesis only
            return [BridgeEvent(PROPOSAL if kind == "proposal" else KEYWORD, sym, key)]
        if key in (self.cfg.gesture_event, self.cfg.movement_event):
            if not isinstance(value, str) or not value:
                raise Rejected(key, value, "expected a non-empty symbol (string)")
            return [BridgeEvent(GESTURE if key == self.cfg.gesture_event else MOVEMENT, value, key)]
        return []


def drain(q: queue.Queue, timeout: float = 0.0) -> list[BridgeEvent]:
    """Everything on the queue now (waiting up to ``timeout`` for the first item)."""
    out = []
    try:
        out.append(q.get(timeout=timeout) if timeout > 0 else q.get_nowait())
    except queue.Empty:
        return out
    while True:
        try:
            out.append(q.get_nowait())
        except queue.Empty:
            return out


def feedback_of(events: Iterable[BridgeEvent]) -> int:
    """One answer per action: a scolding wins over praise; nothing is 0."""
    vals = [e.value for e in events if e.kind == FEEDBACK]
    return -1 if -1 in vals else 1 if 1 in vals else 0


def proposal_of(events: Iterable[BridgeEvent]) -> str | None:
    props = [e.value for e in events if e.kind == PROPOSAL]
    return props[-1] if props else None


def observation_of(events: Iterable[BridgeEvent]) -> dict:
    """The observation fields: the last gesture, movement and keyword seen (None when none)."""
    obs = {"gesture": None, "movement": None, "keyword": None}
    for e in events:
        if e.kind in OBSERVATION_KINDS:
            obs[e.kind] = e.value
    return obs

"""The stand-in's scripted user (no qi import): a file of interactions and timed events.

A user file (``scripts/*.json``, schema ``homeo-pepper-user``)::

    {"schema": "homeo-pepper-user", "version": 1,
     "start": {"battery_percent": 30, "location": "R", "presence": "present", "heat": 0.0},
     "robot": {"drives": {"NAch": 70, "NSoc": 40}},
     "interactions": [
        {"intention": "light", "gesture": "point_up", "words": ["light"], "praise": false},
        {"intention": null},
        {"intention": "music", "words": ["music"], "patience": 2, "proposal": "Play"},
        {"presence": "absent"}
     ],
     "timed": [{"at": 1.5, "touch": "FrontTactilTouched"}, {"at": 2.0, "anger": 8}, {"at": 2.2, "calm": 6},
               {"at": 2.5, "words": [["Play", 0.8]]}, {"at": 3.0, "presence": "absent"}]}

Interactions are reactive, one per robot action: the user expresses the intention (a gesture
event, a movement event, one ``WordRecognized`` per word), watches what the robot does, and
answers: a head touch when the robot did a desired action and ``praise`` (default true); an
angry voice (``EmotionRecognized`` in the documented shape, anger level ``anger`` on the robot's
scale: default 8 of 10, e.g. ``[[2, 8], [1, 8, 0, 0, 0], 7]``) otherwise when ``scold``
(default true), with the proposal spoken (``WordRecognized``) when ``propose`` (default
true). A missed intention is expressed again, up to ``patience`` attempts (default 1). An
interaction with ``"intention": null`` expresses nothing and answers nothing; ``calm`` (a level, e.g. 6)
adds a calm voice to the answer (``[[1, 6], [6, 1, 0, 0, 0], 1]`` on 0..10: not a scolding). ``presence``
("present" / "absent") moves the user before expressing; ``walks`` ("to_robot" / "home") has the person
walk up to the robot, wherever it stands, or back to the user's place before expressing (the stand-in
places the person: ``standin_person``; a timed entry may carry ``presence`` and ``walks`` too).
``helps`` (default true, per interaction or for the whole file): asked for help with the plug (an action of the config that sets the plug variable: the thesis's
Attach / Detach), the user plugs / unplugs the robot when it stands where the plugged object is (the charger). ``start`` sets the stand-in body; ``robot`` holds the robot's initial internal
drives for the field driver. Timed entries fire at ``at`` wall seconds after the user starts
(when the robot first starts its speech recognition).

An interaction may also script the robot (the stand-in, not the user): ``"robot": {"heat": 2.5,
"battery_percent": 20, "drop": 10, "freeze": 20}``. ``heat`` / ``battery_percent`` set the body when
the interaction starts (joint temperature status is floor(heat) on the legs and wheels);
``drop`` / ``freeze`` (seconds): as the robot starts its first action of this interaction, it drops
its connection (and comes back on the same URL) or stops answering with the connection open; that
action is not performed, and the user waits for the next one.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

from .standin_naoqi import EMOTION_EVENT, RELEASED, TOUCH_EVENTS, TOUCHED, WORD_EVENT, voice

SCHEMA = "homeo-pepper-user"
VERSION = 1
ROBOT_LIMITS = {"heat": 3.99, "battery_percent": 100, "drop": 600, "freeze": 600}  # an interaction's "robot" keys
WALKS = ("to_robot", "home")  # where a script may have the person walk


class ScriptError(ValueError):
    pass


@dataclass
class Reaction:
    emits: list  # (event key, value) in order
    plug: bool | None = None  # True: the user plugs the robot in, False: unplugs, None: nothing


@dataclass
class ScriptedUser:
    script: dict
    desired: Mapping[str, tuple]  # intention -> desired actions (from the scenario)
    gesture_event: str = "PepperBridge/Gesture"
    movement_event: str = "PepperBridge/Movement"
    plug_actions: Mapping[str, bool] = field(default_factory=dict)  # action -> True: plug in, False: unplug
    plug_place: str | None = None  # where the plug is (None: anywhere)
    emotion_scale: int = 10  # the robot's emotion levels are integers 0..emotion_scale (NAOqi 2.5+: 10)
    spoken: Mapping[str, str] = field(default_factory=dict)  # action -> the phrase a person says for it
    index: int = 0
    attempts: int = 0
    present: bool = True
    started: bool = False
    walk: str | None = None  # where the script asked the person to walk, until the stand-in takes it
    log: list = field(default_factory=list)  # one row per judged robot action

    def __post_init__(self):
        self.items = list(self.script.get("interactions", []))
        self.present = self.script.get("start", {}).get("presence", "present") == "present"

    @property
    def done(self) -> bool:
        return self.index >= len(self.items)

    @property
    def current(self) -> dict | None:
        return None if self.done else self.items[self.index]

    def start(self) -> list:
        """The first interaction's expression."""
        self.started = True
        return self._express()

    def _express(self) -> list:
        it = self.current
        if it is None:
            return []
        if "presence" in it:
            self.present = it["presence"] == "present"
        if "walks" in it:
            self.walk = it["walks"]
        if not self.present or it.get("intention") is None:
            return []
        out = []
        if it.get("gesture"):
            out.append((self.gesture_event, it["gesture"]))
        if it.get("movement"):
            out.append((self.movement_event, it["movement"]))
        for w in it.get("words", []):
            out.append((WORD_EVENT, [w, 0.9]))
        return out

    def react(self, action: str, location: str | None) -> Reaction:
        """The user's answer to a robot action it saw, then its next expression."""
        it = self.current
        plug = None
        helps = (it or {}).get("helps", self.script.get("helps", True))
        if action in self.plug_actions and helps and self.present \
                and (self.plug_place is None or location == self.plug_place):
            plug = self.plug_actions[action]
        if it is None or not self.started:
            return Reaction([], plug)
        intention = it.get("intention") if self.present else None
        emits: list = []
        row = {"interaction": len(self.log) + 1, "item": self.index, "intention": intention, "action": action, "satisfied": None,
               "feedback": 0, "proposal": None}
        if it.get("calm") is not None:  # a calm answer (documented scale): no scolding
            emits.append((EMOTION_EVENT, calm_voice(it["calm"], self.emotion_scale)))
        if intention is None:
            self._next()
        elif action in self.desired.get(intention, ()):
            row["satisfied"] = True
            if it.get("praise", True):
                emits += [(TOUCH_EVENTS[1], TOUCHED), (TOUCH_EVENTS[1], RELEASED)]
                row["feedback"] = 1
            self._next()
        else:
            row["satisfied"] = False
            if it.get("scold", True):
                emits.append((EMOTION_EVENT, angry_voice(it.get("anger"), self.emotion_scale)))
                row["feedback"] = -1
                if it.get("propose", True):
                    prop = it.get("proposal") or self.desired[intention][0]
                    emits.append((WORD_EVENT, [self.spoken.get(prop, prop), 0.9]))  # words, not action ids
                    row["proposal"] = prop
            self.attempts += 1
            if self.attempts >= int(it.get("patience", 1)):
                self._next()
        self.log.append(row)
        emits += self._express()
        return Reaction(emits, plug)

    def _next(self):
        self.index += 1
        self.attempts = 0

    def take_walk(self) -> str | None:
        """Where the person was last asked to walk (once; None: nowhere new)."""
        where, self.walk = self.walk, None
        return where


def angry_voice(anger: Any, scale: int) -> list:
    """A scolding as ALVoiceEmotionAnalysis reports it: on 0..10, anger 8 -> [[2, 8], [1, 8, 0, 0, 0], 7]."""
    a = int(round(0.8 * scale)) if anger is None else int(anger)
    return voice(scale, calm=min(1, scale - a) if a < scale else 0, anger=a, excitement=min(scale, 7))


def calm_voice(calm: Any, scale: int) -> list:
    """A calm answer: on 0..10, calm 6 -> [[1, 6], [6, 1, 0, 0, 0], 1]."""
    c = int(calm)
    return voice(scale, calm=c, anger=min(1, scale - c) if c < scale else 0, excitement=1)


def timed_entry_emits(entry: Mapping[str, Any], gesture_event: str, movement_event: str, emotion_scale: int = 10) -> list:
    """The events one timed entry raises (presence is handled by the stand-in)."""
    out = []
    if "touch" in entry:
        out += [(entry["touch"], TOUCHED), (entry["touch"], RELEASED)]
    if "anger" in entry:
        out.append((EMOTION_EVENT, angry_voice(entry["anger"], emotion_scale)))
    if "calm" in entry:
        out.append((EMOTION_EVENT, calm_voice(entry["calm"], emotion_scale)))
    if "words" in entry:
        flat = []
        for w in entry["words"]:
            flat += list(w) if isinstance(w, (list, tuple)) else [w, 0.9]
        out.append((WORD_EVENT, flat))
    if "gesture" in entry:
        out.append((gesture_event, entry["gesture"]))
    if "movement" in entry:
        out.append((movement_event, entry["movement"]))
    if "event" in entry:  # any raw key/value
        out.append((entry["event"], entry.get("value")))
    return out


def load_script(path: str | Path) -> dict:
    """A scripted user's file (a path, or the name of a file of ``scripts/``), checked (ScriptError)."""
    from homeo_decision.jsonfile import read, shipped

    from .config import SCRIPTS_DIR

    p = shipped(path, SCRIPTS_DIR)
    return validate_script(read(p, ScriptError, "user script"), str(p))


def validate_script(raw: Any, where: str = "<memory>", intentions: tuple | None = None) -> dict:
    if not isinstance(raw, dict) or raw.get("schema") != SCHEMA:
        raise ScriptError(f"{where}: 'schema' must be {SCHEMA!r}")
    if raw.get("version") != VERSION:
        raise ScriptError(f"{where}: unsupported version {raw.get('version')!r}")
    items = raw.get("interactions", [])
    if not isinstance(items, list) or not all(isinstance(i, dict) for i in items):
        raise ScriptError(f"{where}: 'interactions' must be a list of objects")
    for k, it in enumerate(items):
        if intentions is not None and it.get("intention") is not None and it["intention"] not in intentions:
            raise ScriptError(f"{where}: interaction {k + 1}: unknown intention {it['intention']!r}")
        if it.get("presence", "present") not in ("present", "absent"):
            raise ScriptError(f"{where}: interaction {k + 1}: presence must be 'present' or 'absent'")
        if it.get("walks", "home") not in WALKS:
            raise ScriptError(f"{where}: interaction {k + 1}: walks must be 'to_robot' or 'home'")
        rob = it.get("robot", {})
        if not isinstance(rob, dict) or set(rob) - set(ROBOT_LIMITS) or not all(
                isinstance(v, (int, float)) and not isinstance(v, bool) and 0 <= v <= ROBOT_LIMITS[key]
                for key, v in rob.items()):
            raise ScriptError(f"{where}: interaction {k + 1}: robot must map "
                              + ", ".join(f"{key} to 0..{top}" for key, top in ROBOT_LIMITS.items()))
    timed = raw.get("timed", [])
    if not isinstance(timed, list) or not all(isinstance(t, dict) and isinstance(t.get("at"), (int, float)) for t in timed):
        raise ScriptError(f"{where}: 'timed' entries need a number 'at'")
    if not all(t.get("walks", "home") in WALKS and t.get("presence", "present") in ("present", "absent") for t in timed):
        raise ScriptError(f"{where}: a timed entry's walks must be 'to_robot' or 'home', its presence 'present' or 'absent'")
    return raw

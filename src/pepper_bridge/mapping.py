"""From NAOqi values to the decision system's quantities, with validation (no qi import).

Everything here is a pure function of values read from the robot. A value of the wrong
type or out of range raises :class:`Rejected` with a reason; the bridge counts it as a
diagnostic and keeps running.

Keys and formats (NAOqi 2.5/2.9 documentation):

- ``Device/SubDeviceList/Battery/Charge/Sensor/Value``: battery charge, a 0..1 fraction;
  ``ALBattery.getBatteryCharge()``: the same in percent (int 0..100).
- ``Device/SubDeviceList/<Joint>/Temperature/Sensor/Status``: 0..3 per joint.
- ``FrontTactilTouched`` / ``MiddleTactilTouched`` / ``RearTactilTouched``: 1.0 on touch,
  0.0 on release.
- ``ALVoiceEmotionAnalysis/EmotionRecognized``: ``[[matched index, matched level],
  [calm, anger, joy, sorrow, laughter], excitement]``, levels integers 0..10 (NAOqi 2.5, 2.8)
  or 0..5 (2.1, 2.4); the documentation's example ``[[4, 3], [0, 2, 1, 3, 0], 1]``.
- ``WordRecognized``: ``[phrase, confidence, phrase, confidence, ...]`` best first.
- ``EngagementZones/PeopleInZone1..3`` and ``PeoplePerception/PeopleList``: lists of ids.
- ``BatteryPowerPluggedChanged``: bool, the robot is on its charging station.
"""

from __future__ import annotations

import math
from typing import Any, Iterable, Mapping, Sequence

# Pepper's joints (ALMotion.getBodyNames("Body") on Pepper 1.8: 17 joints + 3 wheels).
PEPPER_JOINTS = (
    "HeadYaw", "HeadPitch",
    "LShoulderPitch", "LShoulderRoll", "LElbowYaw", "LElbowRoll", "LWristYaw", "LHand",
    "HipRoll", "HipPitch", "KneePitch",
    "RShoulderPitch", "RShoulderRoll", "RElbowYaw", "RElbowRoll", "RWristYaw", "RHand",
    "WheelFL", "WheelFR", "WheelB",
)

BATTERY_KEY = "Device/SubDeviceList/Battery/Charge/Sensor/Value"
PLUGGED_KEY = "BatteryPowerPluggedChanged"
TOUCH_EVENTS = ("FrontTactilTouched", "MiddleTactilTouched", "RearTactilTouched")
EMOTION_EVENT = "ALVoiceEmotionAnalysis/EmotionRecognized"
WORD_EVENT = "WordRecognized"
ZONE_KEYS = ("EngagementZones/PeopleInZone1", "EngagementZones/PeopleInZone2", "EngagementZones/PeopleInZone3")
PEOPLE_KEY = "PeoplePerception/PeopleList"
EMOTIONS = ("calm", "anger", "joy", "sorrow", "laughter")  # order of the levels list

# Table 4.6: maximum joint temperature status -> NRes.
TEMPERATURE_TO_NEED = {0: 0.0, 1: 50.0, 2: 80.0, 3: 100.0}


def temperature_key(joint: str) -> str:
    return f"Device/SubDeviceList/{joint}/Temperature/Sensor/Status"


class Rejected(ValueError):
    """A value from the robot that cannot be used; ``source`` names the key, ``reason`` says why."""

    def __init__(self, source: str, value: Any, reason: str):
        self.source, self.value, self.reason = source, value, reason
        super().__init__(f"{source}: rejected {short(value)}: {reason}")


def short(value: Any, n: int = 60) -> str:
    r = repr(value)
    return r if len(r) <= n else r[: n - 3] + "..."


def _number(source: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise Rejected(source, value, f"expected a number, got {type(value).__name__}")
    x = float(value)
    if not math.isfinite(x):
        raise Rejected(source, value, "not a finite number")
    return x


# -- body -------------------------------------------------------------------------
def percent_from_fraction(value: Any, source: str = BATTERY_KEY) -> float:
    """The charge sensor's 0..1 fraction as a percentage."""
    x = _number(source, value)
    if not 0.0 <= x <= 1.0:
        raise Rejected(source, value, "battery charge fraction outside 0..1")
    return x * 100.0


def percent_from_albattery(value: Any, source: str = "ALBattery.getBatteryCharge") -> float:
    x = _number(source, value)
    if not 0.0 <= x <= 100.0:
        raise Rejected(source, value, "battery percentage outside 0..100")
    return x


def need_from_percent(percent: float) -> float:
    """The energy drive (the thesis's NEng) = 100 - battery percentage (Section 4.3.1)."""
    return 100.0 - float(percent)


def temperature_status(value: Any, source: str = "temperature status") -> int:
    """One joint's temperature status: an integer 0..3 (an integral float is accepted)."""
    x = _number(source, value)
    if x != int(x):
        raise Rejected(source, value, "temperature status must be an integer")
    s = int(x)
    if s not in TEMPERATURE_TO_NEED:
        raise Rejected(source, value, "temperature status outside 0..3")
    return s


def need_from_status(status: int) -> float:
    """The rest drive (the thesis's NRes) from the hottest joint's temperature status: Table 4.6."""
    return TEMPERATURE_TO_NEED[status]


def max_temperature_status(values: Mapping[str, Any]) -> tuple[int | None, list[Rejected]]:
    """Max status over the joints whose value is valid, and the rejections of the others."""
    best, bad = None, []
    for joint, v in values.items():
        try:
            s = temperature_status(v, temperature_key(joint))
        except Rejected as r:
            bad.append(r)
            continue
        best = s if best is None else max(best, s)
    return best, bad


def plugged(value: Any, source: str = PLUGGED_KEY) -> bool:
    if isinstance(value, bool):
        return value
    if isinstance(value, (int, float)) and value in (0, 1):
        return bool(value)
    raise Rejected(source, value, "expected a bool")


# -- feedback ---------------------------------------------------------------------
def touch_feedback(value: Any, source: str = "touch") -> int:
    """+1 on a touch (1.0), 0 on the release (0.0)."""
    x = _number(source, value)
    if x not in (0.0, 1.0):
        raise Rejected(source, value, "touch value must be 0.0 or 1.0")
    return 1 if x == 1.0 else 0


# Levels of EmotionRecognized are integers on a scale that depends on the NAOqi version
# (ALVoiceEmotionAnalysis overview, "Emotion levels ... Scores are integers between 0 and N"):
# http://doc.aldebaran.com/2-1/naoqi/audio/alvoiceemotionanalysis.html and .../2-4/...: 0..5;
# http://doc.aldebaran.com/2-5/naoqi/audio/alvoiceemotionanalysis.html and .../2-8/...: 0..10.
# 2.9 has no page of its own: it keeps the 2.8 scale here (docs/PEPPER.md says so).
EMOTION_SCALES = {"2.1": 5, "2.3": 5, "2.4": 5, "2.5": 10, "2.7": 10, "2.8": 10, "2.9": 10}
EMOTION_SHAPE = "[[matched index, matched level], [calm, anger, joy, sorrow, laughter], excitement]"
DEFAULT_NAOQI = "2.5"  # the scale read until the robot says otherwise (and anger_threshold's with "auto")
AUTO_NAOQI = "auto"  # config / parameter value: ask the robot (ALSystem.systemVersion)


def emotion_scale(version: str) -> int:
    """The top of the emotion levels' scale for a NAOqi version ("2.5", "2.5.5.5", ...)."""
    key = naoqi_release(version)
    if key not in EMOTION_SCALES:
        raise ValueError(f"unknown NAOqi version {version!r} (known: {', '.join(EMOTION_SCALES)})")
    return EMOTION_SCALES[key]


def naoqi_release(version: str) -> str:
    """ "2.5.5.5" -> "2.5" (ALSystem.systemVersion answers the full version string)."""
    return ".".join(str(version).strip().split(".")[:2])


def _level(source: str, value: Any, whole: Any, what: str, top: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise Rejected(source, whole, f"{what} must be an integer, got {type(value).__name__}")
    if not math.isfinite(value) or value != int(value):
        raise Rejected(source, whole, f"{what} must be an integer 0..{top} (documented scale)")
    if not 0 <= value <= top:
        raise Rejected(source, whole, f"{what} {value:g} outside 0..{top} (documented scale)")
    return int(value)


def emotion_levels(value: Any, scale: int = 10, source: str = EMOTION_EVENT) -> dict:
    """A documented EmotionRecognized value -> {"matched": (index, level), "levels": {emotion: level},
    "excitement": level}; anything else raises Rejected."""
    if not isinstance(value, (list, tuple)) or len(value) != 3:
        raise Rejected(source, value, f"expected {EMOTION_SHAPE}")
    matched, levels, excitement = value
    if not isinstance(matched, (list, tuple)) or len(matched) != 2:
        raise Rejected(source, value, "expected [matched index, matched level] first")
    index = _level(source, matched[0], value, "matched index", len(EMOTIONS) - 1)  # 0 unknown .. 4 sorrow
    level = _level(source, matched[1], value, "matched level", scale)
    if not isinstance(levels, (list, tuple)) or len(levels) != len(EMOTIONS):
        raise Rejected(source, value, "emotion levels must be [calm, anger, joy, sorrow, laughter]")
    named = {e: _level(source, v, value, f"{e} level", scale) for e, v in zip(EMOTIONS, levels)}
    if isinstance(excitement, bool) or not isinstance(excitement, (int, float)) or not math.isfinite(excitement) \
            or excitement < 0:
        raise Rejected(source, value, "excitement must be a non-negative number")
    return {"matched": (index, level), "levels": named, "excitement": excitement}


def anger_level(value: Any, scale: int = 10, source: str = EMOTION_EVENT) -> int:
    """The anger level (``levels[1]``) of a documented EmotionRecognized value."""
    return emotion_levels(value, scale, source)["levels"]["anger"]


def emotion_feedback(value: Any, threshold: float, scale: int = 10, source: str = EMOTION_EVENT) -> int:
    """-1 when the anger level is above ``threshold`` (on the same 0..scale), else 0."""
    return -1 if anger_level(value, scale, source) > threshold else 0


def recognized_phrases(value: Any, min_confidence: float, source: str = WORD_EVENT) -> list[str]:
    """Phrases of a WordRecognized value at or above ``min_confidence``, best first."""
    if not isinstance(value, (list, tuple)) or len(value) % 2:
        raise Rejected(source, value, "expected [phrase, confidence, ...]")
    out = []
    for i in range(0, len(value), 2):
        phrase, conf = value[i], value[i + 1]
        if not isinstance(phrase, str):
            raise Rejected(source, value, f"phrase {i // 2} is not a string")
        c = _number(source, conf)
        if not 0.0 <= c <= 1.0:
            raise Rejected(source, value, "confidence outside 0..1")
        phrase = phrase.strip()
        if phrase and c >= min_confidence:
            out.append(phrase)
    return out


def normalize(phrase: str) -> str:
    return " ".join(phrase.lower().replace("<...>", " ").split())


class WordMap:
    """Spoken phrases -> proposals (action names) or keywords.

    A phrase that is an action name (case-insensitive) or listed under ``proposals`` in the
    config becomes a proposal, but only for actions the scenario knows; any other phrase is
    a keyword, mapped through ``keywords`` when listed there and passed through otherwise.
    """

    def __init__(self, actions: Iterable[str], proposals: Mapping[str, str] | None = None,
                 keywords: Mapping[str, str] | None = None):
        self.actions = tuple(actions)
        known = {a.lower(): a for a in self.actions}
        self.proposals = dict(known)
        for phrase, act in (proposals or {}).items():
            if act not in self.actions:
                raise ValueError(f"proposal phrase {phrase!r} names unknown action {act!r}; known: {', '.join(self.actions)}")
            self.proposals[normalize(phrase)] = act
        self.keywords = {normalize(k): v for k, v in (keywords or {}).items()}

    def classify(self, phrase: str) -> tuple[str, str]:
        """("proposal", action) or ("keyword", symbol)."""
        p = normalize(phrase)
        if p in self.proposals:
            return "proposal", self.proposals[p]
        return "keyword", self.keywords.get(p, p)


# -- presence ---------------------------------------------------------------------
def _id_list(source: str, value: Any) -> list:
    if value is None:
        return []
    if not isinstance(value, (list, tuple)):
        raise Rejected(source, value, "expected a list of person ids")
    for v in value:
        if isinstance(v, bool) or not isinstance(v, (int, float, str)):
            raise Rejected(source, value, "person ids must be numbers or strings")
    return list(value)


def relation_from_zones(zone1: Any, zone2: Any, zone3: Any, people: Any = None) -> str:
    """near when someone is in engagement zone 1, far when in zone 2 or 3 (or only seen), else absent."""
    z1 = _id_list(ZONE_KEYS[0], zone1)
    z2 = _id_list(ZONE_KEYS[1], zone2)
    z3 = _id_list(ZONE_KEYS[2], zone3)
    seen = _id_list(PEOPLE_KEY, people)
    if z1:
        return "near"
    if z2 or z3 or seen:
        return "far"
    return "absent"


def presence_of(relation: str) -> str:
    return "absent" if relation == "absent" else "present"


def relative_move(here: Sequence[float], there: Sequence[float]) -> tuple[float, float]:
    """Displacement from place ``here`` to place ``there``; the robot keeps its heading,
    so the map frame and the robot frame differ only by a translation."""
    return (float(there[0]) - float(here[0]), float(there[1]) - float(here[1]))

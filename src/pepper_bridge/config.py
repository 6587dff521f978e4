"""The bridge's settings: where to connect, the places, the phrases, the word map (no qi import).

The data part (places, phrases, words, thresholds) lives in a JSON file shared with the
stand-in robot; ``scripts/pepper.json`` is the default. Connection settings are arguments.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

SCHEMA = "homeo-pepper-config"
VERSION = 1
DEFAULT_URL = "tcp://127.0.0.1:9559"
SCRIPTS_DIR = Path(__file__).resolve().parent / "scripts"
DEVICE_ACTIONS = ("Play", "Stop", "LightOn", "LightOff")


def default_config_path() -> Path:
    return SCRIPTS_DIR / "pepper.json"


class ConfigError(ValueError):
    """A config file that cannot be used; the message says where and why."""


@dataclass
class PepperConfig:
    """What the bridge and the stand-in share (see ``scripts/pepper.json``)."""

    places: dict  # location name -> (x, y) in metres, map frame
    start_location: str
    navigation: str  # "ALNavigation" (navigateTo) or "ALMotion" (moveTo)
    speech: dict  # chat: [phrases], stay / attach / detach: phrase
    devices: dict  # action -> {"device", "command", "say"}
    anger_threshold: float = 0.5
    word_confidence: float = 0.4
    proposals: dict = field(default_factory=dict)
    keywords: dict = field(default_factory=dict)
    gesture_event: str = "PepperBridge/Gesture"
    movement_event: str = "PepperBridge/Movement"
    intention_cues: dict = field(default_factory=dict)
    source: str = "<memory>"

    def phrase_actions(self) -> dict[str, str]:
        """Every phrase the robot may say -> the action it belongs to (how a user recognises it)."""
        out = {p: "Chat" for p in self.speech["chat"]}
        for act in ("stay", "attach", "detach"):
            if self.speech.get(act):
                out[self.speech[act]] = act.capitalize()
        for act, d in self.devices.items():
            if d.get("say"):
                out[d["say"]] = act
        return out

    def place_at(self, x: float, y: float, tol: float = 0.05) -> str | None:
        for name, (px, py) in self.places.items():
            if math.hypot(px - x, py - y) <= tol:
                return name
        return None


def load_config(path: str | Path | None = None, actions: tuple | None = None) -> PepperConfig:
    p = Path(path) if path is not None else default_config_path()
    try:
        raw = json.loads(p.read_text())
    except FileNotFoundError:
        raise ConfigError(f"config file not found: {p}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"cannot read config {p}: {exc}") from None
    except json.JSONDecodeError as exc:
        raise ConfigError(f"{p}: not valid JSON (line {exc.lineno}: {exc.msg})") from None
    return config_from_dict(raw, str(p), actions)


def config_from_dict(raw: Any, source: str = "<memory>", actions: tuple | None = None) -> PepperConfig:
    def fail(msg):
        raise ConfigError(f"{source}: {msg}")

    if not isinstance(raw, dict) or raw.get("schema") != SCHEMA:
        fail(f"'schema' must be {SCHEMA!r}")
    if raw.get("version") != VERSION:
        fail(f"unsupported version {raw.get('version')!r} (this program reads {VERSION})")
    places = raw.get("places")
    if not isinstance(places, dict) or not places:
        fail("'places' must map location names to [x, y]")
    pl = {}
    for k, v in places.items():
        if (not isinstance(v, list) or len(v) != 2
                or not all(isinstance(c, (int, float)) and not isinstance(c, bool) and math.isfinite(c) for c in v)):
            fail(f"place {k!r} must be [x, y] in metres")
        pl[k] = (float(v[0]), float(v[1]))
    start = raw.get("start_location")
    if start not in pl:
        fail(f"start_location {start!r} is not one of the places {list(pl)}")
    nav = raw.get("navigation", "ALNavigation")
    if nav not in ("ALNavigation", "ALMotion"):
        fail("navigation must be 'ALNavigation' or 'ALMotion'")
    speech = raw.get("speech")
    if not isinstance(speech, dict) or not isinstance(speech.get("chat"), list) or not speech["chat"] \
            or not all(isinstance(s, str) and s for s in speech["chat"]):
        fail("speech.chat must be a non-empty list of phrases")
    for k in ("stay", "attach", "detach"):
        if not isinstance(speech.get(k, ""), str):
            fail(f"speech.{k} must be a phrase")
    devices = raw.get("devices", {})
    if not isinstance(devices, dict):
        fail("'devices' must be an object")
    for act, d in devices.items():
        if not isinstance(d, dict) or not isinstance(d.get("device"), str) or not isinstance(d.get("command"), str):
            fail(f"devices.{act} needs 'device' and 'command'")
        if not isinstance(d.get("say", ""), str):
            fail(f"devices.{act}.say must be a phrase")
    for k in ("anger_threshold", "word_confidence"):
        v = raw.get(k, 0.5)
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not 0.0 <= v <= 1.0:
            fail(f"{k} must be a number in [0, 1]")
    for k in ("proposals", "keywords"):
        m = raw.get(k, {})
        if not isinstance(m, dict) or not all(isinstance(a, str) and isinstance(b, str) for a, b in m.items()):
            fail(f"'{k}' must map phrases to names")
    if actions is not None:
        for phrase, act in raw.get("proposals", {}).items():
            if act not in actions:
                fail(f"proposal {phrase!r} names unknown action {act!r}")
        for act in devices:
            if act not in actions:
                fail(f"device action {act!r} is not an action of the scenario")
        for loc in pl:
            if f"MoveTo{loc}" not in actions:
                fail(f"place {loc!r} has no MoveTo{loc} action in the scenario")
    owner: dict = {}
    pairs = [(p, "Chat") for p in speech["chat"]] + [(speech.get(k, ""), k) for k in ("stay", "attach", "detach")] \
        + [(d.get("say", ""), a) for a, d in devices.items()]
    for phrase, act in pairs:
        if phrase and owner.setdefault(phrase, act) != act:
            fail(f"phrase {phrase!r} belongs to two actions ({owner[phrase]}, {act})")
    cues = raw.get("intention_cues", {})
    if not isinstance(cues, dict):
        fail("'intention_cues' must be an object")
    cues = {k: v for k, v in cues.items() if k != "description"}
    return PepperConfig(
        places=pl, start_location=start, navigation=nav, speech=dict(speech), devices=dict(devices),
        anger_threshold=float(raw.get("anger_threshold", 0.5)), word_confidence=float(raw.get("word_confidence", 0.4)),
        proposals=dict(raw.get("proposals", {})), keywords=dict(raw.get("keywords", {})),
        gesture_event=str(raw.get("gesture_event", "PepperBridge/Gesture")),
        movement_event=str(raw.get("movement_event", "PepperBridge/Movement")),
        intention_cues=dict(cues), source=source)


@dataclass
class LinkSettings:
    """How to reach the robot and how hard to try."""

    url: str = DEFAULT_URL
    user: str | None = None  # NAOqi 2.9 tcps:// credentials
    password: str | None = None
    connect_timeout: float = 5.0
    backoff_initial: float = 0.2
    backoff_max: float = 10.0
    backoff_factor: float = 2.0
    poll_period: float = 0.1  # polling of event keys where ALMemory.subscriber is refused
    battery_source: str = "memory"  # "memory" (0..1 fraction key) or "albattery" (percent)

"""The bridge's settings: where to connect, and what the scenario's names mean on the robot (no qi import).

The data part lives in a JSON file shared with the stand-in robot (``scripts/pepper.json`` is
the default): the places, which drive the battery and the temperature status are read into
(Section 4.3.1, Table 4.6), which object variable the plug sensor reads, what each action of the
scenario does on the robot (move to a place, rest, say a phrase, command a device, set object
states), and how spoken words map to proposals and keywords. The code knows none of those names;
:func:`check_scenario` checks that every name of the file exists in the scenario.
Connection settings are arguments (:class:`LinkSettings`).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .mapping import AUTO_NAOQI, DEFAULT_NAOQI, emotion_scale

SCHEMA = "homeo-pepper-config"
VERSION = 3  # 3: anger_threshold on the robot's emotion scale (naoqi_version), speech language and words
DEFAULT_URL = "tcp://127.0.0.1:9559"
SCRIPTS_DIR = Path(__file__).resolve().parent / "scripts"
NAVIGATION = ("ALNavigation", "ALMotion")
ACTION_KEYS = ("move", "rest", "say", "device", "command", "set")


def default_config_path() -> Path:
    return SCRIPTS_DIR / "pepper.json"


class ConfigError(ValueError):
    """A config file that cannot be used; the message names the file and the key, on one line
    (a key or value quoted from the file may hold a line break: it is shown escaped)."""

    def __init__(self, message: str):
        super().__init__(str(message).replace("\r", "\\r").replace("\n", "\\n"))


@dataclass(frozen=True)
class RobotAction:
    """What one scenario action does on the robot (the ``actions`` entries of the config)."""

    name: str
    move: str | None = None  # a place: navigate there
    rest: bool = False  # ALMotion.rest
    say: tuple = ()  # phrases, taking turns
    device: str | None = None  # a device command goes out on homeo/device
    command: str | None = None
    set: dict = field(default_factory=dict)  # "object.variable" -> value the bridge believes afterwards


@dataclass
class PepperConfig:
    """What the bridge and the stand-in share (see ``scripts/pepper.json``)."""

    places: dict  # location name -> (x, y) in metres, map frame
    start_location: str
    navigation: str  # "ALNavigation" (navigateTo) or "ALMotion" (moveTo)
    actions: dict  # action name -> RobotAction
    battery_drive: str  # the drive read from the battery (100 - percent)
    temperature_drive: str  # the drive read from the joints' temperature status (Table 4.6)
    plug: dict | None = None  # {"variable": "object.variable", "plugged": value, "unplugged": value}
    anger_threshold: float = 5.0  # anger level above this is a scolding, on the scale of naoqi_version (auto: 2.5's)
    word_confidence: float = 0.4
    naoqi_version: str = AUTO_NAOQI  # "auto": ask the robot (ALSystem.systemVersion); a version overrides it
    speech_language: str = "English"  # ALSpeechRecognition.setLanguage ('' = leave the robot's)
    proposals: dict = field(default_factory=dict)
    keywords: dict = field(default_factory=dict)
    gesture_event: str = "PepperBridge/Gesture"
    movement_event: str = "PepperBridge/Movement"
    intention_cues: dict = field(default_factory=dict)
    source: str = "<memory>"
    robot_version: str | None = None  # what the robot reported (ALSystem.systemVersion), when naoqi_version is auto

    @property
    def version(self) -> str:
        """The NAOqi version whose documented formats are read: the configured one, else the robot's,
        else (auto, not asked yet or not understood) the default."""
        if self.naoqi_version != AUTO_NAOQI:
            return self.naoqi_version
        return self.robot_version or DEFAULT_NAOQI

    @property
    def emotion_scale(self) -> int:
        return emotion_scale(self.version)

    @property
    def threshold_scale(self) -> int:
        """The scale ``anger_threshold`` is written on: the configured version's (auto: the default's)."""
        return emotion_scale(DEFAULT_NAOQI if self.naoqi_version == AUTO_NAOQI else self.naoqi_version)

    @property
    def anger_level(self) -> float:
        """The threshold on the robot's own scale (a 5 of 10 is a 2.5 of 5 on a NAOqi 2.4 robot)."""
        return self.anger_threshold * self.emotion_scale / self.threshold_scale

    def phrase_actions(self) -> dict[str, str]:
        """Every phrase the robot may say -> the action it belongs to (how a user recognises it)."""
        return {p: a.name for a in self.actions.values() for p in a.say}

    def move_action(self, place: str | None) -> str | None:
        """The action that moves the robot to ``place`` (None: none)."""
        return next((a.name for a in self.actions.values() if a.move is not None and a.move == place), None)

    def rest_action(self) -> str | None:
        return next((a.name for a in self.actions.values() if a.rest), None)

    def plug_actions(self) -> dict[str, bool]:
        """Actions that ask for the plug: True to be plugged in, False to be unplugged."""
        if not self.plug:
            return {}
        var = self.plug["variable"]
        return {a.name: a.set[var] == self.plug["plugged"] for a in self.actions.values() if var in a.set}

    def place_at(self, x: float, y: float, tol: float = 0.05) -> str | None:
        for name, (px, py) in self.places.items():
            if math.hypot(px - x, py - y) <= tol:
                return name
        return None


def load_config(path: str | Path | None = None, scenario=None) -> PepperConfig:
    """Read and check a config file; with ``scenario`` also that its names exist there."""
    from homeo_decision.jsonfile import read

    p = Path(path) if path is not None else default_config_path()
    cfg = config_from_dict(read(p, ConfigError, "config"), str(p))
    if scenario is not None:
        check_scenario(cfg, scenario)
    return cfg


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def config_from_dict(raw: Any, source: str = "<memory>", scenario=None) -> PepperConfig:
    def fail(key, msg):
        raise ConfigError(f"{source}: {key}: {msg}")

    if not isinstance(raw, dict) or raw.get("schema") != SCHEMA:
        fail("schema", f"must be {SCHEMA!r}")
    if raw.get("version") != VERSION:
        hint = " (version 2 read voice anger on 0..1; version 3 reads it on NAOqi's 0..10 scale: see docs/PEPPER.md)" \
            if raw.get("version") == 2 else ""
        fail("version", f"unsupported version {raw.get('version')!r} (this program reads {VERSION}){hint}")
    places = raw.get("places")
    if not isinstance(places, dict) or not places:
        fail("places", "must map location names to [x, y]")
    pl = {}
    for k, v in places.items():
        if not isinstance(v, list) or len(v) != 2 or not all(_is_number(c) for c in v):
            fail(f"places.{k}", "must be [x, y] in metres")
        pl[k] = (float(v[0]), float(v[1]))
    start = raw.get("start_location")
    if not isinstance(start, str) or start not in pl:
        fail("start_location", f"{start!r} is not one of the places {list(pl)}")
    nav = raw.get("navigation", NAVIGATION[0])
    if nav not in NAVIGATION:
        fail("navigation", f"must be one of {', '.join(NAVIGATION)}")
    body = raw.get("body")
    if not isinstance(body, dict) or not all(isinstance(body.get(k), str) and body[k] for k in ("battery", "temperature")):
        fail("body", "must name the drive read from the battery and the one read from the temperature "
                     "({\"battery\": DRIVE, \"temperature\": DRIVE})")
    if body["battery"] == body["temperature"]:
        fail("body", "the battery and the temperature must be read into two different drives")
    plug = raw.get("plug")
    if plug is not None:
        if not isinstance(plug, dict) or not all(isinstance(plug.get(k), str) and plug[k]
                                                 for k in ("variable", "plugged", "unplugged")):
            fail("plug", "must be {\"variable\": \"object.variable\", \"plugged\": VALUE, \"unplugged\": VALUE}")
        if "." not in plug["variable"]:
            fail("plug.variable", f"{plug['variable']!r} is not object.variable")
        plug = {k: plug[k] for k in ("variable", "plugged", "unplugged")}
    acts = raw.get("actions")
    if not isinstance(acts, dict) or not acts:
        fail("actions", "must map the scenario's actions to what the robot does")
    actions = {name: _action(name, spec, pl, fail) for name, spec in acts.items()}
    owner: dict = {}
    for a in actions.values():
        for phrase in a.say:
            if owner.setdefault(phrase, a.name) != a.name:
                fail(f"actions.{a.name}.say", f"phrase {phrase!r} belongs to two actions ({owner[phrase]}, {a.name})")
    version = raw.get("naoqi_version", AUTO_NAOQI)
    try:
        scale = emotion_scale(DEFAULT_NAOQI if version == AUTO_NAOQI else version)
    except ValueError as exc:
        fail("naoqi_version", f"{exc} or {AUTO_NAOQI!r} (ask the robot)")
    v = raw.get("anger_threshold", 5.0)
    if not _is_number(v) or not 0.0 <= v < scale:
        on = f"NAOqi {version} reports anger 0..{scale}" if version != AUTO_NAOQI else \
            f"with naoqi_version {AUTO_NAOQI!r} it is on NAOqi {DEFAULT_NAOQI}'s 0..{scale}, rescaled to the robot's"
        fail("anger_threshold", f"must be a number in [0, {scale}) ({on})")
    if not isinstance(raw.get("speech_language", "English"), str):
        fail("speech_language", "must be a language name as ALSpeechRecognition.setLanguage takes it (e.g. English)")
    v = raw.get("word_confidence", 0.4)
    if not _is_number(v) or not 0.0 <= v <= 1.0:
        fail("word_confidence", "must be a number in [0, 1]")
    for k in ("proposals", "keywords"):
        m = raw.get(k, {})
        if not isinstance(m, dict) or not all(isinstance(a, str) and isinstance(b, str) for a, b in m.items()):
            fail(k, "must map phrases to names")
    for k in ("gesture_event", "movement_event"):
        if not isinstance(raw.get(k, "x"), str) or not raw.get(k, "x"):
            fail(k, "must be an ALMemory event name")
    cues = raw.get("intention_cues", {})
    if not isinstance(cues, dict):
        fail("intention_cues", "must be an object")
    cues = {k: v for k, v in cues.items() if k != "description"}
    for k, m in cues.items():
        if k not in ("keywords", "gestures") or not isinstance(m, dict) \
                or not all(isinstance(a, str) and isinstance(b, str) for a, b in m.items()):
            fail(f"intention_cues.{k}", "only 'keywords' and 'gestures', each mapping symbols to intentions")
    cfg = PepperConfig(
        places=pl, start_location=start, navigation=nav, actions=actions, battery_drive=body["battery"],
        temperature_drive=body["temperature"], plug=plug,
        anger_threshold=float(raw.get("anger_threshold", 5.0)), word_confidence=float(raw.get("word_confidence", 0.4)),
        naoqi_version=str(version), speech_language=str(raw.get("speech_language", "English")),
        proposals=dict(raw.get("proposals", {})), keywords=dict(raw.get("keywords", {})),
        gesture_event=str(raw.get("gesture_event", "PepperBridge/Gesture")),
        movement_event=str(raw.get("movement_event", "PepperBridge/Movement")),
        intention_cues=dict(cues), source=source)
    if scenario is not None:
        check_scenario(cfg, scenario)
    return cfg


def _action(name: str, spec: Any, places: dict, fail) -> RobotAction:
    key = f"actions.{name}"
    if not isinstance(spec, dict):
        fail(key, "must be an object with move / rest / say / device + command / set")
    unknown = sorted(set(spec) - set(ACTION_KEYS))
    if unknown:
        fail(f"{key}.{unknown[0]}", f"unknown key (known: {', '.join(ACTION_KEYS)})")
    move = spec.get("move")
    if move is not None and (not isinstance(move, str) or move not in places):
        fail(f"{key}.move", f"{move!r} is not one of the places {list(places)}")
    rest = spec.get("rest", False)
    if not isinstance(rest, bool):
        fail(f"{key}.rest", "must be true or false")
    say = spec.get("say", [])
    say = [say] if isinstance(say, str) else say
    if not isinstance(say, list) or not all(isinstance(s, str) and s for s in say):
        fail(f"{key}.say", "must be a phrase or a list of phrases")
    device, command = spec.get("device"), spec.get("command")
    if (device is None) != (command is None) or not all(v is None or isinstance(v, str) and v for v in (device, command)):
        fail(f"{key}.device", "'device' and 'command' go together, both names")
    sets = spec.get("set", {})
    if not isinstance(sets, dict) or not all(isinstance(k, str) and "." in k and isinstance(v, str) for k, v in sets.items()):
        fail(f"{key}.set", "must map \"object.variable\" to a value")
    if move is not None and (rest or device):
        fail(key, "a move cannot also rest or command a device")
    return RobotAction(name, move, rest, tuple(say), device, command, dict(sets))


def check_scenario(cfg: PepperConfig, sc) -> None:
    """Every name of the config exists in the scenario ``sc``, and every action of ``sc`` is configured."""
    def fail(key, msg):
        raise ConfigError(f"{cfg.source}: {key}: {msg}")

    drives = {d.name: d for d in sc.drives}
    for key, name in (("body.battery", cfg.battery_drive), ("body.temperature", cfg.temperature_drive)):
        if name not in drives:
            fail(key, f"{name!r} is not a drive of the scenario ({', '.join(drives)})")
        if drives[name].source != "body":
            fail(key, f"{name!r} is not a body drive of the scenario")
    unread = [d.name for d in sc.drives if d.source == "body" and d.name not in (cfg.battery_drive, cfg.temperature_drive)]
    if unread:
        fail("body", f"the robot reads no value for the body drive {unread[0]!r}")
    for loc in cfg.places:
        if loc not in sc.locations:
            fail(f"places.{loc}", f"not a location of the scenario ({', '.join(sc.locations)})")

    def check_var(key, var, *values):
        obj, _, v = var.partition(".")
        allowed = (sc.objects.get(obj) or {}).get("variables", {}).get(v)
        if allowed is None:
            fail(key, f"{var!r} is not an object variable of the scenario")
        for val in values:
            if val not in allowed:
                fail(key, f"{val!r} is not a value of {var} ({', '.join(allowed)})")

    if cfg.plug:
        check_var("plug", cfg.plug["variable"], cfg.plug["plugged"], cfg.plug["unplugged"])
    for name, a in cfg.actions.items():
        if name not in sc.action_names:
            fail(f"actions.{name}", "not an action of the scenario")
        for var, val in a.set.items():
            check_var(f"actions.{name}.set", var, val)
    missing = [a for a in sc.action_names if a not in cfg.actions]
    if missing:
        fail("actions", f"the scenario's action {missing[0]!r} is not configured")
    for phrase, act in cfg.proposals.items():
        if act not in sc.action_names:
            fail(f"proposals.{phrase}", f"{act!r} is not an action of the scenario")
    intentions = sc.intention_names[1:]
    for kind, m in cfg.intention_cues.items():
        for sym, it in m.items():
            if it not in intentions:
                fail(f"intention_cues.{kind}.{sym}", f"{it!r} is not an intention of the scenario")


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
    call_timeout: float = 3.0  # a read (or subscribe) the robot does not answer in this time fails
    action_timeout: float = 60.0  # a move, rest or speech call fails after this
    heartbeat_period: float = 1.0  # how often the robot is asked something when nothing else is going on
    heartbeat_timeout: float = 2.0  # no answer for this long, connection open: the robot is unresponsive
    battery_source: str = "memory"  # "memory" (0..1 fraction key) or "albattery" (percent)

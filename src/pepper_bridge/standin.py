"""A stand-in Pepper: a ``qi.Session`` on loopback offering NAOqi's services and memory keys.

The bridge reaches it exactly as it reaches a real Pepper (``qi.Session().connect(url)``).
Services (NAOqi method names):

- ``ALMemory``: getData, getListData, insertData, raiseEvent, subscriber(key) (an object
  with a ``signal``), declareEvent, getDataList, getEventList.
- ``ALBattery``: getBatteryCharge (percent).
- ``ALMotion``: wakeUp, rest, robotIsWakeUp, moveTo(x, y, theta).
- ``ALNavigation``: navigateTo(x, y).
- ``ALTextToSpeech``: say(text).
- ``ALSpeechRecognition``: setLanguage, setVocabulary, pause, subscribe, unsubscribe.
- ``ALVoiceEmotionAnalysis``: subscribe, unsubscribe.
- ``ALSystem``: systemVersion (``naoqi_version``, e.g. "2.5.5.5"; the user's voices are on its scale), robotName.
- ``HomeoStandin`` (not NAOqi; for tests and the CLI): calls, clearCalls, inject, clearInjections,
  setBatteryOverride, dropFor, freezeFor, state, userLog.

The simulated body (per simulated second; every motion / speech / rest call also lasts
``action_seconds`` simulated seconds, so a run at ``time_scale`` 0 is reproducible):
battery drains ``drain`` %/s awake (``drain_rest`` at rest) and ``drain_per_m`` % per metre
moved, charges ``charge`` %/s while plugged (the scripted user plugs it in when asked for
help at the charger; moving away unplugs it); heat rises ``heat_per_m`` per metre and
``heat_awake`` /s awake, falls ``cool_rest`` /s at rest; the wheel and leg joints' temperature
status is floor(heat) (0..3), the other joints' floor(heat / 2).

The scripted user is a person (``standin_person.StandinPerson``) standing in front of the robot's spot at
the user's place; the script may have them walk up to the robot wherever it is (``"walks": "to_robot"``)
and back (``"home"``). The engagement zones and the people list are computed from where the person
stands, as ALEngagementZones and ALPeoplePerception document them (``ALEngagementZones.getFirstLimitDistance``,
``getSecondLimitDistance``, ``getLimitAngle`` and ``computeEngagementZone(x, y, z)`` answer with the same limits).

Every call received is recorded (``calls()``), memory keys can be forced to wrong values
(``inject``), the robot can disappear and come back on the same URL (``drop`` /
``restart``), and it can freeze: stop answering with its connection open (``freeze_for``:
every NAOqi call and event waits until it thaws; ``HomeoStandin`` still answers).
:class:`NotNaoqiPort` is a loopback port that accepts connections but does not speak qi.
"""

from __future__ import annotations

import argparse
import collections
import math
import os
import signal
import sys
import threading
import time
from dataclasses import dataclass
from typing import Any

import qi

from homeo_decision.rng import component_rng
from homeo_msgs_py.cli_args import die_with_parent

from .config import PepperConfig, load_config
from .mapping import (AUTO_NAOQI, BATTERY_KEY, EMOTION_EVENT, PEOPLE_KEY, PEPPER_JOINTS, PLUGGED_KEY, TOUCH_EVENTS,
                      WORD_EVENT, ZONE_KEYS, emotion_scale, relation_from_zones, temperature_key)
from . import naoqi_link
from .standin_person import PEPPER_LIFE_LIMITS, StandinPerson, ZoneLimits, engagement_zone
from .user import ScriptedUser, load_script, timed_entry_emits

MOTION_JOINTS = ("HipRoll", "HipPitch", "KneePitch", "WheelFL", "WheelFR", "WheelB")
STANDIN_NAOQI = "2.5.5.5"  # what ALSystem.systemVersion answers when neither the config nor the caller fixes it


@dataclass
class BodyParams:
    action_seconds: float = 10.0
    drain: float = 0.2
    drain_rest: float = 0.05
    drain_per_m: float = 0.5
    charge: float = 2.0
    heat_per_m: float = 0.12
    heat_awake: float = 0.005
    cool_rest: float = 0.05


class _Sub:
    """What ``ALMemory.subscriber(key)`` returns: an object with a ``signal``."""

    def __init__(self):
        self.signal = qi.Signal("m")


class StandinRobot:
    """The robot's state and the qi session that serves it (see the module docstring)."""

    def __init__(self, config: PepperConfig | None = None, script: dict | None = None, *, seed: int = 0,
                 battery: float | None = None, time_scale: float = 1.0, listen: str = "tcp://127.0.0.1:0",
                 refuse_subscriber: bool = False, body: BodyParams | None = None, desired: dict | None = None,
                 scenario=None, clock=time.monotonic, naoqi_version: str | None = None,
                 zone_limits: ZoneLimits = PEPPER_LIFE_LIMITS):
        self.cfg = config or load_config()
        self.script = script or {"schema": "homeo-pepper-user", "version": 1}
        self.rng = component_rng(seed, "standin")
        self.time_scale = float(time_scale)
        self.listen_url = listen
        self.refuse_subscriber = refuse_subscriber
        self.p = body or BodyParams()
        self.clock = clock
        # the version this robot runs: its voices follow that version's documented scale
        self.naoqi_version = naoqi_version or (self.cfg.naoqi_version if self.cfg.naoqi_version != AUTO_NAOQI
                                               else STANDIN_NAOQI)
        self.emotion_scale = emotion_scale(self.naoqi_version)
        self.lock = threading.RLock()
        self._calls: collections.deque = collections.deque(maxlen=20000)
        self.data: dict[str, Any] = {}
        self.injected: dict[str, Any] = {}
        self.battery_override: Any = None
        self.subs: dict[str, _Sub] = {}
        self.events_declared: set = set()
        start = self.script.get("start", {})
        self.battery = float(battery if battery is not None else start.get("battery_percent", 80.0))
        self.heat = float(start.get("heat", 0.0))
        loc = start.get("location", self.cfg.start_location)
        self.x, self.y = self.cfg.places[loc]
        self.awake = False
        self.plugged = False
        self.moved_m = 0.0
        if scenario is None:
            from homeo_decision.scenario import load_scenario

            scenario = load_scenario()
        if desired is None:
            desired = {i.name: tuple(i.desired) for i in scenario.intentions}
        self.user_place = scenario.human_location  # the user's place (the scenario's human location)
        if self.user_place not in self.cfg.places:
            raise ValueError(f"the stand-in's person stands at the user's place {self.user_place!r}, which the "
                             f"config's places do not locate ({', '.join(self.cfg.places)})")
        self.person = StandinPerson(self.cfg.places[self.user_place], zone_limits)
        plug_obj = self.cfg.plug["variable"].partition(".")[0] if self.cfg.plug else None
        self.user = ScriptedUser(self.script, desired, self.cfg.gesture_event, self.cfg.movement_event,
                                 plug_actions=self.cfg.plug_actions(),
                                 plug_place=(scenario.objects.get(plug_obj) or {}).get("location"),
                                 emotion_scale=self.emotion_scale,
                                 spoken={act: phrase for phrase, act in reversed(list(self.cfg.proposals.items()))})
        self.phrases = self.cfg.phrase_actions()
        self._last = clock()
        self.session: qi.Session | None = None
        self.url: str | None = None
        self._stop = threading.Event()
        self._thawed = threading.Event()  # cleared while frozen
        self._thawed.set()
        self._timed_thread: threading.Thread | None = None
        self._item_applied = -1  # the user interaction whose "robot" body settings were applied
        self._faulted: set = set()  # user interactions whose drop / freeze has happened
        self._services = self._make_services()

    # -- session lifecycle ----------------------------------------------------------
    def start(self) -> str:
        with self.lock:
            self._advance()
            self._publish()
        self._open(self.listen_url)
        return self.url

    def _open(self, url: str) -> None:
        s = qi.Session()
        s.listenStandalone(url)
        eps = [e for e in s.endpoints() if e.startswith("tcp://127.0.0.1") or e.startswith("tcp://localhost")]
        self.url = eps[0] if eps else s.endpoints()[0]
        with self.lock:
            self.subs = {}
        for name, obj in self._services.items():
            s.registerService(name, obj)
        self.session = s

    def drop(self) -> None:
        """The robot disappears: the session closes, every client is disconnected."""
        s, self.session = self.session, None
        if s is not None:
            s.close()

    def restart(self) -> None:
        """The robot comes back on the same URL."""
        if self.session is None:
            self._open(self.url)

    def drop_for(self, seconds: float) -> None:
        """Drop now and come back after ``seconds`` (from another thread)."""
        self.drop()

        def back():
            if not self._stop.wait(seconds):
                self.restart()

        threading.Thread(target=back, daemon=True, name="standin-restart").start()

    def close(self) -> None:
        self._stop.set()
        self._thawed.set()  # release held calls
        self.drop()
        naoqi_link.collect_closed_session()

    # -- recording and injection ----------------------------------------------------
    def record(self, service: str, method: str, *args) -> None:
        """Every NAOqi method starts here: a frozen robot holds the call until it thaws."""
        self._thawed.wait()
        self._calls.append((service, method, list(args)))

    def freeze_for(self, seconds: float) -> None:
        """Stop answering (connection open) for ``seconds`` wall seconds; thaws by itself."""
        self._thawed.clear()
        t = threading.Timer(seconds, self._thawed.set)
        t.daemon = True
        t.start()

    @property
    def frozen(self) -> bool:
        return not self._thawed.is_set()

    def calls(self, service: str | None = None, exclude_memory_reads: bool = True) -> list:
        out = list(self._calls)
        if exclude_memory_reads:
            out = [c for c in out if not (c[0] == "ALMemory" and c[1] in ("getData", "getListData"))]
        if service is not None:
            out = [c for c in out if c[0] == service]
        return out

    def clear_calls(self) -> None:
        self._calls.clear()

    def inject(self, key: str, value: Any, raise_event: bool = False) -> None:
        """Force a memory key to ``value`` (e.g. a wrongly typed battery) until cleared."""
        with self.lock:
            self.injected[key] = value
            self.data[key] = value
        if raise_event:
            self.emit([(key, value)])

    def clear_injections(self) -> None:
        with self.lock:
            self.injected.clear()
            self.battery_override = None
            self._publish()

    # -- body -----------------------------------------------------------------------
    def _advance(self) -> None:
        now = self.clock()
        dt, self._last = (now - self._last) * self.time_scale, now
        if dt > 0:
            self._evolve(dt)

    def _evolve(self, dt: float) -> None:
        p = self.p
        if self.plugged:
            self.battery = min(100.0, self.battery + p.charge * dt)
        else:
            self.battery = max(0.0, self.battery - (p.drain if self.awake else p.drain_rest) * dt)
        if self.awake:
            self.heat = min(3.99, self.heat + p.heat_awake * dt)
        else:
            self.heat = max(0.0, self.heat - p.cool_rest * dt)

    def _act(self) -> None:
        """An action call lasts ``action_seconds`` simulated seconds."""
        self._evolve(self.p.action_seconds)

    def _move(self, dx: float, dy: float) -> None:
        d = math.hypot(dx, dy)
        if d > 1e-9 and self.plugged:
            self.plugged = False  # driving away pulls the plug
        self.x += dx
        self.y += dy
        self.moved_m += d
        self.battery = max(0.0, self.battery - self.p.drain_per_m * d)
        self.heat = min(3.99, self.heat + self.p.heat_per_m * d)
        self._act()

    @property
    def location(self) -> str | None:
        return self.cfg.place_at(self.x, self.y)

    def people(self) -> dict:
        """The people keys of ALMemory: where the person stands, seen from the robot (standin_person)."""
        return self.person.memory((self.x, self.y), self.user.present)

    def relation(self) -> str:
        """What the bridge reads from these keys (zone 1 near; 2, 3 or only tracked far; else absent)."""
        m = self.people()
        return relation_from_zones(*(m[k] for k in (*ZONE_KEYS, PEOPLE_KEY)))

    def _walk(self) -> None:
        """Lock held: where the script last asked the person to walk (to the robot, wherever it is, or home)."""
        where = self.user.take_walk()
        if where is not None:
            self.person.walk(where, (self.x, self.y))

    def statuses(self) -> dict:
        h = int(self.heat)
        return {j: min(3, h if j in MOTION_JOINTS else h // 2) for j in PEPPER_JOINTS}

    def _publish(self) -> None:
        """Body and presence into memory (injected keys keep their forced values).

        Formats (docs/PEPPER.md, "NAOqi as documented"): joint temperature status 0..3
        (http://doc.aldebaran.com/2-8/family/pepper_technical/pepper_dcm/actuator_sensor_names.html);
        EngagementZones/PeopleInZone1..3 and PeoplePerception/PeopleList: lists of person ids, the zones
        from where the person stands (``standin_person``, its pages beside each value); the battery
        charge as the bridge reads it (a 0..1 fraction; no page in the corpus confirms the range)."""
        d = self.data
        d[BATTERY_KEY] = round(self.battery / 100.0, 6)
        d[PLUGGED_KEY] = self.plugged
        for j, s in self.statuses().items():
            d[temperature_key(j)] = s
        d.update(self.people())
        d.update(self.injected)

    def state(self) -> dict:
        with self.lock:
            self._advance()
            return {"battery_percent": self.battery, "heat": self.heat, "temperature_status": max(self.statuses().values()),
                    "location": self.location, "pose": [self.x, self.y], "awake": self.awake, "plugged": self.plugged,
                    "relation": self.relation(), "user_index": self.user.index, "user_done": self.user.done}

    # -- events ---------------------------------------------------------------------
    def emit(self, emits) -> None:
        """Raise events (set the key, then fire the subscribers' signals) outside the lock."""
        self._thawed.wait()  # a frozen robot raises nothing
        fire = []
        with self.lock:
            for key, value in emits:
                self.data[key] = value
                sub = self.subs.get(key)
                if sub is not None:
                    fire.append((sub, value))
        for sub, value in fire:
            sub.signal(value)

    def raise_event(self, key: str, value: Any) -> None:
        self.emit([(key, value)])

    def _user_saw(self, action: str | None) -> list:
        """Called with the lock held: the user's reaction to a completed action (events to emit)."""
        if action is None:
            return []
        r = self.user.react(action, self.location)
        if r.plug is not None:
            self.plugged = r.plug
        self._walk()
        self._apply_item()
        self._publish()
        return r.emits

    def _apply_item(self) -> None:
        """Lock held: the current interaction's ``robot`` body settings (heat, battery_percent), once."""
        if self.user.index == self._item_applied:
            return
        self._item_applied = self.user.index
        r = (self.user.current or {}).get("robot") or {}
        if "heat" in r:
            self.heat = min(3.99, max(0.0, float(r["heat"])))
        if "battery_percent" in r:
            self.battery = min(100.0, max(0.0, float(r["battery_percent"])))

    def _script_fault(self) -> None:
        """At the start of an action: the current interaction's ``robot`` drop / freeze, once. The action is
        not performed (a robot that froze or dropped mid-call); the call raises once the robot is back."""
        with self.lock:
            r = (self.user.current or {}).get("robot") or {}
            if not self.user.started or self.user.index in self._faulted or not ({"drop", "freeze"} & set(r)):
                return
            self._faulted.add(self.user.index)
        if "freeze" in r:
            self.freeze_for(float(r["freeze"]))
            self._thawed.wait()
            raise RuntimeError("the robot froze during this call")
        threading.Timer(0.05, self.drop_for, args=(float(r["drop"]),)).start()  # not from inside the call
        self._stop.wait(1.0)
        raise RuntimeError("the robot dropped during this call")

    def start_user(self) -> None:
        with self.lock:
            if self.user.started:
                return
            emits = self.user.start()
            self._walk()
            self._apply_item()
            self._publish()
            timed = sorted(self.script.get("timed", []), key=lambda e: e["at"])
        self.emit(emits)
        if timed:
            self._timed_thread = threading.Thread(target=self._run_timed, args=(timed,), daemon=True, name="standin-user")
            self._timed_thread.start()

    def _run_timed(self, timed) -> None:
        t0 = time.monotonic()
        for e in timed:
            if self._stop.wait(max(0.0, t0 + e["at"] - time.monotonic())):
                return
            with self.lock:
                if "presence" in e:
                    self.user.present = e["presence"] == "present"
                if "walks" in e:
                    self.person.walk(e["walks"], (self.x, self.y))
                if "presence" in e or "walks" in e:
                    self._publish()
            self.emit(timed_entry_emits(e, self.cfg.gesture_event, self.cfg.movement_event, self.emotion_scale))

    # -- services -------------------------------------------------------------------
    def _make_services(self) -> dict:
        robot = self

        class ALMemory:
            @qi.bind(qi.Dynamic, [qi.String])
            def getData(self, key):
                robot.record("ALMemory", "getData", key)
                with robot.lock:
                    robot._advance()
                    robot._publish()
                    if key not in robot.data:
                        raise RuntimeError(f"ALMemory::getData: data not found: {key}")
                    return robot.data[key]

            @qi.bind(qi.Dynamic, [qi.List(qi.String)])
            def getListData(self, keys):
                robot.record("ALMemory", "getListData", list(keys))
                with robot.lock:
                    robot._advance()
                    robot._publish()
                    return [robot.data.get(k) for k in keys]

            @qi.bind(qi.Void, [qi.String, qi.Dynamic])
            def insertData(self, key, value):
                robot.record("ALMemory", "insertData", key, value)
                with robot.lock:
                    robot.data[key] = value

            @qi.bind(qi.Void, [qi.String, qi.Dynamic])
            def raiseEvent(self, key, value):
                robot.record("ALMemory", "raiseEvent", key, value)
                robot.emit([(key, value)])

            @qi.bind(qi.Void, [qi.String])
            def declareEvent(self, key):
                robot.record("ALMemory", "declareEvent", key)
                robot.events_declared.add(key)

            @qi.bind(qi.Object, [qi.String])
            def subscriber(self, key):
                robot.record("ALMemory", "subscriber", key)
                if robot.refuse_subscriber:
                    raise RuntimeError("ALMemory::subscriber: refused by this robot")
                with robot.lock:
                    sub = robot.subs.get(key)
                    if sub is None:
                        sub = robot.subs[key] = _Sub()
                    return sub

            @qi.bind(qi.List(qi.String), [qi.String])
            def getDataList(self, filt):
                robot.record("ALMemory", "getDataList", filt)
                with robot.lock:
                    robot._publish()
                    return sorted(k for k in robot.data if filt in k)

            @qi.bind(qi.List(qi.String), [])
            def getEventList(self):
                robot.record("ALMemory", "getEventList")
                return sorted(set(TOUCH_EVENTS) | {EMOTION_EVENT, WORD_EVENT, PLUGGED_KEY, robot.cfg.gesture_event,
                                                   robot.cfg.movement_event} | robot.events_declared)

        class ALBattery:
            @qi.bind(qi.Dynamic, [])
            def getBatteryCharge(self):
                robot.record("ALBattery", "getBatteryCharge")
                with robot.lock:
                    if robot.battery_override is not None:
                        return robot.battery_override
                    robot._advance()
                    return int(round(robot.battery))

        class ALMotion:
            @qi.bind(qi.Void, [])
            def wakeUp(self):
                robot.record("ALMotion", "wakeUp")
                with robot.lock:
                    robot.awake = True

            @qi.bind(qi.Void, [])
            def rest(self):
                robot.record("ALMotion", "rest")
                robot._script_fault()
                with robot.lock:
                    robot._advance()
                    robot.awake = False
                    robot._act()
                    emits = robot._user_saw(robot.cfg.rest_action())
                robot.emit(emits)

            @qi.bind(qi.Bool, [])
            def robotIsWakeUp(self):
                robot.record("ALMotion", "robotIsWakeUp")
                return robot.awake

            @qi.bind(qi.Bool, [qi.Float, qi.Float, qi.Float])
            def moveTo(self, x, y, theta):
                robot.record("ALMotion", "moveTo", x, y, theta)
                return robot._motion(x, y)

        class ALNavigation:
            @qi.bind(qi.Bool, [qi.Float, qi.Float])
            def navigateTo(self, x, y):
                robot.record("ALNavigation", "navigateTo", x, y)
                return robot._motion(x, y)

        class ALTextToSpeech:
            @qi.bind(qi.Void, [qi.String])
            def say(self, text):
                robot.record("ALTextToSpeech", "say", text)
                robot._script_fault()
                with robot.lock:
                    robot._advance()
                    emits = robot._user_saw(robot.phrases.get(text))  # e.g. plugged in when asked for help
                    robot._act()
                    robot._publish()
                robot.emit(emits)

        class ALSpeechRecognition:
            @qi.bind(qi.Void, [qi.String])
            def setLanguage(self, lang):
                robot.record("ALSpeechRecognition", "setLanguage", lang)

            @qi.bind(qi.Void, [qi.List(qi.String), qi.Bool])
            def setVocabulary(self, words, spotting):
                robot.record("ALSpeechRecognition", "setVocabulary", list(words), spotting)

            @qi.bind(qi.Void, [qi.Bool])
            def pause(self, on):
                robot.record("ALSpeechRecognition", "pause", on)

            @qi.bind(qi.Void, [qi.String])
            def subscribe(self, name):
                robot.record("ALSpeechRecognition", "subscribe", name)
                robot.start_user()  # the user starts talking once the robot listens

            @qi.bind(qi.Void, [qi.String])
            def unsubscribe(self, name):
                robot.record("ALSpeechRecognition", "unsubscribe", name)

        def extractor(service: str):
            """An extractor (ALExtractor API): subscribe / unsubscribe, each recorded."""
            class Extractor:
                @qi.bind(qi.Void, [qi.String])
                def subscribe(self, name):
                    robot.record(service, "subscribe", name)

                @qi.bind(qi.Void, [qi.String])
                def unsubscribe(self, name):
                    robot.record(service, "unsubscribe", name)

            Extractor.__name__ = service
            return Extractor

        ALPeoplePerception = extractor("ALPeoplePerception")

        class ALEngagementZones(extractor("ALEngagementZones")):  # qi serves the extractor's methods too
            """The zones' limits and computeEngagementZone(x, y, z) (a point in FRAME_ROBOT -> its zone)
            (http://doc.aldebaran.com/2-4/naoqi/peopleperception/alengagementzones-api.html)."""

            @qi.bind(qi.Float, [])
            def getFirstLimitDistance(self):
                robot.record("ALEngagementZones", "getFirstLimitDistance")
                return robot.person.limits.first

            @qi.bind(qi.Float, [])
            def getSecondLimitDistance(self):
                robot.record("ALEngagementZones", "getSecondLimitDistance")
                return robot.person.limits.second

            @qi.bind(qi.Float, [])
            def getLimitAngle(self):
                robot.record("ALEngagementZones", "getLimitAngle")
                return robot.person.limits.angle

            @qi.bind(qi.Int32, [qi.Float, qi.Float, qi.Float])
            def computeEngagementZone(self, x, y, z):
                robot.record("ALEngagementZones", "computeEngagementZone", x, y, z)
                return engagement_zone(float(x), float(y), robot.person.limits)
        # EmotionRecognized values come from user.angry_voice / calm_voice: the documented shape and
        # scale (http://doc.aldebaran.com/2-5/naoqi/audio/alvoiceemotionanalysis.html: 0..10; 2-4: 0..5)
        ALVoiceEmotionAnalysis = extractor("ALVoiceEmotionAnalysis")

        class ALSystem:  # NAOqi SDK ALSystemProxy: std::string systemVersion() "running system version"
            @qi.bind(qi.String, [])
            def systemVersion(self):
                robot.record("ALSystem", "systemVersion")
                return robot.naoqi_version

            @qi.bind(qi.String, [])
            def robotName(self):
                robot.record("ALSystem", "robotName")
                return "standin"

        class HomeoStandin:
            @qi.bind(qi.Dynamic, [])
            def calls(self):
                return [[s, m, a] for s, m, a in robot.calls()]

            @qi.bind(qi.Void, [])
            def clearCalls(self):
                robot.clear_calls()

            @qi.bind(qi.Void, [qi.String, qi.Dynamic])
            def inject(self, key, value):
                robot.inject(key, value)

            @qi.bind(qi.Void, [])
            def clearInjections(self):
                robot.clear_injections()

            @qi.bind(qi.Void, [qi.Dynamic])
            def setBatteryOverride(self, value):
                with robot.lock:
                    robot.battery_override = value

            @qi.bind(qi.Void, [qi.Float])
            def dropFor(self, seconds):
                threading.Timer(0.05, robot.drop_for, args=(seconds,)).start()

            @qi.bind(qi.Void, [qi.Float])
            def freezeFor(self, seconds):
                robot.freeze_for(seconds)

            @qi.bind(qi.Dynamic, [])
            def state(self):
                return robot.state()

            @qi.bind(qi.Dynamic, [])
            def userLog(self):
                return list(robot.user.log)

        return {"ALMemory": ALMemory(), "ALBattery": ALBattery(), "ALMotion": ALMotion(), "ALNavigation": ALNavigation(),
                "ALTextToSpeech": ALTextToSpeech(), "ALSpeechRecognition": ALSpeechRecognition(),
                "ALVoiceEmotionAnalysis": ALVoiceEmotionAnalysis(), "ALPeoplePerception": ALPeoplePerception(),
                "ALEngagementZones": ALEngagementZones(), "ALSystem": ALSystem(), "HomeoStandin": HomeoStandin()}

    def _motion(self, x: float, y: float) -> bool:
        self._script_fault()
        with self.lock:
            self._advance()
            if not self.awake:
                raise RuntimeError("ALMotion: the robot is resting; call wakeUp first")
            self._move(float(x), float(y))
            loc = self.location
            emits = self._user_saw(self.cfg.move_action(loc))
        self.emit(emits)
        return True


class NotNaoqiPort:
    """A loopback TCP port that accepts connections but is not NAOqi: ``mode`` "silent" says
    nothing, "http" answers like a web server. ``url`` is ``tcp://127.0.0.1:PORT``."""

    def __init__(self, mode: str = "silent"):
        import socket

        self.mode = mode
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(8)
        self.sock.settimeout(0.2)
        self.url = f"tcp://127.0.0.1:{self.sock.getsockname()[1]}"
        self._conns: list = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._serve, daemon=True, name="not-naoqi")
        self._thread.start()

    def _serve(self) -> None:
        import socket

        while not self._stop.is_set():
            try:
                conn, _ = self.sock.accept()
            except (socket.timeout, OSError):
                continue
            self._conns.append(conn)
            if self.mode == "http":
                try:
                    conn.sendall(b"HTTP/1.0 200 OK\r\nContent-Type: text/plain\r\n\r\nnot a robot\n")
                except OSError:
                    pass

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2.0)
        for c in self._conns:
            c.close()
        self.sock.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def _loopback_only(url: str) -> str:
    host = url.split("://", 1)[-1].rsplit(":", 1)[0]
    if host not in ("127.0.0.1", "localhost", "[::1]"):
        raise SystemExit(f"homeo-pepper-standin listens on loopback only, not {host!r}")
    return url


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="homeo-pepper-standin",
                                 description="A stand-in Pepper speaking NAOqi over libqi on loopback.")
    ap.add_argument("--listen", default="tcp://127.0.0.1:9559", help="tcp://127.0.0.1:PORT (port 0 picks one)")
    ap.add_argument("--script", help="scripted user file (see pepper_bridge.user)")
    ap.add_argument("--config", help="places/phrases file (default: the shipped scripts/pepper.json)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--battery", type=float, help="initial battery percentage (overrides the script)")
    ap.add_argument("--time-scale", type=float, default=1.0, help="simulated seconds per wall second (0 freezes time)")
    ap.add_argument("--refuse-subscriber", action="store_true", help="refuse ALMemory.subscriber (clients must poll)")
    ap.add_argument("--naoqi-version", help=f"what ALSystem.systemVersion answers; the user's voices follow its scale "
                                            f"(default: the config's naoqi_version, or {STANDIN_NAOQI} when auto)")
    a = ap.parse_args(argv)
    die_with_parent()  # started by a launcher: it ends with it
    if a.battery is not None and not 0 <= a.battery <= 100:
        ap.error("--battery must be in [0, 100]")
    if a.time_scale < 0:
        ap.error("--time-scale must be >= 0")
    done = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: done.set())
    qi.logging.setLevel(qi.logging.ERROR)  # libqi logs to stdout; the URL must be the first line
    cfg = load_config(a.config)
    script = load_script(a.script) if a.script else None
    if a.naoqi_version:
        try:
            emotion_scale(a.naoqi_version)
        except ValueError as exc:
            ap.error(f"--naoqi-version: {exc}")
    robot = StandinRobot(cfg, script, seed=a.seed, battery=a.battery, time_scale=a.time_scale,
                         listen=_loopback_only(a.listen), refuse_subscriber=a.refuse_subscriber,
                         naoqi_version=a.naoqi_version)
    url = robot.start()
    print(url, flush=True)
    try:
        while not done.wait(0.5):
            pass
    except KeyboardInterrupt:
        pass
    finally:
        robot.close()
    # libqi's threads and static objects can abort (SIGABRT) during interpreter teardown, which
    # would turn a clean stop into exit code -6: the session is closed, so leave at once
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0)


if __name__ == "__main__":
    sys.exit(main())

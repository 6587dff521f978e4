"""The ROS-free bridge: robot readings -> world/body dicts, actions -> NAOqi calls, events -> outcome.

``PepperBridge`` is what :class:`~pepper_bridge.environment.PepperEnvironment` wraps:

- ``start(wait)`` / ``stop()``; ``status()``; ``diagnostics.snapshot()``;
- ``read_body()`` / ``read_world()``: the robot's readings as ``body`` and ``world`` dicts (names
  of the scenario: which drive the battery and the temperature are read into, which object
  variable the plug sensor reads and what each action does come from the config);
- ``execute(action)``: the action's NAOqi calls (and the device callback for device commands);
- ``events``: a ``queue.Queue`` of :class:`~pepper_bridge.events.BridgeEvent` filled on qi threads;
  ``poll_events()`` drains it; ``outcome(action, events)`` / ``observation(events)`` build the
  outcome and observation fields from drained events.

Readings that fail validation are rejected (counted in ``diagnostics``; a ``rejected`` event
is queued) and the last good value stands in.
"""

from __future__ import annotations

import queue
import threading
import time
from typing import Any, Callable

from homeo_decision.scenario import Scenario, load_scenario

from . import events as ev
from .config import LinkSettings, PepperConfig, check_scenario, load_config
from .mapping import (AUTO_NAOQI, BATTERY_KEY, DEFAULT_NAOQI, PEOPLE_KEY, PEPPER_JOINTS, PLUGGED_KEY, ZONE_KEYS,
                      Rejected, WordMap, emotion_scale, max_temperature_status, need_from_percent, need_from_status,
                      percent_from_albattery, percent_from_fraction, plugged, presence_of, relation_from_zones,
                      relative_move, short, temperature_key)
from .naoqi_link import CLIENT_NAME, NaoqiLink, RobotUnavailable

# Extractors the bridge reads, subscribed on every connection and unsubscribed at the end: the
# memory keys are only filled while someone subscribes (ALEngagementZones "only works if
# ALPeoplePerception has also been subscribed to"; ALVoiceEmotionAnalysis needs
# ALSpeechRecognition running). Order matters: people perception before the zones.
SUBSCRIBED = ("ALPeoplePerception", "ALEngagementZones", "ALSpeechRecognition", "ALVoiceEmotionAnalysis")

DeviceCallback = Callable[[str, str], None]  # (device, command), called on the caller's thread


class PepperBridge:
    def __init__(self, config: PepperConfig | None = None, settings: LinkSettings | None = None,
                 scenario: Scenario | None = None, device_callback: DeviceCallback | None = None):
        self.sc = scenario or load_scenario()
        self.cfg = config or load_config(scenario=self.sc)
        if config is not None:
            check_scenario(config, self.sc)
        self.settings = settings or LinkSettings()
        self.device_callback = device_callback
        self.words = WordMap(self.sc.action_names, self.cfg.proposals, self.cfg.keywords)
        self.events: queue.Queue = queue.Queue()
        self.diagnostics = ev.Diagnostics()
        self.parser = ev.EventParser(self.cfg, self.words, self.events, self.diagnostics)
        self.link = NaoqiLink(self.settings, self.parser.keys, self.parser, self._on_status, self._on_connect)
        self.link.heartbeat = ("ALMemory", "getData", BATTERY_KEY)  # a documented read every robot answers
        self._lock = threading.Lock()
        self.subscriber = CLIENT_NAME  # renamed on each connection
        # what the bridge knows of the world beyond the sensors
        self.location = self.cfg.start_location
        # object states as the bridge believes them ("object.variable" -> value): the scenario's
        # initial states, then what the actions set (a sensed variable overrides its belief)
        init = self.sc.open.initial_objects
        self.states = {f"{o}.{var}": init.get(f"{o}.{var}", vals[0])
                       for o, spec in self.sc.objects.items() for var, vals in spec["variables"].items()}
        self.sensed: dict = {}
        self._said = {a: 0 for a in self.cfg.actions}  # phrases take turns per action
        # last good readings
        self.battery_percent: float | None = None
        self.temperature_status: int | None = None
        self.relation = "absent"
        # proposal -> the intention it clarifies (when exactly one intention desires it)
        owners: dict[str, list] = {}
        for it in self.sc.intentions:
            for a in it.desired:
                owners.setdefault(a, []).append(it.name)
        self.clarifies = {a: names[0] for a, names in owners.items() if len(names) == 1}

    # -- lifecycle --------------------------------------------------------------------
    def start(self, wait: float | None = 5.0) -> bool:
        return self.link.start(wait)

    def stop(self) -> None:
        """Unsubscribe what ``_on_connect`` subscribed (bounded calls), then close the link."""
        try:
            if self.link.connected:
                for svc in reversed(SUBSCRIBED):
                    if self.link.has(svc):
                        try:
                            self.link.call(svc, "unsubscribe", self.subscriber)
                        except RuntimeError as exc:
                            self.diagnostics.incident(f"{svc}.unsubscribe", str(exc).splitlines()[0] if str(exc) else "")
        finally:
            self.link.stop()

    def status(self) -> dict:
        return self.link.status()

    def wait_connected(self, timeout: float) -> bool:
        return self.link.wait_connected(timeout)

    def _on_status(self, st: dict) -> None:  # supervisor thread
        if st["state"] == "disconnected":
            self.diagnostics.incident("link_down", st["reason"])
        elif st["state"] == "unresponsive":
            self.diagnostics.incident("robot_unresponsive", st["reason"])
        self.events.put(ev.BridgeEvent(ev.STATUS, st, "link"))

    def vocabulary(self) -> list[str]:
        """What people say (the config's phrases and words), never the scenario's action ids."""
        return sorted(set(self.cfg.proposals) | set(self.cfg.keywords)
                      | set(self.cfg.intention_cues.get("keywords", {})))

    def _on_connect(self, link: NaoqiLink) -> None:  # supervisor thread, after (re)connection
        if self.cfg.naoqi_version == AUTO_NAOQI:
            self._ask_version(link)  # before speech starts: the voices' scale follows it
        # a fresh subscriber name per connection: the robot may still hold the old one after a drop
        self.subscriber = f"{CLIENT_NAME}_{link.connects}"
        speech = [("pause", True)]
        if self.cfg.speech_language:
            speech.append(("setLanguage", self.cfg.speech_language))
        speech += [("setVocabulary", self.vocabulary(), False), ("pause", False), ("subscribe", self.subscriber)]
        steps = {"ALSpeechRecognition": speech}
        for svc in SUBSCRIBED:
            steps.setdefault(svc, [("subscribe", self.subscriber)])
        for svc in SUBSCRIBED:
            if not link.has(svc):
                self.diagnostics.incident(f"{svc} missing", "the robot does not offer it")
                continue
            for method, *args in steps[svc]:
                try:
                    link.call(svc, method, *args)
                except RuntimeError as exc:  # e.g. vocabulary refused while another app listens
                    self.diagnostics.incident(f"{svc}.{method}", str(exc).splitlines()[0] if str(exc) else "")

    def _ask_version(self, link: NaoqiLink) -> None:
        """ALSystem.systemVersion() (a string, e.g. "2.5.5.5"; NAOqi SDK ALSystemProxy: "running system
        version"): a version without a known emotion scale keeps the default, and says so."""
        try:
            v = link.call("ALSystem", "systemVersion") if link.has("ALSystem") else None
        except RuntimeError as exc:
            self.diagnostics.incident("naoqi_version unknown", f"ALSystem.systemVersion: {str(exc).splitlines()[0]}")
            return
        if v is None:
            self.diagnostics.incident("naoqi_version unknown", "the robot offers no ALSystem")
            return
        try:
            emotion_scale(v)
        except (ValueError, TypeError):
            self.diagnostics.incident("naoqi_version unknown", f"ALSystem.systemVersion answered {short(v)}; "
                                                               f"reading NAOqi {DEFAULT_NAOQI}'s formats")
            return
        self.cfg.robot_version = str(v)

    def naoqi(self) -> dict:
        """The version whose formats are read, where it came from, and the emotion scale."""
        cfg = self.cfg
        source = "config" if cfg.naoqi_version != AUTO_NAOQI else ("robot" if cfg.robot_version else "default")
        return {"version": cfg.version, "source": source, "emotion_scale": cfg.emotion_scale,
                "anger_level": cfg.anger_level}

    # -- events -----------------------------------------------------------------------
    def poll_events(self, timeout: float = 0.0) -> list:
        return ev.drain(self.events, timeout)

    def collect(self, quiet: float = 0.15, window: float = 2.0) -> list:
        """Events until none came for ``quiet`` seconds (at most ``window`` seconds)."""
        out, end = [], time.monotonic() + window
        while True:
            left = end - time.monotonic()
            if left <= 0:
                return out
            got = ev.drain(self.events, min(quiet, left))
            if not got:
                return out
            out += got

    def outcome(self, action: str | None, events: list) -> dict:
        proposal = ev.proposal_of(events)
        return {"action": action, "feedback": ev.feedback_of(events), "proposal": proposal,
                "clarified_intention": self.clarifies.get(proposal) if proposal else None}

    @staticmethod
    def observation(events: list) -> dict:
        return ev.observation_of(events)

    # -- readings ---------------------------------------------------------------------
    def _reject(self, r: Rejected) -> None:
        self.diagnostics.reject(r)
        self.events.put(ev.BridgeEvent(ev.REJECTED, {"source": r.source, "value": repr(r.value)[:60], "reason": r.reason},
                                       r.source))

    def read_battery(self) -> float | None:
        try:
            if self.settings.battery_source == "albattery":
                self.battery_percent = percent_from_albattery(self.link.call("ALBattery", "getBatteryCharge"))
            else:
                try:
                    v = self.link.call("ALMemory", "getData", BATTERY_KEY)
                except RobotUnavailable:
                    raise
                except RuntimeError:  # key missing: ask ALBattery
                    v = None
                if v is None:
                    self.battery_percent = percent_from_albattery(self.link.call("ALBattery", "getBatteryCharge"))
                else:
                    self.battery_percent = percent_from_fraction(v)
        except Rejected as r:
            self._reject(r)
        return self.battery_percent

    def read_temperature(self) -> int | None:
        keys = [temperature_key(j) for j in PEPPER_JOINTS]
        try:
            vals = self.link.call("ALMemory", "getListData", keys)
        except RobotUnavailable:
            raise
        except RuntimeError:
            vals = [self._get(k) for k in keys]
        if not isinstance(vals, (list, tuple)) or len(vals) != len(keys):
            self._reject(Rejected("ALMemory.getListData", vals, "expected one value per joint"))
            return self.temperature_status
        s, bad = max_temperature_status(dict(zip(PEPPER_JOINTS, vals)))
        for r in bad:
            self._reject(r)
        if s is not None:
            self.temperature_status = s
        return self.temperature_status

    def _get(self, key: str, default: Any = None) -> Any:
        try:
            return self.link.call("ALMemory", "getData", key)
        except RobotUnavailable:
            raise
        except RuntimeError:
            return default

    def read_relation(self) -> str:
        try:
            vals = self.link.call("ALMemory", "getListData", list(ZONE_KEYS) + [PEOPLE_KEY])
            self.relation = relation_from_zones(*vals)
        except Rejected as r:
            self._reject(r)
        except RobotUnavailable:
            raise
        except (RuntimeError, TypeError):
            self.relation = relation_from_zones(*(self._get(k, []) for k in list(ZONE_KEYS) + [PEOPLE_KEY]))
        return self.relation

    def read_plug(self) -> None:
        """The object variable the config reads from the plug sensor (without a sensor: what the bridge asked for)."""
        plug = self.cfg.plug
        if not plug:
            return
        v = self._get(PLUGGED_KEY, _NO)
        if v is _NO:
            self.sensed.pop(plug["variable"], None)
            return
        try:
            self.sensed[plug["variable"]] = plug["plugged"] if plugged(v) else plug["unplugged"]
        except Rejected as r:
            self._reject(r)  # the last good reading stands

    def read_body(self) -> dict:
        """Battery percent and temperature status, and the body drives read from them (Section 4.3.1, Table 4.6)."""
        p = self.read_battery()
        s = self.read_temperature()
        return {"battery_percent": p, "temperature_status": s,
                self.cfg.battery_drive: None if p is None else need_from_percent(p),
                self.cfg.temperature_drive: None if s is None else need_from_status(s)}

    def object_states(self) -> dict:
        """``{object: {variable: value}}``: the beliefs, with the sensed variables read."""
        out: dict = {}
        for key, v in dict(self.states, **self.sensed).items():
            o, _, var = key.partition(".")
            out.setdefault(o, {})[var] = v
        return out

    def read_world(self) -> dict:
        """The robot's ``world`` dict (raises RobotUnavailable when disconnected)."""
        body = self.read_body()
        rel = self.read_relation()
        self.read_plug()
        return {"robot": {"location": self.location}, "objects": self.object_states(),
                "human": {"presence": presence_of(rel), "relation": rel}, "body": body}

    # -- actions ----------------------------------------------------------------------
    def execute(self, action: str) -> dict:
        """Perform ``action`` on the robot; returns {"action", "ok", "reason", "calls"}."""
        calls: list = []

        def call(service, method, *args):
            calls.append((service, method, list(args)))
            return self.link.call(service, method, *args)

        if action not in self.sc.action_names:
            raise ValueError(f"unknown action {action!r}; known: {', '.join(self.sc.action_names)}")
        unavailable = False
        try:
            ok = self._do(action, call)
            reason = None if ok else "the robot reported failure"
        except RobotUnavailable as exc:  # away, frozen or silent: the action's tick is missed
            ok, reason, unavailable = False, str(exc), True
        except RuntimeError as exc:
            ok, reason = False, str(exc).strip().splitlines()[0] if str(exc).strip() else "robot error"
            self.diagnostics.incident(f"action {action}", reason)
        return {"action": action, "ok": ok, "reason": reason, "calls": calls, "unavailable": unavailable}

    def _do(self, action: str, call) -> bool:
        spec = self.cfg.actions.get(action)
        if spec is None:
            raise RuntimeError(f"the config {self.cfg.source} says nothing of {action}")
        if spec.move is not None:
            return self._move(spec.move, call)
        if spec.rest:
            call("ALMotion", "rest")
        if spec.say:
            n = self._said[action]
            call("ALTextToSpeech", "say", spec.say[n % len(spec.say)])
            self._said[action] = n + 1
        if spec.device is not None and self.device_callback is not None:
            self.device_callback(spec.device, spec.command)
        self.states.update(spec.set)
        return True

    def _move(self, target: str, call) -> bool:
        cfg = self.cfg
        if not call("ALMotion", "robotIsWakeUp"):
            call("ALMotion", "wakeUp")
        dx, dy = relative_move(cfg.places[self.location], cfg.places[target])
        if cfg.navigation == "ALNavigation" and self.link.has("ALNavigation"):
            ok = bool(call("ALNavigation", "navigateTo", dx, dy))
        else:
            ok = bool(call("ALMotion", "moveTo", dx, dy, 0.0))
        if ok:
            if target != self.location:  # what leaving a place does to the objects there (the scenario's on_leave)
                for o, spec in self.sc.objects.items():
                    if spec.get("location") == self.location:
                        self.states.update({f"{o}.{var}": v for var, v in (spec.get("on_leave") or {}).items()})
            self.location = target
        return ok


_NO = object()

"""The ROS-free bridge: robot readings -> world/body dicts, actions -> NAOqi calls, events -> outcome.

``PepperBridge`` is what the ROS node wraps (and what ``field.py`` drives in-process):

- ``start(wait)`` / ``stop()``; ``status()``; ``diagnostics.snapshot()``;
- ``read_body()`` / ``read_world()``: the ``body`` and ``world`` dicts of the message contract;
- ``execute(action)``: the action's NAOqi calls (and the device callback for Play/Stop/LightOn/LightOff);
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
from .config import DEVICE_ACTIONS, LinkSettings, PepperConfig, load_config
from .mapping import (BATTERY_KEY, PEOPLE_KEY, PEPPER_JOINTS, PLUGGED_KEY, ZONE_KEYS, Rejected, WordMap,
                      max_temperature_status, neng_from_percent, nres_from_status, percent_from_albattery,
                      percent_from_fraction, plugged, presence_of, relation_from_zones, relative_move,
                      temperature_key)
from .naoqi_link import CLIENT_NAME, NaoqiLink, RobotUnavailable

DeviceCallback = Callable[[str, str], None]  # (device, command), called on the caller's thread


class PepperBridge:
    def __init__(self, config: PepperConfig | None = None, settings: LinkSettings | None = None,
                 scenario: Scenario | None = None, device_callback: DeviceCallback | None = None):
        self.sc = scenario or load_scenario()
        self.cfg = config or load_config(actions=tuple(self.sc.action_names))
        self.settings = settings or LinkSettings()
        self.device_callback = device_callback
        self.words = WordMap(self.sc.action_names, self.cfg.proposals, self.cfg.keywords)
        self.events: queue.Queue = queue.Queue()
        self.diagnostics = ev.Diagnostics()
        self.parser = ev.EventParser(self.cfg, self.words, self.events, self.diagnostics)
        self.link = NaoqiLink(self.settings, self.parser.keys, self.parser, self._on_status, self._on_connect)
        self._lock = threading.Lock()
        # what the bridge knows of the world beyond the sensors
        self.location = self.cfg.start_location
        self.devices = {"player": "idle", "light": "off"}
        self.charger_booked = "idle"
        self._chat_i = 0
        # last good readings
        self.battery_percent: float | None = None
        self.temperature_status: int | None = None
        self.relation = "absent"
        self.charger = "idle"
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
        try:
            if self.link.connected:
                for svc in ("ALSpeechRecognition", "ALVoiceEmotionAnalysis"):
                    if self.link.has(svc):
                        self.link.call(svc, "unsubscribe", CLIENT_NAME)
        except Exception:
            pass
        self.link.stop()

    def status(self) -> dict:
        return self.link.status()

    def wait_connected(self, timeout: float) -> bool:
        return self.link.wait_connected(timeout)

    def _on_status(self, st: dict) -> None:  # supervisor thread
        if st["state"] == "disconnected":
            self.diagnostics.incident("link_down", st["reason"])
        self.events.put(ev.BridgeEvent(ev.STATUS, st, "link"))

    def _on_connect(self, link: NaoqiLink) -> None:  # supervisor thread, after (re)connection
        vocab = sorted(set(self.words.proposals) | set(self.words.keywords)
                       | set(self.cfg.intention_cues.get("keywords", {})))
        for svc, steps in (("ALSpeechRecognition", [("pause", True), ("setVocabulary", vocab, False), ("pause", False),
                                                    ("subscribe", CLIENT_NAME)]),
                           ("ALVoiceEmotionAnalysis", [("subscribe", CLIENT_NAME)])):
            if not link.has(svc):
                continue
            for method, *args in steps:
                try:
                    link.call(svc, method, *args)
                except RuntimeError as exc:  # e.g. vocabulary refused while another app listens
                    self.diagnostics.incident(f"{svc}.{method}", str(exc).splitlines()[0] if str(exc) else "")

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

    def read_charger(self) -> str:
        v = self._get(PLUGGED_KEY, _NO)
        if v is _NO:  # no plug sensor: what the bridge asked for
            self.charger = self.charger_booked
        else:
            try:
                self.charger = "charging" if plugged(v) else "idle"
            except Rejected as r:
                self._reject(r)
        return self.charger

    def read_body(self) -> dict:
        p = self.read_battery()
        s = self.read_temperature()
        return {"battery_percent": p, "temperature_status": s,
                "NEng": None if p is None else neng_from_percent(p),
                "NRes": None if s is None else nres_from_status(s)}

    def read_world(self) -> dict:
        """The ``world`` dict of the message contract (raises RobotUnavailable when disconnected)."""
        body = self.read_body()
        rel = self.read_relation()
        charger = self.read_charger()
        return {"robot": {"location": self.location},
                "objects": {"charger": {"status": charger}, "player": {"status": self.devices["player"]},
                            "light": {"status": self.devices["light"]}},
                "human": {"presence": presence_of(rel), "relation": rel},
                "body": body}

    # -- actions ----------------------------------------------------------------------
    def execute(self, action: str) -> dict:
        """Perform ``action`` on the robot; returns {"action", "ok", "reason", "calls"}."""
        calls: list = []

        def call(service, method, *args):
            calls.append((service, method, list(args)))
            return self.link.call(service, method, *args)

        if action not in self.sc.action_names:
            raise ValueError(f"unknown action {action!r}; known: {', '.join(self.sc.action_names)}")
        try:
            ok = self._do(action, call)
            reason = None if ok else "the robot reported failure"
        except RobotUnavailable as exc:
            ok, reason = False, str(exc)
        except RuntimeError as exc:
            ok, reason = False, str(exc).strip().splitlines()[0] if str(exc).strip() else "robot error"
            self.diagnostics.incident(f"action {action}", reason)
        return {"action": action, "ok": ok, "reason": reason, "calls": calls}

    def _do(self, action: str, call) -> bool:
        cfg = self.cfg
        if action.startswith("MoveTo") and action[6:] in cfg.places:
            target = action[6:]
            if not call("ALMotion", "robotIsWakeUp"):
                call("ALMotion", "wakeUp")
            dx, dy = relative_move(cfg.places[self.location], cfg.places[target])
            if cfg.navigation == "ALNavigation" and self.link.has("ALNavigation"):
                ok = bool(call("ALNavigation", "navigateTo", dx, dy))
            else:
                ok = bool(call("ALMotion", "moveTo", dx, dy, 0.0))
            if ok:
                if target != self.location:
                    self.charger_booked = "idle"
                self.location = target
            return ok
        if action == "Rest":
            call("ALMotion", "rest")
            return True
        if action == "Chat":
            phrases = cfg.speech["chat"]
            call("ALTextToSpeech", "say", phrases[self._chat_i % len(phrases)])
            self._chat_i += 1
            return True
        if action in ("Attach", "Detach", "Stay"):
            phrase = cfg.speech.get(action.lower(), "")
            if phrase:
                call("ALTextToSpeech", "say", phrase)
            if action == "Attach":
                self.charger_booked = "charging"
            elif action == "Detach":
                self.charger_booked = "idle"
            return True
        if action in cfg.devices:
            d = cfg.devices[action]
            if d.get("say"):
                call("ALTextToSpeech", "say", d["say"])
            if self.device_callback is not None:
                self.device_callback(d["device"], d["command"])
            if d["device"] in self.devices:
                self.devices[d["device"]] = {"play": "playing", "stop": "idle"}.get(d["command"], d["command"])
            return True
        if action in DEVICE_ACTIONS:
            raise RuntimeError(f"no device handler configured for {action}")
        raise RuntimeError(f"the bridge does not know how to perform {action}")


_NO = object()

"""A stand-in Pepper: a ``qi.Session`` on loopback offering NAOqi's services and memory keys.

The bridge reaches it exactly as it reaches a real Pepper (``qi.Session().connect(url)``). What it fakes, each in
a module of its own: the services (``standin_services``), their keys and formats from the NAOqi documentation
(``standin_naoqi``), the body (``standin_body``), the person in front of it (``standin_person``), the scripted
user (``user``) and the faults on demand (``standin_faults``). This module holds the robot that joins them: its
session, the calls it received (``calls()``), its memory and events.
:class:`NotNaoqiPort` is a loopback port that accepts connections but does not speak qi.
"""

from __future__ import annotations

import argparse
import collections
import signal
import sys
import threading
import time
from typing import Any

import qi

from homeo_decision.rng import component_rng
from homeo_msgs_py.cli_args import die_with_parent, leave

from . import naoqi_link
from .config import AUTO_NAOQI, PepperConfig, load_config
from .standin_body import BodyParams, StandinBody
from .standin_faults import StandinFaults
from .standin_naoqi import emotion_scale
from .standin_person import PEPPER_LIFE_LIMITS, StandinPerson, ZoneLimits
from .standin_services import naoqi_services
from .user import ScriptedUser, load_script, timed_entry_emits

STANDIN_NAOQI = "2.5.5.5"  # what ALSystem.systemVersion answers when neither the config nor the caller fixes it


class StandinRobot(StandinBody, StandinFaults):
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
        self.subs: dict = {}  # key -> what ALMemory.subscriber(key) returned
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
        self._services = naoqi_services(self)

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

    def calls(self, service: str | None = None, exclude_memory_reads: bool = True) -> list:
        out = list(self._calls)
        if exclude_memory_reads:
            out = [c for c in out if not (c[0] == "ALMemory" and c[1] in ("getData", "getListData"))]
        if service is not None:
            out = [c for c in out if c[0] == service]
        return out

    def clear_calls(self) -> None:
        self._calls.clear()

    @property
    def location(self) -> str | None:
        return self.cfg.place_at(self.x, self.y)

    def people(self) -> dict:
        """The people keys of ALMemory: where the person stands, seen from the robot (standin_person)."""
        return self.person.memory((self.x, self.y), self.user.present)

    def _walk(self) -> None:
        """Lock held: where the script last asked the person to walk (to the robot, wherever it is, or home)."""
        where = self.user.take_walk()
        if where is not None:
            self.person.walk(where, (self.x, self.y))

    def _publish(self) -> None:
        """Body and presence into memory (injected keys keep their forced values): ``body_memory``, and the
        people keys from where the person stands (``standin_person``, its pages beside each value)."""
        self.data.update(self.body_memory())
        self.data.update(self.people())
        self.data.update(self.injected)

    def state(self) -> dict:
        with self.lock:
            self._advance()
            return {"battery_percent": self.battery, "heat": self.heat, "temperature_status": max(self.statuses().values()),
                    "location": self.location, "pose": [self.x, self.y], "awake": self.awake, "plugged": self.plugged,
                    "zone": self.person.zone((self.x, self.y), self.user.present), "user_index": self.user.index, "user_done": self.user.done}

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
    def _motion(self, x: float, y: float) -> bool:
        self.script_fault()
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
    leave(0)  # the session is closed: libqi's teardown must not turn the clean stop into -6


if __name__ == "__main__":
    sys.exit(main())

"""The connection to the robot: a qi.Session, service proxies, memory subscribers, reconnection.

A supervisor thread owns the connection. It connects (``qi.Session().connect(url)``, with
``tcps://`` + user/password through a client authenticator factory for NAOqi 2.9), creates
the proxies and one ``ALMemory.subscriber(key)`` per event key, and hands every event
value to ``on_event(key, value)`` (called on qi threads: it must only queue). Where the
robot refuses ``subscriber``, the key is polled with ``getData`` every ``poll_period`` and a
changed value counts as an event. When the session drops (``disconnected`` signal or a
failed call) the supervisor reports it through ``on_status``, tears the proxies down and
retries with exponential back-off, re-creating proxies and subscribers.

Every call to the robot is bounded: it goes out as a qi future (``_async=True``) and is waited
for in slices up to its timeout (``call_timeout`` for reads, ``action_timeout`` for motion and
speech). A heartbeat (one ``ALMemory.getData`` at a time, every ``heartbeat_period``) finds a
robot that stops answering with the connection still open: after ``heartbeat_timeout`` without
an answer (an error is an answer) the link is ``unresponsive``: calls fail at once (the caller
holds its tick), the state is reported, and the first answer brings it back to ``connected``.
"""

from __future__ import annotations

import gc
import threading

from functools import partial
from typing import Any, Callable

import qi

from .config import LinkSettings

SERVICES = ("ALMemory", "ALBattery", "ALMotion", "ALNavigation", "ALTextToSpeech", "ALSpeechRecognition",
            "ALVoiceEmotionAnalysis", "ALPeoplePerception", "ALEngagementZones", "ALSystem")
REQUIRED = ("ALMemory", "ALMotion", "ALTextToSpeech")
CLIENT_NAME = "homeo_pepper_bridge"
_MISSING = object()


class RobotUnavailable(RuntimeError):
    """The robot is not connected, dropped during the call, or did not answer in time."""


# calls that move or speak last as long as the robot takes; every other call is a read
LONG_CALLS = {("ALNavigation", "navigateTo"), ("ALMotion", "moveTo"), ("ALMotion", "rest"), ("ALMotion", "wakeUp"),
              ("ALTextToSpeech", "say")}
SLICE_MS = 100  # a waiting call looks at the link this often (a freeze found by the heartbeat ends it)


class _Authenticator:
    def __init__(self, user: str, password: str):
        self.user, self.password = user, password

    def initialAuthData(self):  # noqa: N802 (libqi's name)
        return {"user": self.user, "token": self.password}


class _AuthenticatorFactory:
    def __init__(self, user: str, password: str):
        self.user, self.password = user, password

    def newAuthenticator(self):  # noqa: N802 (libqi's name)
        return _Authenticator(self.user, self.password)


class NaoqiLink:
    def __init__(self, settings: LinkSettings, event_keys: list[str], on_event: Callable[[str, Any], None],
                 on_status: Callable[[dict], None] | None = None, on_connect: Callable[["NaoqiLink"], None] | None = None):
        self.s = settings
        self.event_keys = list(event_keys)
        self.on_event = on_event
        self.on_status = on_status or (lambda st: None)
        self.on_connect = on_connect
        self._lock = threading.RLock()
        self._stop = threading.Event()
        self._wake = threading.Event()
        self._up = threading.Event()
        self._thread: threading.Thread | None = None
        self.session: qi.Session | None = None
        self.proxies: dict[str, Any] = {}
        self._subs: list = []
        self.polled: list[str] = []
        self._last_polled: dict[str, Any] = {}
        self.state = "idle"
        self.reason = ""
        self.connects = 0
        self.drops = 0
        self.freezes = 0
        self._generation = 0
        self.unresponsive_since: float | None = None
        self._beat = None  # (future, sent at) of the heartbeat in flight
        self._beat_at = 0.0
        self.heartbeat = ("ALMemory", "getData", "Device/SubDeviceList/Battery/Charge/Sensor/Value")

    # -- public ---------------------------------------------------------------------
    def start(self, wait: float | None = None) -> bool:
        if self._thread is None:
            self._thread = threading.Thread(target=self._run, daemon=True, name="pepper-link")
            self._thread.start()
        return self.wait_connected(wait) if wait else self.connected

    def stop(self) -> None:
        self._stop.set()
        self._wake.set()
        if self._thread is not None:
            self._thread.join(timeout=5.0)
            self._thread = None
        self._teardown()
        self._set_state("stopped", "stopped by the caller")

    @property
    def connected(self) -> bool:
        return self._up.is_set()

    def wait_connected(self, timeout: float) -> bool:
        return self._up.wait(timeout)

    def status(self) -> dict:
        return {"state": self.state, "connected": self.connected, "reason": self.reason, "url": self.s.url,
                "connects": self.connects, "drops": self.drops, "freezes": self.freezes,
                "polled_keys": list(self.polled)}

    def has(self, service: str) -> bool:
        return service in self.proxies

    def call(self, service: str, method: str, *args, timeout: float | None = None) -> Any:
        """A bounded call on the robot; a dropped, frozen or silent robot raises RobotUnavailable."""
        with self._lock:
            proxy = self.proxies.get(service) if self.connected else None
        if proxy is None:
            if not self.connected:
                raise RobotUnavailable(f"robot not connected ({self.reason or self.state})")
            raise RobotUnavailable(f"service {service} is not available on this robot")
        if timeout is None:
            timeout = self.s.action_timeout if (service, method) in LONG_CALLS else self.s.call_timeout
        try:
            fut = getattr(proxy, method)(*args, _async=True)
        except RuntimeError as exc:  # the call could not even go out
            self._check_session(f"{service}.{method}: {_msg(exc)}")
            raise RobotUnavailable(f"robot dropped during {service}.{method}") from None
        return self._wait(fut, f"{service}.{method}", timeout)

    def _wait(self, fut, what: str, timeout: float) -> Any:
        import time

        end = time.monotonic() + timeout
        while True:
            left = end - time.monotonic()
            if fut.wait(int(max(1, min(SLICE_MS, left * 1000)))) != qi.FutureState.Running:
                break
            if not self.connected:  # dropped or found frozen meanwhile: do not wait it out
                _cancel(fut)
                raise RobotUnavailable(f"{what} abandoned: robot {self.state} ({self.reason})")
            if left <= 0:
                _cancel(fut)
                self._froze(f"no answer to {what} within {timeout:g} s")
                raise RobotUnavailable(f"robot did not answer {what} within {timeout:g} s")
        if fut.hasError():
            err = fut.error()
            self._check_session(f"{what}: {err}")
            if self.connected and _is_lost(err):  # the robot closing: its services go before the socket does
                self._lost(f"{what}: {_first_line(err)}")
            if not self.connected:
                raise RobotUnavailable(f"robot dropped during {what}")
            raise RuntimeError(err)
        if fut.isCanceled():
            raise RobotUnavailable(f"{what} canceled")
        return fut.value()

    def _check_session(self, reason: str) -> None:
        if self.session is None or not self.session.isConnected():
            self._lost(reason)

    # -- supervisor -----------------------------------------------------------------
    def _run(self) -> None:
        backoff = self.s.backoff_initial
        while not self._stop.is_set():
            if self.session is None:
                self._set_state("connecting", f"connecting to {self.s.url}")
                try:
                    self._connect()
                except Exception as exc:  # any failure: retry later
                    self._teardown()
                    self._set_state("disconnected", f"connect failed: {_msg(exc)}; retry in {backoff:.2f} s")
                    self._stop.wait(backoff)
                    backoff = min(self.s.backoff_max, backoff * self.s.backoff_factor)
                    continue
                backoff = self.s.backoff_initial
            period = min(self.s.heartbeat_period, self.s.poll_period if self.polled else 1.0)
            self._wake.wait(period)
            self._wake.clear()
            if self._stop.is_set():
                break
            if self.state != "disconnected" and self.session is not None and not self.session.isConnected():
                self._lost("session reports disconnected")
            if self.state == "disconnected":
                self._teardown()
                continue
            self._heartbeat()
            if self.polled and self.connected:
                self._poll()

    def _heartbeat(self) -> None:
        """One read at a time: no answer within heartbeat_timeout = unresponsive; an answer = back."""
        import time

        now = time.monotonic()
        if self._beat is not None:
            fut, sent = self._beat
            if fut.isFinished() or fut.isCanceled():  # a value or an error: the robot answers
                self._beat = None
                if self.unresponsive_since is not None:
                    gone = now - self.unresponsive_since
                    self.unresponsive_since = None
                    self._up.set()
                    self._set_state("connected", f"the robot answers again after {gone:.1f} s")
            elif now - sent > self.s.heartbeat_timeout:
                self._froze(f"no answer to the heartbeat ({self.heartbeat[0]}.{self.heartbeat[1]}) "
                            f"within {self.s.heartbeat_timeout:g} s, connection open")
            return
        if now - self._beat_at < self.s.heartbeat_period:
            return
        with self._lock:
            proxy = self.proxies.get(self.heartbeat[0])
        if proxy is None:
            return
        self._beat_at = now
        try:
            self._beat = (getattr(proxy, self.heartbeat[1])(*self.heartbeat[2:], _async=True), now)
        except RuntimeError as exc:
            self._check_session(f"heartbeat: {_msg(exc)}")

    def _froze(self, reason: str) -> None:
        import time

        if self.state == "disconnected":
            return
        if self.unresponsive_since is None:
            self.unresponsive_since = time.monotonic()
            self.freezes += 1
            self._up.clear()
            self._set_state("unresponsive", reason)

    def _connect(self) -> None:
        s = qi.Session()
        if self.s.user:
            s.setClientAuthenticatorFactory(_AuthenticatorFactory(self.s.user, self.s.password or ""))
        fut = s.connect(self.s.url, _async=True)
        try:
            fut.value(int(self.s.connect_timeout * 1000))
        except Exception:
            fut.cancel()
            raise
        if not fut.isFinished() or fut.hasError():
            raise RuntimeError(fut.error() if fut.hasError() else "connect timed out")
        self._generation += 1
        gen = self._generation
        s.disconnected.connect(partial(self._on_disconnected, gen))
        ms = int(self.s.call_timeout * 1000)
        proxies = {}
        for name in SERVICES:
            try:
                proxies[name] = s.service(name, _async=True).value(ms)
            except RuntimeError as exc:
                if "timeout" in str(exc).lower():
                    raise RuntimeError(f"no answer from the robot's service directory within {ms} ms") from None
                if name in REQUIRED:
                    raise RuntimeError(f"required service {name} missing on the robot") from None
        mem = proxies["ALMemory"]
        subs, polled = [], []
        for key in self.event_keys:
            try:
                sub = mem.subscriber(key, _async=True).value(ms)
                sub.signal.connect(partial(self._event, gen, key), _async=True).value(ms)
                subs.append(sub)
            except RuntimeError as exc:
                if "timeout" in str(exc).lower():
                    raise RuntimeError(f"no answer to ALMemory.subscriber within {ms} ms") from None
                polled.append(key)
        with self._lock:
            self.session, self.proxies, self._subs = s, proxies, subs
            self.polled = polled
            self._last_polled = {}
            for key in polled:
                self._last_polled[key] = self._get_or_missing(key)
        self.connects += 1
        self.unresponsive_since, self._beat = None, None
        self._up.set()
        self._set_state("connected", f"connected to {self.s.url}" + (f"; polling {len(polled)} event keys" if polled else ""))
        if self.on_connect is not None:
            self.on_connect(self)

    def _get_or_missing(self, key: str) -> Any:
        try:
            return self.proxies["ALMemory"].getData(key, _async=True).value(int(self.s.call_timeout * 1000))
        except RuntimeError:
            return _MISSING

    def _poll(self) -> None:
        for key in list(self.polled):
            try:
                v = self.call("ALMemory", "getData", key)
            except RobotUnavailable:
                return
            except RuntimeError:
                continue
            if v != self._last_polled.get(key, _MISSING):
                self._last_polled[key] = v
                self.on_event(key, v)

    def _event(self, gen: int, key: str, value: Any) -> None:  # qi thread
        if gen == self._generation:
            self.on_event(key, value)

    def _on_disconnected(self, gen: int, reason: Any = "") -> None:  # qi thread: only flag it
        if gen == self._generation:
            self._lost(f"robot disconnected ({reason})")

    def _lost(self, reason: str) -> None:
        if self.state in ("connected", "unresponsive"):
            self._up.clear()
            self.drops += 1
            self.unresponsive_since = None
            self._set_state("disconnected", reason)
        self._wake.set()

    def _teardown(self) -> None:
        with self._lock:
            s, self.session = self.session, None
            self.proxies, self._subs = {}, []
        if s is not None:
            try:
                s.close()
            except Exception:
                pass
            collect_closed_session()  # at this known point, not inside a later qi call

    def _set_state(self, state: str, reason: str) -> None:
        self.state, self.reason = state, reason
        try:
            self.on_status(self.status())
        except Exception:
            pass


def collect_closed_session() -> None:
    """Destroy now what a closed qi session left in reference cycles. Otherwise an automatic garbage
    collection destroys it later, at whatever point it runs. With qi 3.1.5, that point was sometimes
    inside another session's ``registerService``, and the process died there with a segfault:
    tools/qi_stress.py reproduces it, see docs/PEPPER.md."""
    gc.collect()


def _cancel(fut) -> None:
    try:
        fut.cancel()
    except RuntimeError:
        pass


# libqi's errors for a call cut by the connection (not the robot's answer): the session is gone
_LOST = ("service removed", "socket", "disconnected", "not connected", "connection closed", "endpoint")


def _is_lost(err) -> bool:
    return any(w in str(err).lower() for w in _LOST)


def _first_line(err) -> str:
    return str(err).strip().splitlines()[0] if str(err).strip() else "error"


def _msg(exc: BaseException) -> str:
    return str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__

"""What goes wrong with the stand-in Pepper on demand: memory keys forced to wrong values (``inject``), the robot
disappearing and coming back on the same URL (``drop`` / ``restart``), and freezing: no answer with the connection
open (``freeze_for``: every NAOqi call and event waits until it thaws; ``HomeoStandin`` still answers). A user
script's interaction may drop or freeze the robot as its first action starts (``script_fault``)."""

from __future__ import annotations

import threading
from typing import Any


class StandinFaults:
    """Mixed into ``StandinRobot``: its ``session``, ``_thawed`` (cleared while frozen), ``_stop``, ``injected``."""

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

    def freeze_for(self, seconds: float) -> None:
        """Stop answering (connection open) for ``seconds`` wall seconds; thaws by itself."""
        self._thawed.clear()
        t = threading.Timer(seconds, self._thawed.set)
        t.daemon = True
        t.start()

    @property
    def frozen(self) -> bool:
        return not self._thawed.is_set()

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

    def script_fault(self) -> None:
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

"""Starting a Pepper for the graph (no rclpy): the stand-in robot as its own process, and the check
that a real robot answers at its URL before any node starts. The launcher's Pepper front end
(``homeo_launch.pepper``) uses these; they are the Pepper's own, as its world is
(``world_backend.PepperWorld``).
"""

from __future__ import annotations

import os
import select
import subprocess
import sys
import threading
import time
from pathlib import Path

from homeo_msgs_py.cli_args import UserError

STANDIN_START_S = 30.0


class StandinError(RuntimeError):
    """The stand-in robot did not start, or died: one line (and its last output)."""


class StandinProcess:
    """``python -m pepper_bridge.standin --listen tcp://127.0.0.1:0 ...``; its URL is the first line."""

    def __init__(self, script: str | None, seed: int, time_scale: float, log_path: Path, config: str | None = None,
                 battery: float | None = None):
        cmd = [sys.executable, "-m", "pepper_bridge.standin", "--listen", "tcp://127.0.0.1:0", "--seed", str(seed),
               "--time-scale", repr(float(time_scale))]
        if script:
            cmd += ["--script", script]
        if config:
            cmd += ["--config", config]
        if battery is not None:
            cmd += ["--battery", repr(float(battery))]
        env = dict(os.environ, PYTHONUNBUFFERED="1")
        self.log_path = log_path
        self.proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                     env=env, start_new_session=True, preexec_fn=_die_with_parent)
        self.url = self._read_url()
        self._drain = threading.Thread(target=self._copy_output, daemon=True, name="standin-output")
        self._drain.start()

    def _read_url(self) -> str:
        end = time.monotonic() + STANDIN_START_S
        buf = b""
        fd = self.proc.stdout.fileno()
        while b"\n" not in buf:
            left = end - time.monotonic()
            if left <= 0 or self.proc.poll() is not None:
                break
            r, _, _ = select.select([fd], [], [], min(left, 0.5))
            if r:
                chunk = os.read(fd, 4096)
                if not chunk:
                    break
                buf += chunk
        line, _, rest = buf.partition(b"\n")
        self._rest = rest
        url = line.decode(errors="replace").strip()
        if not url.startswith(("tcp://", "tcps://")):
            self.stop()
            raise StandinError("the stand-in robot did not start" + (f": {url or buf.decode(errors='replace')[-400:]}"
                                                                   if url or buf else " (no URL printed)"))
        return url

    def _copy_output(self) -> None:
        with open(self.log_path, "ab") as log:
            log.write(self._rest)
            for chunk in iter(lambda: self.proc.stdout.read1(4096), b""):
                log.write(chunk)

    def dead(self) -> int | None:
        return self.proc.poll()

    def user_log(self, timeout: float = 10.0) -> list:
        """The scripted user's judgement of each robot action (HomeoStandin.userLog over qi)."""
        import qi

        qi.logging.setLevel(qi.logging.ERROR)
        s = qi.Session()
        try:
            fut = s.connect(self.url, _async=True)
            fut.value(int(timeout * 1000))
            return [dict(r) for r in s.service("HomeoStandin").userLog()]
        except Exception:
            return []
        finally:
            try:
                s.close()
            except Exception:
                pass

    def stop(self) -> int | None:
        if self.proc.poll() is None:
            try:
                os.killpg(self.proc.pid, 15)
                self.proc.wait(timeout=3.0)
            except (ProcessLookupError, PermissionError):
                pass
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, 9)
                self.proc.wait(timeout=2.0)
        return self.proc.returncode


def _die_with_parent() -> None:  # runs in the child before exec
    try:
        import ctypes

        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, 15)  # PR_SET_PDEATHSIG = SIGTERM
    except (OSError, AttributeError):
        pass


# -- is the robot there? ----------------------------------------------------------------------
def probe_robot(url: str, bound: float, user: str | None = None, password: str | None = None,
                shown: float | None = None) -> None:
    """Raise UserError (one line) unless ``url`` answers as NAOqi (an ALMemory service) within ``bound`` s:
    a malformed URL, an unknown host, a refused connection, a port that is not NAOqi, or silence."""
    import socket
    from urllib.parse import urlsplit

    try:
        u = urlsplit(url)
        host, port = u.hostname, u.port
    except ValueError:
        host = port = None
    if u.scheme not in ("tcp", "tcps") or not host or not port:
        raise UserError(f"cannot reach the robot at {url}: not a NAOqi URL (tcp://HOST:9559 or tcps://HOST:9503)")
    result: dict = {}

    def attempt():
        import qi

        end = time.monotonic() + bound
        try:
            socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)
        except socket.gaierror:
            result["error"] = f"unknown host {host!r}"
            return
        except OSError as exc:
            result["error"] = f"cannot resolve {host!r} ({exc})"
            return
        qi.logging.setLevel(qi.logging.ERROR)
        s = qi.Session()
        result["session"] = s
        if user:
            from pepper_bridge.naoqi_link import _AuthenticatorFactory

            s.setClientAuthenticatorFactory(_AuthenticatorFactory(user, password or ""))
        try:
            s.connect(url, _async=True).value(max(1, int((end - time.monotonic()) * 1000)))
        except RuntimeError as exc:
            msg = str(exc).strip().splitlines()[0] if str(exc).strip() else "connection failed"
            result["error"] = ("no NAOqi handshake (not a NAOqi port?)" if "timeout" in msg.lower()
                               else f"connection failed: {msg}")
            return
        try:
            s.service("ALMemory", _async=True).value(max(1, int((end - time.monotonic()) * 1000)))
        except RuntimeError:
            result["error"] = "it answers but offers no ALMemory service: not NAOqi"
            return
        result["ok"] = True

    t = threading.Thread(target=attempt, daemon=True, name="robot-probe")
    t.start()
    t.join(bound)
    s = result.get("session")
    if s is not None:
        threading.Thread(target=s.close, daemon=True).start()  # closing a half-open session may block
    if result.get("ok"):
        return
    raise UserError(f"cannot reach the robot at {url}: "
                    + result.get("error", f"no answer within {shown or bound:g} s (--connect-bound)"))



def check_standin(standin: "StandinProcess | None") -> None:
    if standin is not None and standin.dead() is not None:
        tail = ""
        try:
            tail = "\n".join(standin.log_path.read_text(errors="replace").rstrip().splitlines()[-12:])
        except OSError:
            pass
        raise StandinError(f"the stand-in robot exited with code {standin.dead()}" + (f"; its last output:\n{tail}"
                                                                                    if tail else ""))



"""The Pepper's part of a launch (no rclpy): what the front ends do for the world ``pepper`` through its
class methods (``world_backend.PepperWorld``), written here once for ``homeo-launch pepper`` and
``ros2 launch homeo_robot world.launch.py world:=pepper``.

- the launch options: a stand-in robot instead of a real one (``standin``, its scripted user ``script``,
  ``time_scale``), ``connect_bound``, ``fresh_schedule``;
- the plan: the stand-in as a companion process on a free loopback port, or the real robot checked at
  its URL before any node starts; the script's ``robot.drives`` as the initial drives; with a Q-table,
  the scenario's learning schedule reduced to its last phase (the robot continues after its simulated
  training); the collection window 3 s / 0.15 s with the stand-in, 8 s / 8 s on a robot;
- the result: the interaction log (one line a row as it happens), with the stand-in's scripted user its
  judgement and summary (``field.FieldResult``).
"""

from __future__ import annotations

import json
import socket
import sys
import threading
import time
from pathlib import Path

from homeo_decision.world_api import Companion, LaunchPlan, WorldConfigError
from homeo_msgs_py.graph import BAYES, ORACLE
from homeo_msgs_py.learning import DOD
from homeo_msgs_py.params import ParamSpec

LAUNCH = (
    ParamSpec("standin", False, "start a stand-in Pepper on loopback (its own process) instead of reaching a robot"),
    ParamSpec("script", "", "the stand-in's scripted user (a path or a file of pepper_bridge/scripts/); its "
              "robot.drives are the initial drives"),
    ParamSpec("time_scale", 0.0, "stand-in: simulated seconds per wall second (0: each action lasts 10 s, "
              "reproducible)", 0.0, 1000.0),
    ParamSpec("connect_bound", 15.0, "seconds to wait for the robot at qi_url before giving up (exit 2)", 0.5, 600.0),
    ParamSpec("fresh_schedule", False, "with a Q-table: start the learning schedule over (default: go on in its "
              "last phase)"),
)
INTENTIONS = {"cues": ORACLE, BAYES: BAYES}  # cues: the config's keyword/gesture cues name the intention
HEADER = f"{'#':>3}  {'m_dom':<10} {'intention':<9} {'action':<8} {'fb':>3}  {'proposal':<8}  done"


def plan(sc, given: dict, workdir: str, params: tuple) -> LaunchPlan:
    """The Pepper's launch plan (``WorldBackend.plan``); WorldConfigError for what cannot start."""
    from .config import DEFAULT_URL, ConfigError, load_config
    from .mapping import AUTO_NAOQI, emotion_scale

    standin, script = bool(given.get("standin")), given.get("script") or ""
    if standin and given.get("qi_url") is not None:
        raise WorldConfigError("qi_url and standin: the stand-in has its own URL; give one of them")
    if script and not standin:
        raise WorldConfigError("script needs standin (a real robot has a real user)")
    p = {s.name: given[s.name] for s in params if given.get(s.name) is not None}
    if p.get("config"):
        p["config"] = str(Path(p["config"]).resolve())
    try:
        load_config(p.get("config") or None, scenario=sc)
    except ConfigError as exc:
        raise WorldConfigError(str(exc)) from None
    if p.get("naoqi_version") not in (None, "", AUTO_NAOQI):
        try:
            emotion_scale(p["naoqi_version"])
        except ValueError as exc:
            raise WorldConfigError(f"naoqi_version: {exc} or {AUTO_NAOQI!r}") from None
    p.setdefault("collect_window", 3.0 if standin else 8.0)
    p.setdefault("collect_quiet", 0.15 if standin else p["collect_window"])
    p.setdefault("intention_cues", INTENTIONS.get(given.get("intention")) == ORACLE)  # the oracle reads them
    p.setdefault("end_with_script", bool(standin and script))
    out = LaunchPlan(p, bounded=bool(given.get("iterations")) or bool(standin and script))
    if script:
        script = str(script_path(script))
        drives = (_load_script(script).get("robot") or {}).get("drives")
        if drives:
            out.overrides["initial_drives"] = dict(drives)
    if given.get("load_q") and not given.get("fresh_schedule"):
        out.scenario = _last_phase(given.get("scenario"), Path(workdir))
    if standin:
        p["qi_url"] = f"tcp://127.0.0.1:{_free_port()}"
        argv = [sys.executable, "-m", "pepper_bridge.standin", "--listen", p["qi_url"], "--seed",
                str(given.get("seed") or 0), "--time-scale", repr(float(given.get("time_scale") or 0.0))]
        argv += (["--script", script] if script else []) + (["--config", p["config"]] if p.get("config") else [])
        out.companions = (Companion("pepper_standin", argv),)
    else:
        bound = given.get("connect_bound") or 15.0
        # the bound is the whole command's: keep about 1 s for the interpreter's start and exit
        probe_robot(p.get("qi_url", DEFAULT_URL), max(0.5, bound - 1.0), p.get("user"), p.get("password"), shown=bound)
    return out


def script_path(s: str) -> Path:
    """A scripted user: a path, or the name of a shipped script (pepper_bridge/scripts/)."""
    from homeo_decision.jsonfile import shipped

    from .config import SCRIPTS_DIR

    p = shipped(s, SCRIPTS_DIR)
    if not p.is_file():
        raise WorldConfigError(f"user script not found: {s}")
    return p.resolve()


def _load_script(path: str) -> dict:
    from .user import ScriptError, load_script

    try:
        return load_script(path)
    except ScriptError as exc:
        raise WorldConfigError(str(exc)) from None


def _last_phase(scenario: str | None, workdir: Path) -> str:
    """The scenario with its learning schedule reduced to the last phase, written into ``workdir``."""
    from homeo_decision.scenarios import default_scenario_path

    from homeo_decision.jsonfile import read
    from homeo_decision.scenario import ScenarioError

    raw = read(scenario or default_scenario_path(), ScenarioError, "scenario")
    raw["learning"]["schedule"] = [dict(raw["learning"]["schedule"][-1], **{"from": 0})]
    dst = workdir / "scenario.json"
    dst.write_text(json.dumps(raw))
    return str(dst)


def _free_port() -> int:
    with socket.socket() as s:  # a free port on loopback, known before any node starts
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


# -- the result ---------------------------------------------------------------------------------
def row_line(r: dict) -> str:
    fb = {1: "+", -1: "-", 0: ""}.get(r["feedback"], "?")
    return (f"{r['interaction']:>3}  {r['m_dom'] or '-':<10} {r['intention'] or '-':<9} {r['action'] or '-':<8} "
            f"{fb:>3}  {r['proposal'] or '-':<8}  {done_note(r)}").rstrip()


def done_note(r: dict) -> str:
    """What became of the action: '' when done; 'FAILED: reason' (refused: no effect) or
    'MISSED: reason' (robot away or unresponsive)."""
    if r.get("ok", True) or r.get("action") is None:
        return ""
    why = (r.get("reason") or "").splitlines()[0][:60] if r.get("reason") else "no reason given"
    return f"{'MISSED' if r.get('missed') else 'FAILED'}: {why}"


def _field(sc, setting: dict, log: list, user_log: list):
    from .config import load_config
    from .field import FieldResult, charging_roles

    dod = setting.get("learning", {}).get(DOD.name)
    roles = charging_roles(load_config(setting.get("values", {}).get("config") or None, scenario=sc), sc)
    return FieldResult("robot", sc.learning[DOD.name] if dod is None else dod, setting.get("seed", 0), log=list(log),
                       user_log=list(user_log), roles=roles)


def result(sc, status: dict, setting: dict) -> dict | None:
    """The interaction log of the run (None: none yet); with the stand-in's scripted user, its
    judgement and the field summary."""
    extra = status.get("extra") or {}
    if setting.get("interrupted") and not extra.get("log"):
        return None
    res = _field(sc, setting, extra.get("log") or [], extra.get("user_log") or [])
    out = {"seed": res.seed, DOD.name: res.dod, "url": (extra.get("robot") or {}).get("url"),
           "interactions": len(res.log), "missed": status.get("missed", 0), "log": res.log}
    if res.user_log:
        out.update(summary=res.summary(), user_log=res.user_log)
    if status.get("restarts"):
        out["restarts"] = status["restarts"]
    return out


def result_text(sc, out: dict, setting: dict) -> str:
    from .field import format_table

    table = (format_table(_field(sc, setting, out["log"], out["user_log"])) if out.get("user_log")
             else [HEADER, *map(row_line, out["log"])])
    return "\n".join(table + [f"{len(out['log'])} interactions, {out['missed']} missed"])


# -- is the robot there? ----------------------------------------------------------------------
def probe_robot(url: str, bound: float, user: str | None = None, password: str | None = None,
                shown: float | None = None) -> None:
    """Raise WorldConfigError (one line) unless ``url`` answers as NAOqi (an ALMemory service) within
    ``bound`` s: a malformed URL, an unknown host, a refused connection, a port that is not NAOqi, or silence."""
    from urllib.parse import urlsplit

    try:
        u = urlsplit(url)
        host, port = u.hostname, u.port
    except ValueError:
        host = port = None
    if u.scheme not in ("tcp", "tcps") or not host or not port:
        raise WorldConfigError(f"cannot reach the robot at {url}: not a NAOqi URL (tcp://HOST:9559 or tcps://HOST:9503)")
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
    err = WorldConfigError(f"cannot reach the robot at {url}: "
                           + result.get("error", f"no answer within {shown or bound:g} s (connect_bound)"))
    err.hard_exit = True  # libqi's threads may abort the interpreter's teardown after a failed session
    raise err

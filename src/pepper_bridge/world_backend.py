"""A (stand-in) Pepper as a world of the graph (``homeo_decision.world_api.WorldBackend``), no rclpy.

A :class:`~pepper_bridge.environment.PepperEnvironment` over a :class:`~pepper_bridge.bridge.PepperBridge`
in message fields: the user's first expression before tick 0, observations out, actions in,
outcomes out; the interaction log (one row per interaction: what the decision chose it for,
``m_dom`` and the intention, and what the robot did and heard), the link's state and the robot's
rejected values on /diagnostics, and the device commands of the config. The robot sets the
pace: every robot call may block (``blocking``), so the world node runs them on a worker thread;
qi calls never run on the executor, and nothing on a qi thread touches ROS.

Its part of the run's checkpoint is the interaction log and the interactions done: the world
itself lives on the robot, which goes on by itself while the node is down.
"""

from __future__ import annotations

import json
from contextlib import contextmanager

from homeo_decision import codec
from homeo_decision.checkpoint import CheckpointError, check_int
from homeo_decision.environment import Outcome
from homeo_decision.world_api import WorldBackend, WorldConfigError
from homeo_msgs_py.diagnostics import ERROR, OK, WARN
from homeo_msgs_py.params import ParamSpec

from . import launch_support
from .config import DEFAULT_URL

STANDIN_SERVICE = "HomeoStandin"  # the stand-in's control service (not NAOqi; a real robot has none)
ROW_STR = ("m_dom", "intention", "proposal", "reason", "cue_intention")  # what the launcher prints: text or null


class PepperWorld(WorldBackend):
    """A SoftBank Pepper over NAOqi (a robot at --qi-url, or --standin); its result: the interaction log."""

    NAME = "pepper"
    blocking = FAILS_STEPS = DROPS_LINK = True
    RESETS = False  # the robot's world goes on: a reset starts a new log
    TICKS = ("interactions", 0)  # 0: until the scripted user is done, or Ctrl-C on a robot
    INTENTIONS = launch_support.INTENTIONS
    LAUNCH = launch_support.LAUNCH
    LOG_HEADER = launch_support.HEADER
    PARAMS = (
        ParamSpec("qi_url", DEFAULT_URL, "NAOqi URL (tcp://host:9559, or tcps://host:9503 with user/password)",
                  fixed=True),
        ParamSpec("user", "", "NAOqi 2.9 user ('' = no authentication)", fixed=True),
        ParamSpec("password", "", "NAOqi 2.9 password", fixed=True),
        ParamSpec("config", "", "the robot's meaning of the scenario's names ('' = scripts/pepper.json)", fixed=True),
        ParamSpec("battery_source", "memory", "where the battery is read: ALMemory's battery fraction or "
                  "ALBattery.getBatteryCharge", choices=("memory", "albattery"), fixed=True, eq="Sec 4.3.1"),
        ParamSpec("collect_window", 3.0, "longest wait for the user's reaction (s; a launch's default: 3 with the "
                  "stand-in, 8 on a robot)", 0.0, 600.0),
        ParamSpec("collect_quiet", 0.15, "a gap without robot events that ends the wait early (s; = collect_window: "
                  "wait it out; a launch's default: 0.15 with the stand-in, the whole window on a robot)", 0.0, 600.0),
        ParamSpec("anger_threshold", -1.0, "voice anger level above this is a scolding, on naoqi_version's scale: "
                  "0..10 (NAOqi 2.5+, and auto, rescaled to the robot's) or 0..5 (2.1/2.4) (-1 = the config's)",
                  -1.0, 10.0, eq="Eq 3.22"),
        ParamSpec("naoqi_version", "", "the robot's NAOqi version, for its documented formats: auto = ask the robot "
                  "(ALSystem.systemVersion); '' = the config's", fixed=True),
        ParamSpec("word_confidence", 0.4, "lowest confidence of a recognised word", 0.0, 1.0),
        ParamSpec("intention_cues", True, "put the intention recognised from the config's keyword/gesture cues in "
                  "the observation (the intention node's oracle mode needs it)"),
        ParamSpec("end_with_script", False, "stand-in only: end the run when the stand-in's scripted user is done",
                  fixed=True),
        ParamSpec("connect_timeout", 5.0, "seconds per connection attempt", 0.1, 600.0, fixed=True),
        ParamSpec("backoff_max", 10.0, "longest pause between reconnection attempts", 0.1, 600.0, fixed=True),
    )

    def __init__(self, sc, values: dict):
        import qi

        from .bridge import PepperBridge
        from .config import ConfigError, LinkSettings, load_config
        from .environment import PepperEnvironment
        from .mapping import AUTO_NAOQI, emotion_scale

        super().__init__(sc, values)
        v = values
        qi.logging.setLevel(qi.logging.WARNING)
        try:
            cfg = load_config(v["config"] or None, scenario=sc)
        except ConfigError as exc:
            raise WorldConfigError(str(exc)) from None
        if v["naoqi_version"]:
            if v["naoqi_version"] != AUTO_NAOQI:
                try:
                    emotion_scale(v["naoqi_version"])
                except ValueError as exc:
                    raise WorldConfigError(f"parameter naoqi_version: {exc} or {AUTO_NAOQI!r}") from None
            cfg.naoqi_version = v["naoqi_version"]
        if v["anger_threshold"] >= 0:
            if v["anger_threshold"] >= cfg.threshold_scale:
                raise WorldConfigError(f"parameter anger_threshold: {v['anger_threshold']} is not below the top of its "
                                       f"scale 0..{cfg.threshold_scale} (naoqi_version {cfg.naoqi_version})")
            cfg.anger_threshold = v["anger_threshold"]
        cfg.word_confidence = v["word_confidence"]
        settings = LinkSettings(url=v["qi_url"], user=v["user"] or None, password=v["password"] or None,
                                connect_timeout=v["connect_timeout"], backoff_max=v["backoff_max"],
                                battery_source=v["battery_source"])
        self._devices: list = []  # device commands from the worker thread; the node publishes them
        self.bridge = PepperBridge(cfg, settings, sc, device_callback=self._on_device)
        self.env = PepperEnvironment(self.bridge, quiet=v["collect_quiet"], window=v["collect_window"],
                                     use_cues=v["intention_cues"])
        self.end_with_script = v["end_with_script"]
        self.link = self.bridge.status()
        self.log: list = []
        self.user_done = False  # the stand-in's scripted user has no more interactions
        self.user_log: list = []  # its judgement of each robot action (the stand-in's HomeoStandin.userLog)
        self._standin = None
        self._acting: dict | None = None  # the action message being performed
        self._tick = 0
        self.bridge.start(None)  # the supervisor connects in the background, with back-off

    # -- the lockstep -----------------------------------------------------------------------------
    def start(self) -> None:
        self.env.reset()

    def step(self, action_fields: dict | None) -> dict:
        self._acting, self._tick = action_fields, self.env.tick
        name = action_fields.get("action") if action_fields is not None else None
        out = self.env.step(self.sc.action_index(name) if name is not None else None)
        self._row(action_fields)
        self.last_missed = bool(self.env.last_row.get("missed"))
        if self.end_with_script:
            self.user_done = self._standin_user_done()
        return codec.outcome_fields(self.sc, out)

    def step_failed(self, action_fields: dict | None, reason: str) -> dict:
        name = action_fields.get("action") if action_fields is not None else None
        out = self.env.failed(self.sc.action_index(name) if name is not None else None, reason)
        self._row(action_fields)
        self.last_missed = True
        return codec.outcome_fields(self.sc, out)

    def status(self, done: bool) -> dict:
        link = self.env.bridge.status()
        return {"extra": {"log": list(self.log), "interactions_done": self.env.tick,
                          "robot": {k: link.get(k) for k in ("state", "connected", "reason", "url", "connects", "drops",
                                                             "freezes")},
                          "robot_missed": sum(1 for r in self.log if r.get("missed")), "naoqi": self.env.bridge.naoqi(),
                          **({"user_log": self.user_log} if done and self.user_log else {})}}

    def _row(self, action_fields: dict | None) -> None:
        from .environment import MAX_LOG_ROWS

        r = dict(self.env.last_row)
        f = action_fields or {}
        rec = f.get("intention")  # what the decision acted on (the recogniser's), else what the cues named
        r["m_dom"] = f.get("m_dom")
        r["drives"] = f.get("drives")  # the drives the decision chose with (the body's, read this tick)
        r["intention"] = (None if rec == self.sc.intention_names[0] else rec) if rec is not None else r["cue_intention"]
        self.log.append(r)
        del self.log[:-MAX_LOG_ROWS]
        failed = not r.get("ok", True) and r.get("action") is not None
        self.last_failure = f"{r['action']} failed: {r.get('reason') or 'no reason given'}" if failed else None

    def _standin_user_done(self) -> bool:
        """The stand-in's scripted user is done (on a real robot there is no such service: False); its
        judgement so far kept for the run's result."""
        session = self.bridge.link.session
        if session is None:
            return False
        try:
            if self._standin is None or self._standin[0] is not session:
                self._standin = (session, session.service(STANDIN_SERVICE))
            self.user_log = [dict(r) for r in self._standin[1].userLog()]
            return bool(self._standin[1].state()["user_done"])
        except RuntimeError:
            return False

    # -- the run ----------------------------------------------------------------------------------
    def reset(self, seed: int | None) -> None:
        self.log, self.user_done = [], False  # the robot's world goes on: a new run only restarts the log

    # -- the front ends (launch_support) --------------------------------------------------------------
    @classmethod
    def plan(cls, sc, given: dict, workdir: str):
        return launch_support.plan(sc, given, workdir, cls.PARAMS)

    @classmethod
    def log_line(cls, row: dict) -> str:
        return launch_support.row_line(row)

    @classmethod
    def result(cls, sc, status: dict, setting: dict) -> dict | None:
        return launch_support.result(sc, status, setting)

    @classmethod
    def result_text(cls, sc, result: dict, setting: dict) -> str:
        return launch_support.result_text(sc, result, setting)

    def ready(self) -> list[str]:
        if self.bridge.link.connected:
            return []
        link = self.link
        return [f"the robot at {link['url']} is {link['state']} ({link['reason']})"]

    def finished(self) -> bool:
        return self.user_done

    def set_param(self, name: str, value) -> str | None:
        env, cfg = self.env, self.bridge.cfg
        if name == "collect_window":
            env.window = value
        elif name == "collect_quiet":
            env.quiet = value
        elif name == "anger_threshold":
            if value >= cfg.threshold_scale:
                return f"anger_threshold must be below {cfg.threshold_scale} (naoqi_version {cfg.naoqi_version})"
            if value >= 0:
                cfg.anger_threshold = value  # the event parser reads it per event
        elif name == "word_confidence":
            cfg.word_confidence = value
        elif name == "intention_cues":
            env.use_cues = value
        return None

    def poll(self) -> list[tuple[str, str]]:
        from .events import STATUS

        out = []
        for e in self.env.notices():
            if e.kind == STATUS:
                self.link = dict(e.value)
                if e.value["state"] == "connected":
                    out.append(("info", f"robot connected: {e.value['reason']}"))
                else:
                    out.append(("warning", f"robot {e.value['state']}: {e.value['reason']}"))
            else:
                out.append(("burst", f"rejected a value from the robot: {e.value['source']} = {e.value['value']}: "
                                       f"{e.value['reason']}"))
        return out

    def _on_device(self, device: str, command: str) -> None:  # the worker thread: queue it, the node publishes
        action = (self._acting or {}).get("action")  # the action message being performed
        self._devices.append({"device": device, "command": command, "action": action, "tick": self._tick})

    def devices(self) -> list[dict]:
        out = []
        while self._devices:
            out.append(self._devices.pop(0))
        return out

    def diagnostics(self) -> list[dict]:
        """The link and the bridge's diagnostics snapshot as one DiagnosticStatus (plain dict)."""
        snap = self.bridge.diagnostics.snapshot()
        link = self.link
        values = {"state": str(link.get("state")), "connected": str(bool(link.get("connected"))).lower(),
                  "url": str(link.get("url")), "reason": str(link.get("reason")), "connects": str(link.get("connects")),
                  "drops": str(link.get("drops")), "freezes": str(link.get("freezes", 0)),
                  "polled_keys": str(len(link.get("polled_keys") or [])), "rejected_total": str(snap["rejected_total"])}
        naoqi = self.bridge.naoqi()
        values.update({"naoqi_version": f"{naoqi['version']} ({naoqi['source']})",
                       "emotion_scale": f"0..{naoqi['emotion_scale']}", "anger_level": f"{naoqi['anger_level']:g}"})
        values.update({f"rejected {s}": str(n) for s, n in sorted(snap["rejected_by_source"].items())})
        values.update({f"incident {s}": str(n) for s, n in sorted(snap["incidents"].items())})
        values.update({f"unknown {ch} symbols": str(n) for ch, n in sorted(self.env.dropped.items())})
        if snap["recent"]:
            values["recent"] = json.dumps(snap["recent"][-8:])
        if not link.get("connected"):
            level, msg = ERROR, f"robot {link.get('state')}: {link.get('reason')}"
        elif snap["rejected_total"] or snap["incidents"]:
            level = WARN
            msg = f"connected; rejected {snap['rejected_total']} value{'s' if snap['rejected_total'] != 1 else ''}"
            if snap["incidents"]:
                msg += f", {sum(snap['incidents'].values())} incidents"
        else:
            level, msg = OK, "connected"
        return [{"name": "homeo_world: robot", "hardware_id": str(link.get("url")), "level": level, "message": msg,
                 "values": values}]

    def close(self) -> None:
        self.bridge.stop()

    @classmethod
    @contextmanager
    def test_double(cls, sc, values: dict):
        """A stand-in Pepper over a real libqi session on loopback, time frozen, with the field test's
        scripted user; it drops its link on request (``StandinRobot.drop_for``)."""
        import qi

        from .config import load_config
        from .standin import StandinRobot
        from .user import load_script

        qi.logging.setLevel(qi.logging.ERROR)  # libqi logs to stdout: a checker's or a test's output stays its own
        robot = StandinRobot(load_config(values["config"] or None, scenario=sc), load_script("field_user.json"),
                             seed=values["seed"], time_scale=0.0, scenario=sc)
        try:
            yield dict(values, qi_url=robot.start(), collect_window=2.0, collect_quiet=0.15), robot.drop_for
        finally:
            robot.close()

    # -- the run's checkpoint ---------------------------------------------------------------------
    def state(self) -> tuple[None, dict]:
        return None, {"log": list(self.log), "interactions_done": self.env.tick}

    def set_state(self, rng, st, tick: int) -> None:
        if not isinstance(st, dict):
            raise ValueError("the world's state must be an object")
        rows = check_rows(st.get("log"), self.sc)
        done = check_int(st.get("interactions_done"), "interactions_done", 0, 10**9)
        if done != tick:
            raise CheckpointError(f"tick {tick} is not the robot's {done} interactions done")
        self.log = list(rows)
        self.env.tick = done

    def rejoin(self, tick: int, lost: int, step_lost) -> dict | None:
        self.env.tick = tick  # the interactions go on being numbered from here
        if not lost:
            return None
        # the robot went on meanwhile; the node saw none of it
        return codec.outcome_fields(self.sc, Outcome(None, 0, None, None, None))


def check_rows(rows, sc) -> list:
    """An interaction log from a checkpoint, checked row by row (CheckpointError: one line)."""
    from .environment import MAX_LOG_ROWS

    if not isinstance(rows, list) or len(rows) > MAX_LOG_ROWS:
        raise CheckpointError(f"log must be a list of at most {MAX_LOG_ROWS} rows")
    actions = set(sc.action_names)
    for r in rows:
        if not isinstance(r, dict):
            raise CheckpointError("a log row that is not an object")
        check_int(r.get("interaction"), "a log row's interaction", 1, 10**9)
        if r.get("action") is not None and r.get("action") not in actions:
            raise CheckpointError(f"a log row's action {str(r.get('action'))[:40]!r} is not the scenario's")
        if type(r.get("ok")) is not bool or type(r.get("missed")) is not bool or r.get("feedback") not in (-1, 0, 1) \
                or type(r.get("feedback")) is not int:
            raise CheckpointError("a log row's ok, missed or feedback is malformed")
        if any(r.get(k) is not None and not isinstance(r.get(k), str) for k in ROW_STR):
            raise CheckpointError(f"a log row's {', '.join(ROW_STR)} must be text or null")
    return rows

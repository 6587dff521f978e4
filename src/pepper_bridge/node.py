"""``pepper_bridge`` node: a (stand-in) Pepper in the place of ``homeo_sim``.

Publishes  /homeo/world (state: what the robot read, ``body`` with battery_percent,
           temperature_status, NEng, NRes), /homeo/observation (event: gesture, movement,
           keyword and the cue-recognised intention), /homeo/outcome (event: action, feedback
           +1/-1/0, proposal, clarified_intention, body after the action), /homeo/run_status
           (state: iterations, done, missed, state; ``extra``: the interaction log, the link),
           /homeo/device (std_msgs/String JSON ``{"device", "command", "action", "tick", "stamp"}``
           for Play/Stop/LightOn/LightOff), /diagnostics (input health, and "pepper_bridge: robot":
           connection state, rejected robot values, incidents)
Subscribes /homeo/action (tick k's action)
Parameters qi_url, user, password (NAOqi 2.9 tcps), config (places/phrases file, '' = shipped),
           battery_source (memory | albattery), interactions (0 = until stopped),
           collect_window (s, the longest wait for the user's reaction), collect_quiet (s, a gap
           without events that ends the wait early), action_timeout (s), anger_threshold,
           word_confidence, intention_cues (put the cue-recognised intention in the observation,
           as the intention node's oracle mode needs), end_with_script (stand-in only: end when its
           scripted user is done), wait_for_readers, outcome_readers, scenario, overrides

Tick k (the bridge sets the pace): read the robot (a worker thread: qi calls never run on the
executor, and nothing on a qi thread touches ROS), publish observation(k) and world(k); wait for
action(k) (a timeout counts as no action); execute it on the robot (worker thread); collect the
user's reaction from the event queue (drained by a ROS timer) until ``collect_quiet`` passes
without an event or ``collect_window`` is over; publish outcome(k); tick k+1. After the last
interaction a world with ``final`` lets the decision node learn from the last answer.

When the robot is unavailable the node says so on /diagnostics and waits; the bridge core
reconnects with back-off and the tick resumes where it stopped.
"""

from __future__ import annotations

import json
import sys
import time
from concurrent.futures import Future, ThreadPoolExecutor

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor, SetParametersResult
from std_msgs.msg import String

from homeo_msgs_py.diagnostics import ERROR, OK, WARN
from homeo_msgs_py.node_base import HomeoNode, NodeConfigError, run_node
from homeo_msgs_py.qos import EVENT, quiet_pub_events
from homeo_msgs_py.schemas import Message, Rejected
from homeo_msgs_py.topics import ACTION, OBSERVATION, OUTCOME, RUN_STATUS, WORLD

DEVICE = "/homeo/device"  # std_msgs/String, plain JSON (not a homeo schema)
READERS = {WORLD: 1, OBSERVATION: 1, OUTCOME: 1}  # 2 when the intention node learns (bayes)
POLL_S = 0.02
STATUS_PERIOD_S = 0.5
MAX_LOG_ROWS = 1000  # in run_status; an unbounded run keeps the newest


def _float(lo, hi, text, read_only=False):
    return ParameterDescriptor(description=text, read_only=read_only,
                               floating_point_range=[FloatingPointRange(from_value=lo, to_value=hi)])


def _int(lo, hi, text, read_only=False):
    return ParameterDescriptor(description=text, read_only=read_only,
                               integer_range=[IntegerRange(from_value=lo, to_value=hi, step=1)])


class BridgeNode(HomeoNode):
    def __init__(self):
        super().__init__("pepper_bridge")
        import qi

        from .bridge import PepperBridge
        from .config import DEFAULT_URL, ConfigError, LinkSettings, load_config
        from .field import IntentionCues

        qi.logging.setLevel(qi.logging.WARNING)
        D = ParameterDescriptor
        self.declare_parameter("qi_url", DEFAULT_URL, D(description="NAOqi URL (tcp://host:9559, or tcps://host:9503 "
                                                                    "with user/password)", read_only=True))
        self.declare_parameter("user", "", D(description="NAOqi 2.9 user ('' = no authentication)", read_only=True))
        self.declare_parameter("password", "", D(description="NAOqi 2.9 password", read_only=True))
        self.declare_parameter("config", "", D(description="places/phrases file ('' = scripts/pepper.json)",
                                               read_only=True))
        self.declare_parameter("battery_source", "memory", D(
            description="memory (ALMemory battery fraction) or albattery (ALBattery.getBatteryCharge)", read_only=True))
        self.declare_parameter("interactions", 0, _int(0, 10**9, "interactions per run (0 = until stopped)"))
        self.declare_parameter("collect_window", 3.0, _float(0.0, 600.0, "longest wait for the user's reaction (s)"))
        self.declare_parameter("collect_quiet", 0.15, _float(0.0, 600.0, "a gap without robot events that ends the "
                                                                        "wait early (s; = collect_window: wait it out)"))
        self.declare_parameter("action_timeout", 5.0, _float(0.01, 3600.0, "seconds to wait for an action before the "
                                                                          "interaction counts as no action"))
        self.declare_parameter("anger_threshold", 0.5, _float(0.0, 1.0, "voice anger above this is a scolding"))
        self.declare_parameter("word_confidence", 0.4, _float(0.0, 1.0, "lowest confidence of a recognised word"))
        self.declare_parameter("intention_cues", True, D(
            description="put the intention recognised from the config's keyword/gesture cues in the observation "
                        "(the intention node's oracle mode needs it)"))
        self.declare_parameter("end_with_script", False, D(
            description="stand-in only: end the run when the stand-in's scripted user is done", read_only=True))
        self.declare_parameter("wait_for_readers", True, D(description="start only when the graph's readers and "
                                                                      "writers have matched"))
        self.declare_parameter("outcome_readers", READERS[OUTCOME], _int(0, 100, "readers of /homeo/outcome to wait for "
                                                                           "(2 when the intention node learns)"))
        self.declare_parameter("connect_timeout", 5.0, _float(0.1, 600.0, "seconds per connection attempt",
                                                              read_only=True))
        self.declare_parameter("backoff_max", 10.0, _float(0.1, 600.0, "longest pause between reconnection attempts",
                                                           read_only=True))
        p = lambda n: self.get_parameter(n).value  # noqa: E731
        if p("battery_source") not in ("memory", "albattery"):
            raise NodeConfigError(f"parameter battery_source: {p('battery_source')!r} is not memory or albattery")
        try:
            self.cfg = load_config(p("config") or None, actions=tuple(self.sc.action_names))
        except ConfigError as exc:
            raise NodeConfigError(str(exc)) from None
        self.cfg.anger_threshold = p("anger_threshold")
        self.cfg.word_confidence = p("word_confidence")
        try:
            self.cues = IntentionCues(self.cfg.intention_cues, self.sc.intention_names[1:])
        except ValueError as exc:
            raise NodeConfigError(f"config {self.cfg.source}: {exc}") from None
        settings = LinkSettings(url=p("qi_url"), user=p("user") or None, password=p("password") or None,
                                connect_timeout=p("connect_timeout"), backoff_max=p("backoff_max"),
                                battery_source=p("battery_source"))
        self._devices: list = []  # device commands from the worker thread; published by the timer
        self.bridge = PepperBridge(self.cfg, settings, self.sc, device_callback=self._on_device)
        self.interactions = p("interactions")
        self.window, self.quiet = p("collect_window"), p("collect_quiet")
        self.timeout = p("action_timeout")
        self.use_cues = p("intention_cues")
        self.end_with_script = p("end_with_script")
        self.add_on_set_parameters_callback(self._on_params)

        self.pub_world = self.publisher(WORLD)
        self.pub_obs = self.publisher(OBSERVATION)
        self.pub_outcome = self.publisher(OUTCOME)
        self.pub_status = self.publisher(RUN_STATUS)
        self.pub_device = self.create_publisher(String, DEVICE, EVENT, event_callbacks=quiet_pub_events())
        self.subscribe(ACTION, self._on_action)

        self.worker = ThreadPoolExecutor(max_workers=1, thread_name_prefix="pepper-io")
        self.run = 0
        self.k = 0
        self.state = "waiting"  # waiting -> greeting -> running -> finishing -> done
        self.phase = ""  # within a tick: read -> act -> exec -> collect
        self.missed = 0
        self.log: list = []
        self.link = self.bridge.status()
        self._job: Future | None = None
        self._job_kind = ""
        self._retry_at = 0.0
        self._buffer: list = []  # robot events since the last outcome
        self._last_event = 0.0
        self._collect_from = 0.0
        self._tick_info: dict = {}
        self._since = time.monotonic()
        self._logged = 0.0
        self._status_dirty = True
        self._status_at = 0.0
        self._standin = None
        self.bridge.start(None)  # the supervisor connects in the background, with back-off
        self.create_timer(POLL_S, self._poll)

    def _on_device(self, device: str, command: str) -> None:  # worker thread: queue it, the timer publishes
        self._devices.append((device, command, self._tick_info.get("action"), self.k))

    # -- parameters -------------------------------------------------------------------
    def _on_params(self, params) -> SetParametersResult:
        for prm in params:
            if prm.name == "interactions":
                self.interactions = prm.value  # at or below the current interaction: this one is the last
            elif prm.name == "collect_window":
                self.window = prm.value
            elif prm.name == "collect_quiet":
                self.quiet = prm.value
            elif prm.name == "action_timeout":
                self.timeout = prm.value
            elif prm.name == "anger_threshold":
                self.cfg.anger_threshold = prm.value  # the event parser reads it per event
            elif prm.name == "word_confidence":
                self.cfg.word_confidence = prm.value
            elif prm.name == "intention_cues":
                self.use_cues = prm.value
        return SetParametersResult(successful=True)

    # -- the ROS timer: events, status, the tick's phases -------------------------------
    def _poll(self) -> None:
        self._drain()
        self._flush_devices()
        now = time.monotonic()
        if self.state == "waiting":
            self._wait_start(now)
        elif self.state == "greeting":
            if self._collected(now):
                self._begin()
        elif self.state in ("running", "finishing"):
            self._step_phase(now)
        if self._status_dirty or now - self._status_at > STATUS_PERIOD_S * 4:
            if now - self._status_at >= STATUS_PERIOD_S or self.state == "done":
                self._publish_status()

    def _drain(self) -> None:
        from .events import REJECTED, STATUS

        changed = False
        for e in self.bridge.poll_events():
            if e.kind == STATUS:
                self.link = dict(e.value)
                changed = True
                if e.value["state"] == "connected":
                    self.get_logger().info(f"robot connected: {e.value['reason']}")
                else:
                    self.get_logger().warning(f"robot {e.value['state']}: {e.value['reason']}")
            elif e.kind == REJECTED:
                changed = True
                self.get_logger().warning(f"rejected a value from the robot: {e.value['source']} = {e.value['value']}: "
                                          f"{e.value['reason']}", throttle_duration_sec=1.0)
            else:
                self._buffer.append(e)
                self._last_event = max(self._last_event, e.t)
        if changed:
            self.publish_diagnostics()  # connection changes and rejections go out at once

    def _flush_devices(self) -> None:
        while self._devices:
            device, command, action, tick = self._devices.pop(0)
            self.pub_device.publish(String(data=json.dumps({"device": device, "command": command, "action": action,
                                                            "run": self.run, "tick": tick, "stamp": time.time()})))

    def _collected(self, now: float) -> bool:
        """The user's reaction is in: a quiet gap after the last event, or the window is over."""
        if now - self._collect_from >= self.window:
            return True
        return now - max(self._collect_from, self._last_event) >= self.quiet

    def _missing(self) -> list[str]:
        out = []
        if not self.bridge.link.connected:
            out.append(f"the robot at {self.link['url']} is {self.link['state']} ({self.link['reason']})")
        if not self.get_parameter("wait_for_readers").value:
            return out
        for pub, topic in ((self.pub_world, WORLD), (self.pub_obs, OBSERVATION), (self.pub_outcome, OUTCOME)):
            want = self.get_parameter("outcome_readers").value if topic == OUTCOME else READERS[topic]
            if pub.matched() < want:
                out.append(f"{topic} has {pub.matched()}/{want} readers")
        if self.count_publishers(ACTION) < 1:
            out.append(f"{ACTION} has no writer")
        return out

    def _wait_start(self, now: float) -> None:
        missing = self._missing()
        if not missing:
            self.state = "greeting"  # the user's first expression (it starts when the robot listens)
            self._collect_from = now
            self._status_dirty = True
        elif now - self._logged > 2.0:
            self._logged = now
            self.get_logger().info("waiting: " + "; ".join(missing))

    def _begin(self) -> None:
        self.state = "running"
        self._t_begin = time.monotonic()
        self.get_logger().info(f"run {self.run}: {self.interactions or 'unbounded'} interactions on {self.link['url']}")
        self._start_tick()

    def _start_tick(self) -> None:
        self.phase = "read"
        self._submit("read", self._read_job)

    def _submit(self, kind: str, fn, *args) -> None:
        self._job_kind = kind
        self._job = self.worker.submit(fn, *args)

    def _step_phase(self, now: float) -> None:
        if self._job is not None:
            if not self._job.done():
                return
            job, kind = self._job, self._job_kind
            self._job = None
            try:
                result = job.result()
            except Exception as exc:  # RobotUnavailable, or anything the robot threw at us
                self._job_failed(kind, exc, now)
                return
            if kind == "read":
                self._after_read(result)
            elif kind == "exec":
                self._after_exec(result, now)
            return
        if self.phase == "read" and now >= self._retry_at and self.bridge.link.connected:
            self._start_tick()
        elif self.phase == "act" and now - self._since > self.timeout:
            if self.state == "finishing":
                self.rejects.note("missed final")
                self._finish()
                return
            self.missed += 1
            self.rejects.note("missed ticks")
            self.get_logger().warning(f"no action for interaction {self.k} within {self.timeout:g} s: counted as none")
            self._act(None, None)
        elif self.phase == "collect" and self._collected(now):
            self._conclude()

    def _job_failed(self, kind: str, exc: Exception, now: float) -> None:
        from .naoqi_link import RobotUnavailable

        why = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        if kind == "read":  # retried when the robot is back (the core reconnects with back-off)
            if not isinstance(exc, RobotUnavailable):
                self.bridge.diagnostics.incident("read_world", why)
            self.rejects.note("reads retried")
            self.get_logger().warning(f"reading the robot failed ({why}); interaction {self.k} waits",
                                      throttle_duration_sec=2.0)
            self.phase, self._retry_at = "read", now + 0.5
            self._status_dirty = True
        else:  # execute() reports failures itself; anything else: nothing was done
            self.bridge.diagnostics.incident("execute", why)
            self._after_exec({"action": self._tick_info.get("action"), "ok": False, "reason": why, "calls": [],
                              "body": None}, now)

    # -- robot I/O (worker thread: qi calls only, no ROS) ----------------------------------
    def _read_job(self) -> dict:
        world = self.bridge.read_world()
        done = self._standin_user_done() if self.end_with_script else False
        return {"world": world, "user_done": done}

    def _exec_job(self, action: str | None) -> dict:
        res = self.bridge.execute(action) if action is not None else {"action": None, "ok": True, "reason": None,
                                                                       "calls": []}
        try:
            body = self.bridge.read_body()
        except Exception:
            body = None
        return dict(res, body=body)

    def _standin_user_done(self) -> bool:
        """The stand-in's scripted user has no more interactions (HomeoStandin is the stand-in's
        control service, not NAOqi; on a real robot there is none and this is False)."""
        session = self.bridge.link.session
        if session is None:
            return False
        try:
            if self._standin is None or self._standin[0] is not session:
                self._standin = (session, session.service("HomeoStandin"))
            return bool(self._standin[1].state()["user_done"])
        except RuntimeError:
            return False

    # -- the tick ---------------------------------------------------------------------------
    def _after_read(self, r: dict) -> None:
        world = r["world"]
        body = {k: v for k, v in world["body"].items() if v is not None}
        missing = [d.name for d in self.sc.drives if d.source == "body" and d.name not in body]
        if missing:  # no good reading yet (e.g. a wrongly typed battery from the start): wait
            self.rejects.note("reads without a valid body")
            self.get_logger().warning(f"no valid reading of {', '.join(missing)} yet; interaction {self.k} waits",
                                      throttle_duration_sec=2.0)
            self.phase, self._retry_at = "read", time.monotonic() + 0.5
            return
        world = dict(world, body=body)
        final = self.state == "running" and (bool(self.interactions) and self.k >= self.interactions
                                             or r["user_done"])
        if final:
            self.state = "finishing"
            if r["user_done"]:
                self.get_logger().info(f"the scripted user is done after {self.k} interactions")
        events, self._buffer = self._buffer, []
        obs = self.bridge.observation(events)
        intention = self.cues(obs)
        fields = self._known_symbols(obs)
        if self.use_cues:
            fields["intention"] = intention or "none"
        if self.state == "finishing":
            world["final"] = True
        self._tick_info = {"intention": intention, "observation": obs, "world": world}
        self.phase = "act"
        self._since = time.monotonic()
        self.send(self.pub_obs, self.k, fields, self.run)
        self.send(self.pub_world, self.k, world, self.run)
        self._status_dirty = True

    def _known_symbols(self, obs: dict) -> dict:
        """The observation with symbols outside the scenario's alphabets left out (unobserved):
        the recogniser rejects unknown symbols, and one stray word must not cost a tick."""
        alph = getattr(self.sc.observations, "alphabets", None) if getattr(self.sc, "observations", None) else None
        out = dict(obs)
        if alph:
            for ch, v in obs.items():
                if v is not None and ch in alph and v not in alph[ch]:
                    out[ch] = None
                    self.rejects.note(f"unknown {ch} symbols")
        return out

    def _on_action(self, msg: Message) -> None:
        if self.state not in ("running", "finishing"):
            raise Rejected(f"no run in progress (state {self.state})")
        if msg.run != self.run:
            raise Rejected(f"run {msg.run} is not the current run {self.run}")
        if msg.tick < self.k:
            raise Rejected(f"stale tick {msg.tick} (now at interaction {self.k})")
        if msg.tick > self.k:
            raise Rejected(f"tick {msg.tick} is ahead of the run (now at interaction {self.k})")
        if self.phase != "act":
            raise Rejected(f"an action for tick {msg.tick} while the robot is in phase {self.phase!r}")
        f = msg.fields
        if bool(f.get("final")) != (self.state == "finishing"):
            raise Rejected("a final message before the run's end" if f.get("final")
                           else f"an action after the run's end at interaction {self.k}")
        if self.state == "finishing":
            self._finish()
            return
        self._act(f["action"], f.get("m_dom"), f.get("intention"))

    def _act(self, action: str | None, m_dom: str | None, recognised: str | None = None) -> None:
        self._tick_info.update(action=action, m_dom=m_dom, recognised=recognised)
        self.phase = "exec"
        self._submit("exec", self._exec_job, action)

    def _after_exec(self, res: dict, now: float) -> None:
        if not res["ok"]:
            self.rejects.note("failed actions")
            self.get_logger().warning(f"{res['action']} failed: {res['reason']}")
        self._tick_info["exec"] = res
        self.phase = "collect"
        self._collect_from = now

    def _conclude(self) -> None:
        from .events import FEEDBACK, PROPOSAL

        info, res = self._tick_info, self._tick_info["exec"]
        events = self._buffer
        answer = [e for e in events if e.kind in (FEEDBACK, PROPOSAL)]
        self._buffer = [e for e in events if e.kind not in (FEEDBACK, PROPOSAL)]  # the next expression
        done = res["action"] if res["ok"] else None  # what the world saw (nothing when it failed)
        out = self.bridge.outcome(done, answer)
        body = {k: v for k, v in (res.get("body") or {}).items() if v is not None}
        if body:
            out["body"] = body
        self.send(self.pub_outcome, self.k, out, self.run)
        wb = info["world"]["body"]
        rec = info.get("recognised")  # what the decision acted on (the recogniser's), else what the cues named
        intention = (None if rec == "none" else rec) if rec is not None else info["intention"]
        self.log.append({"interaction": self.k + 1, "m_dom": info.get("m_dom"), "intention": intention,
                         "cue_intention": info["intention"],
                         "action": info.get("action"), "feedback": out["feedback"], "proposal": out["proposal"],
                         "ok": res["ok"], "location": info["world"]["robot"]["location"],
                         "battery_percent": wb.get("battery_percent"), "temperature_status": wb.get("temperature_status"),
                         "observation": info["observation"]})
        del self.log[:-MAX_LOG_ROWS]
        self.k += 1
        self._status_dirty = True
        self._start_tick()

    def _finish(self) -> None:
        self.state, self.phase = "done", ""
        self.elapsed = time.monotonic() - self._t_begin
        self._status_dirty = True
        self._publish_status()
        self.get_logger().info(f"run {self.run} done: {self.k} interactions, {self.missed} missed")

    # -- status and diagnostics ----------------------------------------------------------------
    def _publish_status(self) -> None:
        self._status_dirty = False
        self._status_at = time.monotonic()
        extra = {"log": self.log, "interactions_done": self.k, "phase": self.phase,
                 "robot": {k: self.link.get(k) for k in ("state", "connected", "reason", "url", "connects", "drops")}}
        if self.state == "done":
            extra["elapsed_s"] = self.elapsed
        self.send(self.pub_status, self.k, {"iterations": self.interactions, "done": self.state == "done",
                                            "missed": self.missed, "state": self.state, "extra": extra}, self.run)

    def extra_statuses(self) -> list[dict]:
        return [self.robot_status()]

    def robot_status(self) -> dict:
        """The link and the bridge's diagnostics snapshot as one DiagnosticStatus (plain dict)."""
        snap = self.bridge.diagnostics.snapshot()
        link = self.link
        values = {"state": str(link.get("state")), "connected": str(bool(link.get("connected"))).lower(),
                  "url": str(link.get("url")), "reason": str(link.get("reason")), "connects": str(link.get("connects")),
                  "drops": str(link.get("drops")), "polled_keys": str(len(link.get("polled_keys") or [])),
                  "rejected_total": str(snap["rejected_total"])}
        values.update({f"rejected {s}": str(n) for s, n in sorted(snap["rejected_by_source"].items())})
        values.update({f"incident {s}": str(n) for s, n in sorted(snap["incidents"].items())})
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
        return {"name": "pepper_bridge: robot", "hardware_id": str(link.get("url")), "level": level, "message": msg,
                "values": values}

    def destroy_node(self):
        try:
            self.bridge.stop()
        finally:
            self.worker.shutdown(wait=False, cancel_futures=True)
        return super().destroy_node()


def main(args=None) -> int:
    return run_node(BridgeNode, args)


if __name__ == "__main__":
    sys.exit(main())

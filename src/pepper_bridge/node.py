"""``pepper_bridge`` node: a (stand-in) Pepper in the place of ``homeo_sim``.

Publishes  homeo/world (state: what the robot read; ``body`` with the body drives and the raw
           battery_percent, temperature_status), homeo/observation (event: gesture, movement,
           keyword and, with intention_cues, the cue-recognised intention), homeo/outcome (event:
           action (none when it failed), feedback +1/-1/0, proposal, clarified_intention, body
           after the action), homeo/run_status (state: iterations, done, missed, state; ``extra``:
           the interaction log, the link, the phase), homeo/device (std_msgs/String JSON
           ``{"device", "command", "action", "run", "tick", "stamp"}`` for the config's device
           commands), /diagnostics (input health, and "pepper_bridge: robot": connection state,
           rejected robot values, incidents)
Subscribes homeo/action (tick k's action)
Parameters qi_url, user, password (NAOqi 2.9 tcps), config (the robot's meaning of the scenario's
           names, '' = shipped), battery_source (memory | albattery), interactions (0 = until
           stopped), collect_window (s, the longest wait for the user's reaction), collect_quiet
           (s, a gap without events that ends the wait early), action_timeout (s),
           anger_threshold, word_confidence, intention_cues (put the cue-recognised intention in
           the observation, as the intention node's oracle mode needs), end_with_script (stand-in
           only: end when its scripted user is done), wait_for_readers, outcome_readers,
           connect_timeout, backoff_max, scenario, overrides

The tick is ``homeo_msgs_py.lockstep.LockstepDriver`` over ``world_side.PepperWorldSide`` over
``environment.PepperEnvironment``; the bridge sets the pace: every robot call runs on one worker
thread (qi calls never run on the executor, and nothing on a qi thread touches ROS). This node
declares parameters, waits for the robot and the graph's readers (``homeo_msgs_py.graph``), and
wires topics, timers and diagnostics. When the robot is unavailable it says so on /diagnostics;
the bridge core reconnects with back-off and the tick resumes where it stopped.
"""

from __future__ import annotations

import json
import sys
import time
from concurrent.futures import ThreadPoolExecutor

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor, SetParametersResult
from std_msgs.msg import String

from homeo_decision import durable
from homeo_decision.node_runtime import ScenarioNode, run_scenario_node
from homeo_msgs_py import graph as G
from homeo_msgs_py.diagnostics import ERROR, OK, WARN
from homeo_msgs_py.lockstep import WAITING, LockstepDriver
from homeo_msgs_py.node_base import NodeConfigError
from homeo_msgs_py.qos import EVENT, quiet_pub_events

DESC = G.NODES["pepper_bridge"]
POLL_S = 0.02
STATUS_PERIOD_S = 0.5


def _float(lo, hi, text, read_only=False):
    return ParameterDescriptor(description=text, read_only=read_only,
                               floating_point_range=[FloatingPointRange(from_value=lo, to_value=hi)])


def _int(lo, hi, text, read_only=False):
    return ParameterDescriptor(description=text, read_only=read_only,
                               integer_range=[IntegerRange(from_value=lo, to_value=hi, step=1)])


class BridgeNode(durable.DurableWorld, ScenarioNode):
    def __init__(self):
        super().__init__(DESC.name)
        import qi

        from .bridge import PepperBridge
        from .config import DEFAULT_URL, ConfigError, LinkSettings, load_config
        from .environment import PepperEnvironment
        from .mapping import AUTO_NAOQI, emotion_scale
        from .world_side import PepperWorldSide

        qi.logging.setLevel(qi.logging.WARNING)
        D = ParameterDescriptor
        self.declare_fixed("qi_url", DEFAULT_URL, D(description="NAOqi URL (tcp://host:9559, or tcps://host:9503 "
                                                                    "with user/password)"))
        self.declare_fixed("user", "", D(description="NAOqi 2.9 user ('' = no authentication)"))
        self.declare_fixed("password", "", D(description="NAOqi 2.9 password"))
        self.declare_fixed("config", "", D(description="the robot's meaning of the scenario's names "
                                                           "('' = scripts/pepper.json)"))
        self.declare_fixed("battery_source", "memory", D(
            description="memory (ALMemory battery fraction) or albattery (ALBattery.getBatteryCharge)"))
        self.declare_parameter("interactions", 0, _int(0, G.TICKS_MAX, "interactions per run (0 = until stopped)"))
        self.declare_parameter("collect_window", 3.0, _float(0.0, 600.0, "longest wait for the user's reaction (s)"))
        self.declare_parameter("collect_quiet", 0.15, _float(0.0, 600.0, "a gap without robot events that ends the "
                                                                        "wait early (s; = collect_window: wait it out)"))
        self.declare_parameter("action_timeout", 5.0, _float(0.01, 3600.0, "seconds to wait for an action before the "
                                                                          "interaction counts as no action"))
        self.declare_parameter("anger_threshold", -1.0, _float(-1.0, 10.0, "voice anger level above this is a scolding, "
                                                                    "on naoqi_version's scale: 0..10 (NAOqi 2.5+, and "
                                                                    "auto, rescaled to the robot's) or 0..5 (2.1/2.4) "
                                                                    "(-1 = the config's)"))
        self.declare_fixed("naoqi_version", "", D(description="the robot's NAOqi version, for its documented "
                                                                  "formats: auto = ask the robot (ALSystem."
                                                                  "systemVersion); '' = the config's"))
        self.declare_parameter("word_confidence", 0.4, _float(0.0, 1.0, "lowest confidence of a recognised word"))
        self.declare_parameter("intention_cues", True, D(
            description="put the intention recognised from the config's keyword/gesture cues in the observation "
                        "(the intention node's oracle mode needs it)"))
        self.declare_fixed("end_with_script", False, D(
            description="stand-in only: end the run when the stand-in's scripted user is done"))
        self.declare_parameter("wait_for_readers", True, D(description="start only when the graph's readers and "
                                                                      "writers have matched"))
        self.declare_parameter("outcome_readers", G.readers("pepper", "outcome", False),
                               _int(0, 100, "readers of homeo/outcome to wait for (2 when the intention node learns)"))
        self.declare_fixed("connect_timeout", 5.0, _float(0.1, 600.0, "seconds per connection attempt"))
        self.declare_fixed("backoff_max", 10.0, _float(0.1, 600.0, "longest pause between reconnection attempts"))
        p = lambda n: self.get_parameter(n).value  # noqa: E731
        cfg_durable = durable.declare(self)  # checkpoints; a respawned bridge goes on with the run
        if p("battery_source") not in ("memory", "albattery"):
            raise NodeConfigError(f"parameter battery_source: {p('battery_source')!r} is not memory or albattery")
        try:
            cfg = load_config(p("config") or None, scenario=self.sc)
        except ConfigError as exc:
            raise NodeConfigError(str(exc)) from None
        if p("naoqi_version"):
            if p("naoqi_version") != AUTO_NAOQI:
                try:
                    emotion_scale(p("naoqi_version"))
                except ValueError as exc:
                    raise NodeConfigError(f"parameter naoqi_version: {exc} or {AUTO_NAOQI!r}") from None
            cfg.naoqi_version = p("naoqi_version")
        if p("anger_threshold") >= 0:
            if p("anger_threshold") >= cfg.threshold_scale:
                raise NodeConfigError(f"parameter anger_threshold: {p('anger_threshold')} is not below the top of "
                                      f"its scale 0..{cfg.threshold_scale} (naoqi_version {cfg.naoqi_version})")
            cfg.anger_threshold = p("anger_threshold")
        cfg.word_confidence = p("word_confidence")
        settings = LinkSettings(url=p("qi_url"), user=p("user") or None, password=p("password") or None,
                                connect_timeout=p("connect_timeout"), backoff_max=p("backoff_max"),
                                battery_source=p("battery_source"))
        self._devices: list = []  # device commands from the worker thread; published by the timer
        self.bridge = PepperBridge(cfg, settings, self.sc, device_callback=self._on_device)
        self.env = PepperEnvironment(self.bridge, quiet=p("collect_quiet"), window=p("collect_window"),
                                     use_cues=p("intention_cues"))
        self.side = PepperWorldSide(self.env, end_with_script=p("end_with_script"))
        # the Bayesian recogniser learns from the outcome: one more reader of it (the launcher says so)
        self.learning = p("outcome_readers") > G.readers("pepper", "outcome", False)
        self.pubs = {key: self.publisher(key) for key in DESC.publishes}
        self.pub_device = self.create_publisher(String, G.DEVICE, EVENT, event_callbacks=quiet_pub_events())
        self.worker = ThreadPoolExecutor(max_workers=1, thread_name_prefix="pepper-io")
        self.driver = LockstepDriver(self.side, self._send, iterations=p("interactions"),
                                     timeout=p("action_timeout"), run_async=self.worker.submit, log=self._log,
                                     note=self.rejects.note)
        self.driver.on_done = self._publish_status
        self.setup_durable_world(cfg_durable)
        self.link = self.bridge.status()
        self.add_on_set_parameters_callback(self._on_params)
        self.subscribe("action", self.driver.on_action)
        self._logged = 0.0
        self._status_at = 0.0
        self._status_key = None
        self.bridge.start(None)  # the supervisor connects in the background, with back-off
        self.create_timer(POLL_S, self._poll)

    def _on_device(self, device: str, command: str) -> None:  # worker thread: queue it, the timer publishes
        action = (self.driver.last_action or {}).get("action")  # the action message being performed
        self._devices.append((device, command, action, self.driver.tick))

    def _send(self, key: str, tick: int, fields: dict, run: int) -> None:
        self.send(self.pubs[key], tick, fields, run)
        if key == "outcome" and self.side.log and self.side.log[-1]["interaction"] == tick + 1 \
                and not self.side.log[-1]["ok"]:
            row = self.side.log[-1]
            self.rejects.note("failed actions")
            self.get_logger().warning(f"{row['action']} failed: {row['reason']}")
        its = self.driver.iterations
        if key == "outcome" and self.side.user_done and (its == 0 or its > tick + 1):
            # the scripted user is done: the next world is the final one (the driver checks
            # iterations right after publishing this outcome)
            self.driver.iterations = tick + 1
            self.get_logger().info(f"the scripted user is done after {tick + 1} interactions")

    def _log(self, text: str) -> None:
        if "retrying" in text:  # a robot that is away: once every 2 s is enough
            self.get_logger().warning(text, throttle_duration_sec=2.0)
        else:
            self.get_logger().info(text)

    # -- parameters -------------------------------------------------------------------
    def _on_params(self, params) -> SetParametersResult:
        env, cfg = self.env, self.bridge.cfg
        for prm in params:
            if prm.name == "interactions":
                self.driver.iterations = prm.value  # at or below the current interaction: this one is the last
            elif prm.name == "collect_window":
                env.window = prm.value
            elif prm.name == "collect_quiet":
                env.quiet = prm.value
            elif prm.name == "action_timeout":
                self.driver.timeout = prm.value
            elif prm.name == "anger_threshold":
                if prm.value >= cfg.threshold_scale:
                    return SetParametersResult(successful=False, reason=f"anger_threshold must be below "
                                                                        f"{cfg.threshold_scale} (naoqi_version "
                                                                        f"{cfg.naoqi_version})")
                if prm.value >= 0:
                    cfg.anger_threshold = prm.value  # the event parser reads it per event
            elif prm.name == "word_confidence":
                cfg.word_confidence = prm.value
            elif prm.name == "intention_cues":
                env.use_cues = prm.value
        return SetParametersResult(successful=True)

    # -- the ROS timer: robot notices, device commands, the gate, the driver, the status -------
    def _poll(self) -> None:
        self._notices()
        self._flush_devices()
        drv = self.driver
        if drv.state == WAITING:
            missing = self._missing()
            if not missing:
                if not self.rejoin_due():
                    drv.begin()  # the user's first expression, on the worker thread
            elif time.monotonic() - self._logged > 2.0:
                self._logged = time.monotonic()
                self.get_logger().info("waiting: " + "; ".join(missing))
        else:
            drv.poll()
        key = (drv.state, drv.tick, drv.phase, len(self.side.log))
        now = time.monotonic()
        if (key != self._status_key and now - self._status_at >= STATUS_PERIOD_S) \
                or now - self._status_at > STATUS_PERIOD_S * 4:
            self._publish_status()

    def _notices(self) -> None:
        from .events import STATUS

        got = self.env.notices()
        for e in got:
            if e.kind == STATUS:
                self.link = dict(e.value)
                if e.value["state"] == "connected":
                    self.get_logger().info(f"robot connected: {e.value['reason']}")
                else:
                    self.get_logger().warning(f"robot {e.value['state']}: {e.value['reason']}")
            else:
                self.get_logger().warning(f"rejected a value from the robot: {e.value['source']} = {e.value['value']}: "
                                          f"{e.value['reason']}", throttle_duration_sec=1.0)
        if got:
            self.publish_diagnostics()  # connection changes and rejections go out at once

    def _flush_devices(self) -> None:
        while self._devices:
            device, command, action, tick = self._devices.pop(0)
            self.pub_device.publish(String(data=json.dumps({"device": device, "command": command, "action": action,
                                                            "run": self.driver.run, "tick": tick,
                                                            "stamp": time.time()})))

    def _missing(self) -> list[str]:
        out = []
        if not self.bridge.link.connected:
            out.append(f"the robot at {self.link['url']} is {self.link['state']} ({self.link['reason']})")
        if not self.get_parameter("wait_for_readers").value:
            return out
        pubs = {k: p for k, p in self.pubs.items() if k != "run_status"}  # read by the launcher, not a node
        outcome = self.get_parameter("outcome_readers").value
        return out + self.gate_missing(pubs, lambda key: self.extra_readers + (
            outcome if key == "outcome" else G.readers("pepper", key, self.learning)), [i.topic for i in DESC.inputs])

    # -- status and diagnostics ----------------------------------------------------------------
    def _publish_status(self) -> None:
        drv = self.driver
        self._status_at = time.monotonic()
        self._status_key = (drv.state, drv.tick, drv.phase, len(self.side.log))
        fields = drv.status_fields()
        fields["extra"] = dict(fields.get("extra") or {}, phase=drv.phase)
        self._send("run_status", drv.tick, fields, drv.run)

    def extra_statuses(self) -> list[dict]:
        return [self.robot_status(), *durable.DurableWorld.extra_statuses(self)]  # and its checkpoints

    def robot_status(self) -> dict:
        """The link and the bridge's diagnostics snapshot as one DiagnosticStatus (plain dict)."""
        snap = self.bridge.diagnostics.snapshot()
        link = self.link
        values = {"state": str(link.get("state")), "connected": str(bool(link.get("connected"))).lower(),
                  "url": str(link.get("url")), "reason": str(link.get("reason")), "connects": str(link.get("connects")),
                  "drops": str(link.get("drops")), "freezes": str(link.get("freezes", 0)), "polled_keys": str(len(link.get("polled_keys") or [])),
                  "rejected_total": str(snap["rejected_total"])}
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
        return {"name": "pepper_bridge: robot", "hardware_id": str(link.get("url")), "level": level, "message": msg,
                "values": values}

    # -- checkpoints and the rejoin of a respawned bridge (durable.DurableWorld) -------------------
    def world_checkpoint(self) -> dict:
        from .checkpoint import bridge_checkpoint, run_config

        return bridge_checkpoint(self.side, self.driver.position(), run_config(self.sc, self.driver.iterations),
                                 self.durable["session"])

    def restore_world(self, ck: dict) -> dict:
        from .checkpoint import restore_bridge, run_config

        where = str(durable.checkpoint.path_for(self.durable["resume_dir"], DESC.name))
        cfg, pos = restore_bridge(self.side, ck, run_config(self.sc, self.driver.iterations), where)
        self.driver.iterations = cfg["interactions"]
        return pos

    def go_on(self, run: int, tick: int, pos: dict, lost: int) -> None:
        from homeo_decision import codec
        from homeo_decision.environment import Outcome

        drv = self.driver
        outcome = pos["outcome"]
        if lost:  # the robot went on meanwhile; the bridge saw none of it
            outcome = (tick - 1, codec.outcome_fields(self.sc, Outcome(None, 0, None, None, None)))
            self.get_logger().warning(f"interactions {pos['tick'] + 1}..{tick} were lost with the process that died: "
                                      "counted as missed")
        self.env.tick = tick  # the interactions go on being numbered from here
        drv.rejoin(run, tick, pos["missed"] + lost, pos["elapsed"], outcome)

    def destroy_node(self):
        self.save_final()
        try:
            self.bridge.stop()
        finally:
            self.worker.shutdown(wait=False, cancel_futures=True)
        return super().destroy_node()


def main(args=None) -> int:
    return run_scenario_node(BridgeNode, args)


if __name__ == "__main__":
    sys.exit(main())

"""``homeo_world`` node: the one world node, hosting any world of the ``homeo_robot.worlds`` registry.

Publishes  homeo/world (state), homeo/observation (event), homeo/outcome (event),
           homeo/run_status (state: progress; the world's metrics or log), homeo/device (event:
           the world's device commands), homeo/last_action (state, with a person in the loop: the
           action being performed, for them to read), /diagnostics (input health, checkpoints,
           the world's own)
Subscribes homeo/action (tick k's action, with the robot's drives), and what the world reads from
           outside the graph (homeo/human_input, with the simulation's human:=person)
Services   ~/reset (std_srvs/Trigger): a new run from tick 0 (the robot keeps what it learned)
Parameters world (sim | pepper | day | ...), seed, iterations, rate, action_timeout, trace_path,
           wait_for_readers, intention_learns (``world_api.WORLD_PARAMS``); the world's own
           (``WorldBackend.PARAMS``); scenario, overrides, data_dir, extra_readers, record_spool;
           the checkpoint parameters of ``durable``

The tick is ``world_host.WorldHost`` (the lockstep driver over the world, the trace, the status,
the run's checkpoint): this node declares parameters, waits for the world and the graph's readers
and writers (``homeo_msgs_py.graph``), and wires topics, timers and services. A world whose calls
block (a robot, a person) runs them on one worker thread.
"""

from __future__ import annotations

import sys
import time

from rcl_interfaces.msg import SetParametersResult

from homeo_msgs_py.data_dir import OutsideDataDir
from homeo_msgs_py.graph import NODES, WORLD, readers
from homeo_msgs_py.lockstep import DONE, RUNNING, WAITING
from homeo_msgs_py.node_base import NodeConfigError

from . import durable
from .node_runtime import ScenarioNode, run_scenario_node
from .world_api import WORLD_PARAMS, WorldConfigError, world_class
from .world_host import WorldHost

DESC = NODES[WORLD]
POLL_S = 0.02
# a run that only needs its timeouts and status from the timer (a world that never blocks, at full speed):
# the action wakes the node, not the timer, so fewer wake-ups of the executor each second
IDLE_POLL_S = 0.1
STATUS_PERIOD_S = 0.25  # at most this often while the run moves; at least once a second
STATUS_IDLE_S = 1.0


class WorldNode(durable.DurableWorld, ScenarioNode):
    def __init__(self):
        super().__init__(DESC.name)
        v = self.declare_specs(WORLD_PARAMS)
        try:
            cls = world_class(v["world"])
        except WorldConfigError as exc:
            raise NodeConfigError(f"parameter world: {exc}") from None
        self._world_params = {s.name for s in cls.PARAMS}
        v.update(self.declare_specs(cls.PARAMS))
        cfg = durable.declare(self)  # checkpoints; a respawned node goes on with the run (durable.DurableWorld)
        try:
            self.world = cls(self.sc, v)
        except (WorldConfigError, OutsideDataDir) as exc:
            raise NodeConfigError(str(exc)) from None
        self.learning = v["intention_learns"]
        self._pool = None
        run_async = None
        if self.world.blocking:
            from concurrent.futures import ThreadPoolExecutor

            self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix=f"{v['world']}-io")
            run_async = self._pool.submit
        # a respawned node's trace goes on where its checkpoint left it (restore_world cuts it there)
        trace = self._open_trace(v["trace_path"], keep=cfg["respawned"])
        self.pubs = {key: self.publisher(key) for key in DESC.publishes}
        self.host = WorldHost(self.world, self._send, iterations=v["iterations"], rate=v["rate"],
                              timeout=v["action_timeout"], run_async=run_async, log=self._log, note=self.rejects.note,
                              warn=lambda text: self.get_logger().warning(text), trace=trace)
        self.driver = self.host.driver
        self.driver.on_done = self._publish_status
        self.setup_durable_world(cfg)
        self.add_on_set_parameters_callback(self._on_params)
        self.subscribe("action", self.driver.on_action)
        for key, handler in self.world.inputs().items():
            self.subscribe_text(key, handler)
        if self.world.inputs():  # a person in the loop: what the robot does, latched for them to read
            self.driver.on_act = self._announce
        self.trigger("~/reset", self._reset)
        self._wait_logged = self._status_at = 0.0
        self._status_key = None
        self._timer = self.create_timer(POLL_S, self._poll)
        self._period_ns = self._timer.timer_period_ns  # kept here: reading it back is a call into rcl

    def _send(self, key: str, tick: int, fields: dict, run: int) -> None:
        self.send(self.pubs[key], tick, fields, run)

    def _announce(self, tick: int, action: dict | None) -> None:
        f = {"action": action.get("action")} if action else {"action": None}
        if action:
            f.update({k: action[k] for k in ("intention", "m_dom") if action.get(k) is not None})
        self._send("last_action", tick, f, self.driver.run)

    def _log(self, text: str) -> None:
        if "retrying" in text:  # a robot that is away: once every 2 s is enough
            self.get_logger().warning(text, throttle_duration_sec=2.0)
        else:
            self.get_logger().info(text)

    # -- parameters -------------------------------------------------------------------------------
    def _on_params(self, params) -> SetParametersResult:
        drv = self.driver
        for prm in params:
            if prm.name == "rate":
                drv.set_rate(prm.value)
            elif prm.name == "action_timeout":
                drv.timeout = prm.value
            elif prm.name == "trace_path":
                try:
                    self.data_path(prm.value, "trace_path")  # opened at the next ~/reset
                except OutsideDataDir as exc:
                    return SetParametersResult(successful=False, reason=str(exc))
            elif prm.name == "iterations":
                if prm.value and prm.value <= drv.tick and drv.state == RUNNING:
                    return SetParametersResult(successful=False, reason=f"the run is already at tick {drv.tick}")
                drv.iterations = prm.value
            elif prm.name in self._world_params:
                reason = self.world.set_param(prm.name, prm.value)
                if reason:
                    return SetParametersResult(successful=False, reason=reason)
        return SetParametersResult(successful=True)  # seed and trace_path take effect at the next ~/reset

    def _open_trace(self, path: str, keep: bool = False):
        """The trace file at ``path``, trusted: the start value, or one ``_on_params`` already checked
        inside the data directory when it was set."""
        try:
            path = self.data_path(path, "trace_path", trusted=True)
        except OutsideDataDir as exc:
            raise NodeConfigError(str(exc)) from None
        if not path:
            return None
        try:
            if keep:
                fh = open(path, "a+")  # created if missing, never truncated here
                fh.seek(0, 2)
                return fh
            return open(path, "w")
        except OSError as exc:
            raise NodeConfigError(f"trace_path {path}: {exc.strerror}") from None

    # -- the timer: the world's notices and devices, the start gate, the driver, the status --------
    def _poll(self) -> None:
        notices = self.world.poll()
        log = self.get_logger()
        for level, text in notices:  # one call site per severity and filter: rclpy's logger insists
            if level == "burst":
                log.warning(text, throttle_duration_sec=1.0)
            elif level == "warning":
                log.warning(text)
            else:
                log.info(text)
        if notices:
            self.publish_diagnostics()  # connection changes and rejections go out at once
        for d in self.world.devices():
            self._send("device", d.pop("tick"), d, self.driver.run)
        drv = self.driver
        if drv.state == WAITING:
            missing = self._missing()
            if not missing:
                if not self.rejoin_due():
                    drv.begin()
            elif time.monotonic() - self._wait_logged > 2.0:
                self._wait_logged = time.monotonic()
                self.get_logger().info("waiting: " + "; ".join(missing))
        else:
            drv.poll()
            if drv.state == DONE and self.host.trace is not None:
                self.host.trace.flush()
        period = int(poll_period(drv, self.world.blocking) * 1e9)
        if period != self._period_ns:
            self._timer.timer_period_ns = self._period_ns = period
        key = (drv.state, drv.tick, drv.phase)
        now = time.monotonic()
        if (key != self._status_key and now - self._status_at >= STATUS_PERIOD_S) or now - self._status_at > STATUS_IDLE_S:
            self._publish_status()

    def _missing(self) -> list[str]:
        out = self.world.ready()
        if not self.get_parameter("wait_for_readers").value:
            return out
        extra = self.extra_readers
        return out + self.gate_missing(self.pubs, lambda key: readers(key, self.learning) + extra,
                                       [i.topic for i in DESC.inputs])

    # -- status and services ----------------------------------------------------------------------
    def _publish_status(self) -> None:
        drv = self.driver
        self._status_at, self._status_key = time.monotonic(), (drv.state, drv.tick, drv.phase)
        self._send("run_status", drv.tick, self.host.status_fields(), drv.run)

    def extra_statuses(self) -> list[dict]:
        return [*self.world.diagnostics(), *durable.DurableWorld.extra_statuses(self)]

    def _reset(self) -> tuple[bool, str]:
        seed = self.get_parameter("seed").value
        try:  # the start value, or one set since (checked inside the data directory when it was set)
            trace = self._open_trace(self.get_parameter("trace_path").value)
        except NodeConfigError as exc:
            return False, str(exc)
        self.host.reset(seed, trace)
        self.checkpoints.save()  # a restart from here goes on with the new run, not the old one
        return True, f"run {self.driver.run} starts from tick 0 with seed {seed}"

    # -- checkpoints and the rejoin of a respawned node (durable.DurableWorld) -------------------------
    def world_checkpoint(self) -> dict:
        return self.host.checkpoint(self.durable["session"])

    def restore_world(self, ck: dict) -> dict:
        where = str(durable.checkpoint.path_for(self.durable["resume_dir"], DESC.name))
        pos = self.host.restore(ck, where)
        trace, tb = self.host.trace, pos.pop("trace_bytes")
        if trace is not None and tb is not None and tb <= trace.tell():
            trace.truncate(tb)  # the ticks after the checkpoint are written again, as they now go
            trace.seek(tb)
        return pos

    def fresh_run(self) -> None:
        self.world.reset(None)  # no checkpoint of this run: its world from the start
        if self.host.trace is not None:
            self.host.trace.truncate(0)  # the world starts over: so does its trace

    def go_on(self, run: int, tick: int, pos: dict, lost: int) -> None:
        if lost:
            self.get_logger().warning(f"ticks {pos['tick']}..{tick - 1} were lost with the process that died: "
                                      "counted as missed")
        self.host.go_on(run, tick, pos, lost)

    def destroy_node(self):
        self.save_final()
        try:
            self.world.close()
        finally:
            if self._pool is not None:
                self._pool.shutdown(wait=False, cancel_futures=True)
            if self.host.trace is not None:
                self.host.trace.close()
                self.host.trace = None
        return super().destroy_node()


def poll_period(drv, blocking: bool) -> float:
    """How often the timer polls: ``IDLE_POLL_S`` while a run needs it only for its timeouts (a world
    that never blocks, no rate to keep, no retry, a timeout ten periods long at least), else ``POLL_S``."""
    quiet = (drv.state == RUNNING and not blocking and drv.rate == 0 and drv.phase != "retry"
             and drv.timeout >= 10 * IDLE_POLL_S)
    return IDLE_POLL_S if quiet else POLL_S


def main(args=None) -> int:
    return run_scenario_node(WorldNode, args)


if __name__ == "__main__":
    sys.exit(main())

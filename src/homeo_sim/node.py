"""``homeo_sim`` node: the simulated world, human and body, stepped in lockstep.

Publishes  homeo/world (state), homeo/observation (event), homeo/outcome (event),
           homeo/run_status (state: progress, and the metrics of Section 4.1), /diagnostics
Subscribes homeo/action (tick k's action, with the robot's drives that the metrics need),
           homeo/human_input (only with human:=person: a person's wishes and answers)
Services   ~/reset (std_srvs/Trigger): a new run from tick 0 (the robot keeps its Q-table)
Parameters seed (int), iterations (int, 0 = until stopped), rate (Hz, 0 = as fast as lockstep
           allows), action_timeout (s), trace_path (JSON lines per tick, '' = none),
           wait_for_readers (bool), extra_readers (int), intention_accuracy, human (sim | person),
           human_timeout (s), scenario, overrides

The tick itself is ``homeo_msgs_py.lockstep.LockstepDriver`` over ``world_side.SimWorldSide``;
this node declares parameters, waits for its readers and writers (``homeo_msgs_py.graph``) and
wires topics, timers and the service.
"""

from __future__ import annotations

import sys
import time

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor, SetParametersResult
from std_srvs.srv import Trigger

from homeo_decision import durable
from homeo_decision.node_runtime import ScenarioNode, run_scenario_node
from homeo_msgs_py.graph import NODES, SEED_MAX, TICKS_MAX, TOPICS, readers
from homeo_msgs_py.lockstep import DONE, RUNNING, WAITING, LockstepDriver
from homeo_msgs_py.data_dir import OutsideDataDir
from homeo_msgs_py.node_base import NodeConfigError

from .world_side import SimWorldSide

DESC = NODES["homeo_sim"]
STATUS_PERIOD_S = 0.25
SIM_HUMAN, PERSON = "sim", "person"
POLL_S = 0.02


class SimNode(durable.DurableWorld, ScenarioNode):
    def __init__(self):
        super().__init__(DESC.name)
        d = ParameterDescriptor
        self.declare_parameter("seed", 0, d(description="seed of the human's random stream",
                                            integer_range=[IntegerRange(from_value=0, to_value=SEED_MAX, step=1)]))
        self.declare_parameter("iterations", 5000, d(description="ticks per run (0 = until stopped)",
                                                     integer_range=[IntegerRange(from_value=0, to_value=TICKS_MAX, step=1)]))
        self.declare_parameter("rate", 0.0, d(description="ticks per second (0 = as fast as lockstep allows)",
                                              floating_point_range=[FloatingPointRange(from_value=0.0, to_value=1000.0)]))
        self.declare_parameter("action_timeout", 5.0, d(description="seconds to wait for an action before the tick "
                                                        "counts as no action",
                                                        floating_point_range=[FloatingPointRange(from_value=0.01,
                                                                                                 to_value=3600.0)]))
        self.declare_parameter("trace_path", "", d(description="write one JSON line per tick here ('' = no trace)"))
        self.declare_parameter("wait_for_readers", True, d(description="start only when the graph's readers and "
                                                           "writers have matched"))
        self.declare_fixed("intention_accuracy", False, d(
            description="score the recognised intention of each action against the human's (bayes mode); the "
                        "intention node then learns from the outcome, so the gate waits for its reader too"))
        self.declare_fixed("human", SIM_HUMAN, d(description="who plays the human: the simulated one (sim) or a "
                                                     "person on homeo/human_input (person)"))
        self.declare_parameter("human_timeout", 10.0, d(
            description="seconds a tick waits for the person before it counts as no intention (no answer)",
            floating_point_range=[FloatingPointRange(from_value=0.01, to_value=3600.0)]))
        p = self.get_parameter
        self.learning = p("intention_accuracy").value
        cfg = durable.declare(self)  # checkpoints; a respawned node goes on with the run (durable.DurableWorld)
        human, run_async, self._pool = self._human(p("human").value, p("seed").value)
        # a respawned node's trace goes on where its checkpoint left it (restore_world cuts it there)
        self.side = SimWorldSide(self.sc, p("seed").value, self.learning,
                                 self._open_trace(p("trace_path").value, keep=cfg["respawned"]), human=human)
        self.pubs = {key: self.publisher(key) for key in DESC.publishes}
        self.driver = LockstepDriver(self.side, self._send, iterations=p("iterations").value, rate=p("rate").value,
                                     timeout=p("action_timeout").value, log=self._log, note=self.rejects.note,
                                     run_async=run_async)
        self.driver.on_done = self._publish_status
        self.setup_durable_world(cfg)
        self.add_on_set_parameters_callback(self._on_params)
        self.subscribe("action", self.driver.on_action)
        self.create_service(Trigger, "~/reset", self._on_reset)
        self._wait_logged = 0.0
        self.create_timer(POLL_S, self._poll)
        self.create_timer(STATUS_PERIOD_S, self._publish_status)

    def _human(self, kind: str, seed: int):
        """The simulated human (None: the environment's own), or a person whose messages on
        homeo/human_input fill its inbox; the world then steps off the executor (it waits for them)."""
        if kind == SIM_HUMAN:
            return None, None, None
        if kind != PERSON:
            raise NodeConfigError(f"human must be {SIM_HUMAN} or {PERSON}, not {kind!r}")
        from concurrent.futures import ThreadPoolExecutor

        from std_msgs.msg import String

        from homeo_msgs_py.human_input import decode_human_input
        from homeo_msgs_py.qos import quiet_sub_events, sub_qos
        from homeo_msgs_py.schemas import Rejected

        from .person import PersonHuman

        person = PersonHuman(self.sc, seed, self.get_parameter("human_timeout").value)
        topic = [TOPICS["human_input"].name]

        def on_input(msg: String) -> None:
            try:
                person.inbox.put(decode_human_input(msg.data, self.voc))
            except Rejected as exc:
                self.reject(topic[0], str(exc))

        sub = self.create_subscription(String, topic[0], on_input, sub_qos("human_input"),
                                       event_callbacks=quiet_sub_events())
        topic[0] = sub.topic_name
        pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="person")
        return person, pool.submit, pool

    def _send(self, key: str, tick: int, fields: dict, run: int) -> None:
        self.send(self.pubs[key], tick, fields, run)

    def _log(self, text: str) -> None:
        self.get_logger().info(text)

    # -- parameters -------------------------------------------------------------------
    def _on_params(self, params) -> SetParametersResult:
        drv = self.driver
        for prm in params:
            if prm.name == "rate":
                drv.set_rate(prm.value)
            elif prm.name == "action_timeout":
                drv.timeout = prm.value
            elif prm.name == "human_timeout" and hasattr(self.side.env.human, "timeout"):
                self.side.env.human.timeout = prm.value
            elif prm.name == "trace_path":
                try:
                    self.data_path(prm.value, "trace_path")  # opened at the next ~/reset
                except OutsideDataDir as exc:
                    return SetParametersResult(successful=False, reason=str(exc))
            elif prm.name == "iterations":
                if prm.value and prm.value <= drv.tick and drv.state == RUNNING:
                    return SetParametersResult(successful=False, reason=f"the run is already at tick {drv.tick}")
                drv.iterations = prm.value
        return SetParametersResult(successful=True)  # seed and trace_path take effect at the next ~/reset

    def _open_trace(self, path: str, keep: bool = False):
        try:
            path = self.data_path(path, "trace_path")
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

    # -- start --------------------------------------------------------------------------
    def _missing(self) -> list[str]:
        if not self.get_parameter("wait_for_readers").value:
            return []
        extra = self.extra_readers
        return self.gate_missing(self.pubs, lambda key: readers("sim", key, self.learning) + extra,
                                 [i.topic for i in DESC.inputs])

    def _poll(self) -> None:
        drv = self.driver
        if drv.state == WAITING:
            missing = self._missing()
            if not missing:
                if not self.rejoin_due():
                    drv.begin()
            elif time.monotonic() - self._wait_logged > 2.0:
                self._wait_logged = time.monotonic()
                self.get_logger().info("waiting for the graph: " + "; ".join(missing))
            return
        drv.poll()
        if drv.state == DONE and self.side.trace is not None:
            self.side.trace.flush()

    # -- status and services -----------------------------------------------------------------
    def _publish_status(self) -> None:
        self._send("run_status", self.driver.tick, self.driver.status_fields(), self.driver.run)

    def _on_reset(self, request, response):
        seed = self.get_parameter("seed").value
        side = self.side
        if side.trace is not None:
            side.trace.close()
        try:
            side.trace = self._open_trace(self.get_parameter("trace_path").value)
        except NodeConfigError as exc:
            side.trace = None
            response.success, response.message = False, str(exc)
            return response
        side.reset(seed)
        self.driver.restart()
        self.checkpoints.save()  # a restart from here goes on with the new run, not the old one
        response.success = True
        response.message = f"run {self.driver.run} starts from tick 0 with seed {seed}"
        return response

    # -- checkpoints and the rejoin of a respawned node (durable.DurableWorld) --------------------
    def _run_config(self) -> dict:
        from .checkpoint import run_config

        p = lambda n: self.get_parameter(n).value  # noqa: E731
        trace = self.side.trace
        if trace is not None:
            trace.flush()  # the checkpoint says how much of the trace belongs to the run so far
        return run_config(self.sc, seed=self.side.env.seed, iterations=self.driver.iterations, rate=self.driver.rate,
                          action_timeout=self.driver.timeout, intention_accuracy=self.learning, human=p("human"),
                          trace_bytes=trace.tell() if trace is not None else None)

    def world_checkpoint(self) -> dict:
        from .checkpoint import world_checkpoint

        return world_checkpoint(self.side, self.driver.position(), self._run_config(), self.durable["session"])

    def restore_world(self, ck: dict) -> dict:
        from .checkpoint import restore_world

        where = str(durable.checkpoint.path_for(self.durable["resume_dir"], DESC.name))
        cfg, pos = restore_world(self.side, ck, self._run_config(), where)
        drv = self.driver
        drv.iterations, drv.rate, drv.timeout = cfg["iterations"], cfg["rate"], cfg["action_timeout"]
        trace = self.side.trace
        if trace is not None and cfg["trace_bytes"] is not None and cfg["trace_bytes"] <= trace.tell():
            trace.truncate(cfg["trace_bytes"])  # the ticks after the checkpoint are written again, as they now go
            trace.seek(cfg["trace_bytes"])
        return pos

    def fresh_run(self) -> None:
        self.side.reset(self.side.env.seed)  # no checkpoint of this run: its world from the start
        if self.side.trace is not None:
            self.side.trace.truncate(0)  # the world starts over: so does its trace

    def go_on(self, run: int, tick: int, pos: dict, lost: int) -> None:
        outcome = (tick - 1, self.side.skip(lost)) if lost else pos["outcome"]
        if lost:
            self.get_logger().warning(f"ticks {pos['tick']}..{tick - 1} were lost with the process that died: "
                                      "counted as missed")
        self.driver.rejoin(run, tick, pos["missed"] + lost, pos["elapsed"], outcome)

    def destroy_node(self):
        self.save_final()
        if self._pool is not None:
            self.side.env.human.inbox.put(None)  # a wait in progress ends now (as silence)
            self._pool.shutdown(wait=False, cancel_futures=True)
        if self.side.trace is not None:
            self.side.trace.close()
            self.side.trace = None
        return super().destroy_node()


def main(args=None) -> int:
    return run_scenario_node(SimNode, args)


if __name__ == "__main__":
    sys.exit(main())

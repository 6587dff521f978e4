"""``homeo_sim`` node: the simulated world, human and body, stepped in lockstep.

Publishes  /homeo/world (state), /homeo/observation (event), /homeo/outcome (event),
           /homeo/run_status (state: progress, and the metrics of Section 4.1), /diagnostics
Subscribes /homeo/action (tick k's action, with the robot's drives that the metrics need)
Services   ~/reset (std_srvs/Trigger): a new run from tick 0 (the robot keeps its Q-table)
Parameters seed (int), iterations (int, 0 = until stopped), rate (Hz, 0 = as fast as lockstep
           allows), action_timeout (s), trace_path (JSON lines per tick, '' = none),
           wait_for_readers (bool), outcome_readers, intention_accuracy, scenario, overrides

Tick k: publish world(k) and observation(k); wait for action(k) (a timeout counts as no
action and is reported); step the world; publish outcome(k); then tick k+1. The metrics of
tick k use the drives that come back with the action of tick k+1 (d(t) after the iteration,
as ``homeo-sim run`` records them); after the last tick a final message brings them.
"""

from __future__ import annotations

import json
import sys
import time

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor, SetParametersResult
from std_srvs.srv import Trigger

from homeo_msgs_py.node_base import HomeoNode, NodeConfigError, run_node
from homeo_msgs_py.schemas import Message, Rejected
from homeo_msgs_py.topics import ACTION, OBSERVATION, OUTCOME, RUN_STATUS, WORLD

from .sim_core import SimCore

# readers the standard graph has on each topic: drives reads the world and the outcome (the
# intention node reads the outcome too, when it learns); intention reads the observation
READERS = {WORLD: 1, OBSERVATION: 1, OUTCOME: 1}
WRITERS = (ACTION,)
STATUS_PERIOD_S = 0.25


class SimNode(HomeoNode):
    def __init__(self):
        super().__init__("homeo_sim")
        d = ParameterDescriptor
        self.declare_parameter("seed", 0, d(description="seed of the human's random stream",
                                            integer_range=[IntegerRange(from_value=0, to_value=2**31 - 1, step=1)]))
        self.declare_parameter("iterations", 5000, d(description="ticks per run (0 = until stopped)",
                                                     integer_range=[IntegerRange(from_value=0, to_value=10**9, step=1)]))
        self.declare_parameter("rate", 0.0, d(description="ticks per second (0 = as fast as lockstep allows)",
                                              floating_point_range=[FloatingPointRange(from_value=0.0, to_value=1000.0)]))
        self.declare_parameter("action_timeout", 5.0, d(description="seconds to wait for an action before the tick "
                                                        "counts as no action",
                                                        floating_point_range=[FloatingPointRange(from_value=0.01,
                                                                                                 to_value=3600.0)]))
        self.declare_parameter("trace_path", "", d(description="write one JSON line per tick here ('' = no trace)"))
        self.declare_parameter("wait_for_readers", True, d(description="start only when the standard graph's "
                                                           "readers and writers have matched"))
        self.declare_parameter("outcome_readers", READERS[OUTCOME], d(
            description="readers of /homeo/outcome to wait for (2 when the intention node learns)",
            integer_range=[IntegerRange(from_value=0, to_value=100, step=1)]))
        self.add_on_set_parameters_callback(self._on_params)
        p = self.get_parameter
        self.iterations = p("iterations").value
        self.rate = p("rate").value
        self.timeout = p("action_timeout").value
        self.declare_parameter("intention_accuracy", False, d(
            description="score the recognised intention of each action against the human's (bayes mode)",
            read_only=True))
        self.core = SimCore(self.sc, p("seed").value, p("intention_accuracy").value)
        self.sample_after = self.sc.open["metrics_sample"] == "after_action"
        self.trace = self._open_trace(p("trace_path").value)

        self.pub_world = self.publisher(WORLD)
        self.pub_obs = self.publisher(OBSERVATION)
        self.pub_outcome = self.publisher(OUTCOME)
        self.pub_status = self.publisher(RUN_STATUS)
        self.subscribe(ACTION, self._on_action)
        self.create_service(Trigger, "~/reset", self._on_reset)

        self.run = 0
        self.state = "waiting"  # waiting -> running -> finishing -> done
        self.missed = 0
        self._action: Message | None = None
        self._last_drives: list | None = None
        self._since = time.monotonic()
        self._t0, self._t0_tick = 0.0, 0
        self._due_timer = None
        self._wait_logged = 0.0
        self.create_timer(0.02, self._poll)
        self.create_timer(STATUS_PERIOD_S, self._publish_status)

    # -- parameters -------------------------------------------------------------------
    def _on_params(self, params) -> SetParametersResult:
        for prm in params:
            if prm.name == "rate":
                self.rate = prm.value
                self._t0, self._t0_tick = time.monotonic(), self.core.tick
            elif prm.name == "action_timeout":
                self.timeout = prm.value
            elif prm.name == "iterations":
                if prm.value and prm.value <= self.core.tick and self.state == "running":
                    return SetParametersResult(successful=False,
                                               reason=f"the run is already at tick {self.core.tick}")
                self.iterations = prm.value
            elif prm.name in ("seed", "trace_path"):
                pass  # take effect at the next ~/reset
        return SetParametersResult(successful=True)

    def _open_trace(self, path: str):
        if not path:
            return None
        try:
            return open(path, "w")
        except OSError as exc:
            raise NodeConfigError(f"trace_path {path}: {exc.strerror}") from None

    # -- start --------------------------------------------------------------------------
    def _missing(self) -> list[str]:
        if not self.get_parameter("wait_for_readers").value:
            return []
        out = []
        for pub, topic in ((self.pub_world, WORLD), (self.pub_obs, OBSERVATION), (self.pub_outcome, OUTCOME)):
            n, want = pub.matched(), READERS[topic]
            if topic == OUTCOME:
                want = self.get_parameter("outcome_readers").value
            if n < want:
                out.append(f"{topic} has {n}/{want} readers")
        for topic in WRITERS:
            if self.count_publishers(topic) < 1:
                out.append(f"{topic} has no writer")
        return out

    def _poll(self) -> None:
        now = time.monotonic()
        if self.state == "waiting":
            missing = self._missing()
            if not missing:
                self._begin()
            elif now - self._wait_logged > 2.0:
                self._wait_logged = now
                self.get_logger().info("waiting for the graph: " + "; ".join(missing))
            return
        if self.state in ("running", "finishing") and now - self._since > self.timeout:
            if self.state == "finishing":
                self.rejects.note("missed drives")
                self._finish(self._last_drives)
                return
            self.missed += 1
            self.rejects.note("missed ticks")
            self.get_logger().warning(f"no action for tick {self.core.tick} within {self.timeout:g} s: "
                                      "counted as no action")
            self._step(None)

    def _begin(self) -> None:
        self.state = "running"
        self._t_begin = time.monotonic()
        self._t0, self._t0_tick = time.monotonic(), 0
        self.get_logger().info(f"run {self.run}: {self.iterations or 'unbounded'} ticks, seed {self.core.seed}")
        self._publish_tick()

    def _publish_tick(self, final: bool = False) -> None:
        k = self.core.tick
        self._action = None
        self._since = time.monotonic()
        self.send(self.pub_obs, k, self.core.observation_msg(), self.run)  # first: the critical path starts here
        self.send(self.pub_world, k, self.core.world_msg(final=final), self.run)

    # -- inputs -------------------------------------------------------------------------
    def _on_action(self, msg: Message) -> None:
        if self.state not in ("running", "finishing"):
            raise Rejected(f"no run in progress (state {self.state})")
        if msg.run != self.run:
            raise Rejected(f"run {msg.run} is not the current run {self.run}")
        k = self.core.tick
        if msg.tick < k:
            raise Rejected(f"stale tick {msg.tick} (now at tick {k})")
        if msg.tick > k:
            raise Rejected(f"tick {msg.tick} is ahead of the run (now at tick {k})")
        f = msg.fields
        if bool(f.get("final")) != (self.state == "finishing"):
            raise Rejected("a final message before the run's end" if f.get("final")
                           else f"an action after the run's end at tick {k}")
        drives = f.get("after_action") if self.sample_after else f.get("drives")
        if k > 0 and drives is None:
            raise Rejected(f"no {'after_action' if self.sample_after else 'drives'}: the metrics need them")
        if drives is not None:
            self._last_drives = [drives[n] for n in self.sc.drive_names]
        if self.state == "finishing":
            self._finish(self._last_drives)
            return
        self._action = msg
        self._advance()

    # -- stepping -----------------------------------------------------------------------
    def _advance(self) -> None:
        if self.state != "running" or self._action is None:
            return
        if self.rate > 0:
            due = self._t0 + (self.core.tick + 1 - self._t0_tick) / self.rate
            if time.monotonic() < due:
                if self._due_timer is None:
                    self._due_timer = self.create_timer(max(0.0, due - time.monotonic()), self._on_due)
                return
        f = self._action.fields
        name = f["action"]
        self._step(self.sc.action_index(name) if name is not None else None, f.get("intention"))

    def _on_due(self) -> None:
        self._due_timer.cancel()
        self.destroy_timer(self._due_timer)
        self._due_timer = None
        self._advance()

    def _step(self, action: int | None, recognised: str | None = None) -> None:
        """Tick k: the metrics of k-1 (with the drives the action came with), then the world moves."""
        core = self.core
        k = core.tick
        if k > 0 and self._last_drives is not None:
            core.record(self._last_drives)
        res = core.step(action, recognised)
        self.send(self.pub_outcome, k, res.outcome, self.run)
        if self.trace is not None:
            self.trace.write(json.dumps(res.trace) + "\n")
        final = bool(self.iterations) and core.tick >= self.iterations
        if final:
            self.state = "finishing"  # the last drives come back with a final message
        self._publish_tick(final)

    def _finish(self, drives: list | None) -> None:
        if drives is not None:
            self.core.record(drives)
        self.state = "done"
        self.elapsed = time.monotonic() - self._t_begin
        if self.trace is not None:
            self.trace.flush()
        self._publish_status()
        self.get_logger().info(f"run {self.run} done: {self.core.tick} ticks, {self.missed} missed")

    # -- status and services -----------------------------------------------------------------
    def _publish_status(self) -> None:
        core = self.core
        fields = {"iterations": self.iterations, "done": self.state == "done", "missed": self.missed,
                  "state": self.state}
        if core.rec.n:
            fields["metrics"] = core.metrics()
        if self.state == "done":
            fields["extra"] = {"elapsed_s": self.elapsed, "ticks": core.tick}
        self.send(self.pub_status, core.tick, fields, self.run)

    def _on_reset(self, request, response):
        seed = self.get_parameter("seed").value
        if self.trace is not None:
            self.trace.close()
        try:
            self.trace = self._open_trace(self.get_parameter("trace_path").value)
        except NodeConfigError as exc:
            self.trace = None
            response.success, response.message = False, str(exc)
            return response
        self.core.reset(seed)
        self.run += 1
        self.missed = 0
        self.state = "waiting"
        response.success = True
        response.message = f"run {self.run} starts from tick 0 with seed {seed}"
        return response

    def destroy_node(self):
        if self.trace is not None:
            self.trace.close()
            self.trace = None
        return super().destroy_node()


def main(args=None) -> int:
    return run_node(SimNode, args)


if __name__ == "__main__":
    sys.exit(main())

"""Joining a tick's inputs that arrive on different topics (no rclpy).

DDS orders messages within a topic, not across topics: a node that needs the world of
tick k, the intention of tick k and the outcome of tick k-1 may get them in any order.
:class:`TickJoin` holds them until tick k is complete, then hands them over at once.
``offsets`` says which tick of an input belongs to the node's tick: ``{"world": 0}`` means tick k
needs the world of k (an offset -1 would take the message of the tick before; tick 0 needs none). A message of a tick already
handled is stale; one more than ``window`` ticks ahead cannot belong to this run.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable

from .schemas import Message, Rejected


@dataclass
class TickJoin:
    """Joins a node's inputs into ticks. It cannot be wedged: a new run is taken only from the
    run's first tick (``run + 1``, as the simulation's ~/reset makes it), or mid-run by a node that
    has none yet (one restarted by the launcher); a tick whose missing input will never come
    (every topic it lacks has moved on) is skipped once a later tick is complete."""

    offsets: dict  # input name -> tick offset (0 or negative)
    window: int = 2
    run: int = -1
    expected: int = 0
    skipped: int = 0  # ticks given up because an input of theirs was lost
    _pending: dict = field(default_factory=dict)  # node tick -> {input: Message}

    def restart(self, run: int, at: int = 0) -> None:
        self.run, self.expected = run, at
        self._pending.clear()

    def put(self, name: str, msg: Message) -> list[tuple[int, dict]]:
        """Store one input; returns the ticks it completed, in order, each with its inputs.
        An exact repeat of a stored input (a resent tick) is taken as a no-op.

        Raises :class:`Rejected` for a stale tick (``.tick`` says which), a tick too far ahead,
        an older run, or a newer run that does not start at its first tick.
        """
        k = msg.tick - self.offsets[name]
        if msg.run != self.run:
            if msg.run < self.run:
                raise Rejected(f"stale run {msg.run} (current run {self.run})")
            if self.run >= 0 and not (msg.run == self.run + 1 and k == 0):
                raise Rejected(f"run {msg.run} at tick {msg.tick} is not the start of the next run "
                               f"(current run {self.run})")
            self.restart(msg.run, at=0 if self.run >= 0 else max(k, 0))
        if k < self.expected:
            raise Stale(f"stale tick {msg.tick} on {name} (now at tick {self.expected})", k)
        if k > self.expected + self.window:
            raise Rejected(f"tick {msg.tick} on {name} is ahead of the run (now at tick {self.expected})")
        slot = self._pending.setdefault(k, {})
        if name in slot:
            if slot[name].fields == msg.fields:
                return []
            raise Rejected(f"a different {name} for tick {msg.tick}")
        slot[name] = msg
        done = []
        while True:
            if self._complete(self.expected):
                done.append((self.expected, self._pending.pop(self.expected, {})))
                self.expected += 1
                continue
            later = [t for t in self._pending if t > self.expected and self._complete(t)]
            if not later:
                return done
            # a later tick is whole: DDS keeps each topic in order, so what the expected tick
            # still lacks was lost on the way (crowded out of a queue) and will not come
            nxt = min(later)
            self.skipped += nxt - self.expected
            for t in [t for t in self._pending if t < nxt]:
                del self._pending[t]
            self.expected = nxt

    def _complete(self, k: int) -> bool:
        slot = self._pending.get(k, {})
        return all(n in slot for n, off in self.offsets.items() if k + off >= 0)


class Stale(Rejected):
    """An input of a tick already handled; ``tick`` is the node's tick it belonged to."""

    def __init__(self, reason: str, tick: int):
        super().__init__(reason)
        self.tick = tick


# -- the world side of the lockstep ---------------------------------------------------------------
WAITING, STARTING, RUNNING, FINISHING, DONE = "waiting", "starting", "running", "finishing", "done"
RETRY_S = 0.5  # pause before observing again after a failed observation (a robot that is away)


class LockstepDriver:
    """Tick k of a world node: observe, publish observation(k) and world(k), wait for action(k)
    (a timeout counts as no action), step, publish outcome(k), then tick k+1. After the last tick a
    final world lets the robot learn from the last outcome; the final message that answers it
    carries the drives the metrics of the last tick need.

    ``side`` is the world (``homeo_decision.world_api.WorldBackend``, whose docstring gives the calls
    and their rules). ROS-free: the node calls ``begin`` once its readers have matched, ``on_action`` for every
    decoded action message (a ``Rejected`` it raises is the reason to drop it) and ``poll`` from a
    timer; ``send(topic key, tick, fields, run)`` publishes. ``run_async(fn, *args)`` runs the
    side's blocking calls off the executor and returns a future (a robot); without it they run
    inline (the simulation, whose steps take microseconds)."""

    def __init__(self, side, send: Callable, *, iterations: int, rate: float = 0.0, timeout: float = 5.0,
                 run_async: Callable | None = None, log: Callable[[str], None] | None = None,
                 note: Callable[[str], None] | None = None, clock: Callable[[], float] = time.monotonic):
        self.side, self.send = side, send
        self.note = note or (lambda what: None)  # counted events: "missed ticks", "missed drives"
        self.iterations, self.rate, self.timeout = iterations, rate, timeout
        self.run_async, self.log, self.clock = run_async, log or (lambda text: None), clock
        self.run = 0
        self.on_done: Callable[[], None] | None = None  # called once the run is done
        # called with tick k before k is stepped, its record of k-1 taken: the world's checkpoint point
        self.on_step: Callable[[int], None] | None = None
        # called with tick k and the action message performed in it (None: none came), as the step starts
        self.on_act: Callable[[int, dict | None], None] | None = None
        # called with tick k, its action message and its outcome's fields, once, before the outcome goes out
        self.on_outcome: Callable[[int, dict | None, dict], None] | None = None
        self._reset_run()

    def _reset_run(self) -> None:
        self.state = WAITING
        self.tick = 0
        self.missed = 0
        self.phase = ""  # within a tick: observe -> act -> step
        self._job = None
        self._job_kind = ""
        self._retry_at = 0.0
        self._action: Message | None = None
        self._last_fields: dict | None = None  # the last action message's fields (drives for the metrics)
        self._last_msg: Message | None = None  # the last action message taken (its repeats are no-ops)
        self._outcome: tuple | None = None  # (tick, fields) of the last outcome sent
        self._observed: tuple | None = None  # (observation, world) fields of this tick, once sent
        self._resent = False
        self._since = self.clock()
        self._due: float | None = None
        self._t_begin = self._t0 = self.clock()
        self._t0_tick = 0
        self.elapsed = 0.0

    def restart(self) -> None:
        """A new run from tick 0 (the node resets its side first)."""
        self.run += 1
        self._reset_run()

    # -- progress --------------------------------------------------------------------------
    def begin(self) -> None:
        if self.state != WAITING:
            return
        self.state = STARTING
        self._t_begin = self._t0 = self.clock()
        self._t0_tick = 0
        self._submit("start", self.side.start)

    def _submit(self, kind: str, fn, *args) -> None:
        if self.run_async is None:
            try:
                res, err = fn(*args), None
            except Exception as exc:  # noqa: BLE001 - the side's failure becomes the tick's outcome
                res, err = None, exc
            self._done(kind, res, err, args)
            return
        self._job_kind, self._job_args = kind, args
        self._job = self.run_async(fn, *args)

    def _done(self, kind: str, res, err, args) -> None:
        now = self.clock()
        if kind == "start":
            self.state = RUNNING
            self.log(f"run {self.run}: {self.iterations or 'unbounded'} ticks")
            self._observe()
        elif kind == "observe":
            if err is not None:
                self.phase, self._retry_at = "retry", now + RETRY_S
                self.note("reads retried")
                self.log(f"observing tick {self.tick} failed ({err}); retrying")
                return
            world, seen = res
            o = self._outcome
            if o is not None and o[0] == self.tick - 1:  # tick k carries the outcome of k-1 (graph.Topic.carries)
                world, seen = dict(world, outcome=o[1]), dict(seen, outcome=o[1])
            self.phase, self._since = "act", now
            self._observed = (seen, world)
            self.send("observation", self.tick, seen, self.run)  # first: the critical path starts here
            self.send("world", self.tick, world, self.run)
        elif kind == "step":
            fields = res if err is None else self.side.step_failed(args[0], str(err))
            if getattr(self.side, "last_missed", False):  # the world could not act at all: a missed tick
                self.missed += 1
                self.note("missed ticks")
            if self.on_outcome is not None:
                self.on_outcome(self.tick, args[0], fields)
            self.send("outcome", self.tick, fields, self.run)
            self._outcome, self._observed = (self.tick, fields), None
            self.tick += 1
            if self.iterations and self.tick >= self.iterations:
                self.state = FINISHING  # the last drives come back with a final message
            self._observe()

    def _observe(self) -> None:
        self.phase = "observe"
        self._action = None
        self._resent = False
        self._submit("observe", self.side.observe, self.state == FINISHING)

    def poll(self) -> None:
        """From a timer: finished jobs, retries, the rate, timeouts."""
        now = self.clock()
        if self._job is not None and self._job.done():
            job, self._job = self._job, None
            err = job.exception()
            self._done(self._job_kind, None if err else job.result(), err, self._job_args)
        if self.phase == "retry" and now >= self._retry_at:
            self._observe()
        if self._due is not None and now >= self._due:
            self._due = None
            self._advance()
        if self.state in (RUNNING, FINISHING) and self.phase == "act" and self._action is None \
                and now - self._since > self.timeout:
            if not self._resent:
                self._resend(now)
                return
            if self.state == FINISHING:
                self.note("missed drives")
                self.log(f"no final message within {self.timeout:g} s: the run ends with the drives it has")
                self._finish()
                return
            self.missed += 1
            self.note("missed ticks")
            self.log(f"no action for tick {self.tick} within {self.timeout:g} s: counted as no action")
            self._step(None)

    def _resend(self, now: float) -> None:
        """No action within the timeout: a message of the tick may have been lost on the way
        (crowded out of a reader's queue). Send the tick again, once; the robot nodes answer a
        repeat with the answer they gave (``JoinedStage``), so nothing is computed twice."""
        self._resent, self._since = True, now
        self.note("resent ticks")
        self.log(f"no action for tick {self.tick} within {self.timeout:g} s: sending the tick again")
        if self._observed is not None:  # the outcome of the tick before rides in them
            self.send("observation", self.tick, self._observed[0], self.run)
            self.send("world", self.tick, self._observed[1], self.run)

    # -- actions ---------------------------------------------------------------------------
    def on_action(self, msg: Message) -> None:
        if self.state not in (RUNNING, FINISHING):
            raise Rejected(f"no run in progress (state {self.state})")
        last = self._last_msg
        if last is not None and msg.run == self.run and msg.tick == last.tick and msg.fields == last.fields:
            return  # a repeat of the action taken (answering a resent tick): nothing to do
        if msg.run != self.run:
            raise Rejected(f"run {msg.run} is not the current run {self.run}")
        k = self.tick
        if msg.tick < k:
            raise Rejected(f"stale tick {msg.tick} (now at tick {k})")
        if msg.tick > k:
            raise Rejected(f"tick {msg.tick} is ahead of the run (now at tick {k})")
        if self._action is not None:
            raise Rejected(f"duplicate action for tick {k}")
        if self.phase != "act":
            raise Rejected(f"an action for tick {k} before its world was published (phase {self.phase})")
        f = msg.fields
        if bool(f.get("final")) != (self.state == FINISHING):
            raise Rejected("a final message before the run's end" if f.get("final")
                           else f"an action after the run's end at tick {k}")
        self.side.check_action(f, k)  # raises Rejected when the world cannot use it
        self._last_fields = f
        self._action = self._last_msg = msg
        self._advance()

    def _advance(self) -> None:
        if self.state == FINISHING:
            self._finish()
            return
        if self.rate > 0:
            due = self._t0 + (self.tick + 1 - self._t0_tick) / self.rate
            if self.clock() < due:
                self._due = due
                return
        self._step(self._action.fields)

    def _step(self, action_fields: dict | None) -> None:
        if self.tick > 0:
            self.side.record(self._last_fields)  # the drives after tick k-1 came with this tick's action
        if self.on_step is not None:
            self.on_step(self.tick)
        if self.on_act is not None:
            self.on_act(self.tick, action_fields)
        self.phase = "step"
        self._submit("step", self.side.step, action_fields)

    def _finish(self) -> None:
        self.side.record(self._last_fields)
        self.state, self.phase = DONE, ""
        self.elapsed = self.clock() - self._t_begin
        self.log(f"run {self.run} done: {self.tick} ticks, {self.missed} missed")
        if self.on_done is not None:
            self.on_done()

    # -- a restarted world node ---------------------------------------------------------------
    def position(self) -> dict:
        """Where the run stands, as JSON-able data (the world's checkpoint): ``outcome`` is the last
        one sent, ``[tick, fields]``, which a restart at the next tick sends again."""
        return {"run": self.run, "tick": self.tick, "missed": self.missed, "iterations": self.iterations,
                "done": self.state == DONE, "started": self.state != WAITING, "elapsed": self.run_time(),
                "outcome": list(self._outcome) if self._outcome is not None else None}

    def rejoin(self, run: int, tick: int, missed: int, elapsed: float = 0.0, outcome: tuple | None = None,
               done: bool = False) -> None:
        """Go on with run ``run`` at tick ``tick`` (a world node restarted mid-run; ``missed`` counts
        the ticks lost meanwhile). The outcome of ``tick - 1`` rides in the world and observation of
        ``tick``, as every tick's does. No ``start``: the run started long ago."""
        self._reset_run()
        self.run, self.tick, self.missed = run, tick, missed
        now = self.clock()
        self._t_begin, self._t0, self._t0_tick = now - elapsed, now, tick
        if done:
            self.state, self.elapsed = DONE, elapsed
            return
        self.state = FINISHING if self.iterations and tick >= self.iterations else RUNNING
        self.log(f"run {run}: rejoined at tick {tick}, {missed} missed")
        if outcome is not None:
            self._outcome = (outcome[0], outcome[1])
        self._observe()

    def set_rate(self, rate: float) -> None:
        self.rate = rate
        self._t0, self._t0_tick = self.clock(), self.tick

    def run_time(self) -> float:
        """Seconds of the run so far: still counting while it runs, fixed once it ended."""
        return self.clock() - self._t_begin if self.state in (RUNNING, FINISHING) else self.elapsed

    def status_fields(self) -> dict:
        fields = {"iterations": self.iterations, "done": self.state == DONE, "missed": self.missed,
                  "state": self.state}
        fields.update(self.side.status(self.state == DONE))
        if self.state in (RUNNING, FINISHING, DONE):  # the run's own time: an interrupted run is timed by it too
            fields["extra"] = dict(fields.get("extra") or {}, elapsed_s=self.run_time(), ticks=self.tick)
        return fields


class JoinedStage:
    """A robot part as a node hosts it: its inputs join into ticks (``TickJoin``), a newer run
    restarts it, and each completed tick becomes the fields the node publishes. ROS-free, so the
    nodes and the tests' in-memory bus run the very same code.

    An input of the last tick it answered is the world re-sending a tick whose answer was lost
    (``LockstepDriver``): the stage answers again with the same fields, computed once."""

    def __init__(self, offsets: dict, tick: Callable[[int, dict], dict], restart: Callable[[], None]):
        self.join = TickJoin(offsets)
        self._tick, self._restart = tick, restart
        self._last: tuple[int, int, dict] | None = None  # (run, tick, fields) of the last answer

    @property
    def run(self) -> int:
        return self.join.run

    def resume_after(self, run: int, tick: int, fields: dict) -> None:
        """A restarted node goes on after ``tick`` of ``run``, whose answer was ``fields`` (its
        checkpoint): an input of that tick again is answered with them."""
        self.join.restart(run, at=tick + 1)
        self._last = (run, tick, fields)

    def put(self, key: str, msg: Message) -> list[tuple[int, dict]]:
        """Take one input (raises Rejected); returns ``(tick, fields to publish)`` per completed tick."""
        run = self.join.run
        try:
            done = self.join.put(key, msg)
        except Stale as exc:
            last = self._last
            if last is not None and last[0] == msg.run and last[1] == exc.tick:
                return [(last[1], last[2])]
            raise
        if self.join.run != run:
            self._last = None
            self._restart()
        out = [(k, self._tick(k, {name: m.fields for name, m in inputs.items()})) for k, inputs in done]
        if out:
            self._last = (self.join.run, *out[-1])
        return out

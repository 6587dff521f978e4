"""The world side of the graph, for any world (no rclpy): one ``WorldBackend`` in lockstep.

The host runs the lockstep driver (``homeo_msgs_py.lockstep.LockstepDriver``) over a backend and
adds what every world needs, written once: the trace (one JSON line per tick), the run status,
the actions a robot could not perform (logged and counted), the end of a run whose world has no
more to give, the run's checkpoint (the driver's position and the backend's state in one
envelope), and the way back into a run after the node was restarted. The world node
(``world_node.py``) and the in-memory bus runner (``homeo_ops.bus``) run this same object.
"""

from __future__ import annotations

import json
import time
from typing import Callable

from homeo_msgs_py.graph import WORLD
from homeo_msgs_py.lockstep import LockstepDriver

from homeo_msgs_py.params import ParamSpec

from .checkpoint import CheckpointError, check_codes, check_world_position, codes_print, envelope, scenario_print
from .codec import vocabulary
from .world_api import ACTION_TIMEOUT, ITERATIONS, RATE, WorldBackend

RUN_PARAMS = (ITERATIONS, RATE, ACTION_TIMEOUT)  # the run's settings a restarted node takes from its checkpoint
RUN_KEYS = tuple(s.name for s in RUN_PARAMS)
TRACE_BYTES = ParamSpec("trace_bytes", 0, "bytes of the trace the checkpoint's run wrote", 0, 2**62)


class WorldHost:
    def __init__(self, backend: WorldBackend, send: Callable, *, iterations: int, rate: float = 0.0,
                 timeout: float = 5.0, run_async: Callable | None = None, log: Callable[[str], None] | None = None,
                 note: Callable | None = None, warn: Callable[[str], None] | None = None, trace=None,
                 clock: Callable[[], float] = time.monotonic):
        self.world, self.sc = backend, backend.sc
        self.trace = trace  # a text file open for writing, or None
        self.log = log or (lambda text: None)
        self.warn = warn or self.log
        self.note = note or (lambda what, n=1: None)
        self.driver = LockstepDriver(backend, send, iterations=iterations, rate=rate, timeout=timeout,
                                     run_async=run_async, log=self.log, note=self.note, clock=clock)
        self.driver.on_outcome = self._stepped

    def _trace(self, tick: int, action_fields: dict | None, out: dict) -> dict:
        if self.trace is not None:
            truth = out.get("truth")
            self.trace.write(json.dumps({"tick": tick,
                                         "intention": truth["intention"] if truth and truth["expressed"] else None,
                                         "action": action_fields.get("action") if action_fields else None,
                                         "feedback": out["feedback"], "proposal": out["proposal"]}) + "\n")
        return out

    def _stepped(self, tick: int, action_fields: dict | None, fields: dict) -> None:
        """Tick ``tick`` was stepped, its outcome about to go out: traced, a failure noted, and a world with
        no more to give ends the run after the next tick."""
        self._trace(tick, action_fields, fields)
        w = self.world
        if w.last_failure is not None:
            self.note("failed actions")
            self.warn(w.last_failure)
        its = self.driver.iterations
        if w.finished() and (its == 0 or its > tick + 1):
            # the world has no more to give: the next world is the final one (the driver checks
            # iterations right after sending this outcome)
            self.driver.iterations = tick + 1
            self.log(f"the world is done after {tick + 1} ticks")

    # -- status ---------------------------------------------------------------------------------
    def status_fields(self) -> dict:
        drv = self.driver
        fields = drv.status_fields()
        fields["extra"] = dict(fields.get("extra") or {}, phase=drv.phase)
        return fields

    # -- a new run -------------------------------------------------------------------------------
    def reset(self, seed: int | None, trace=None) -> None:
        """A new run from tick 0 with ``seed`` (None: the world's own), writing ``trace``."""
        if self.trace is not None:
            self.trace.close()
        self.trace = trace
        self.world.reset(seed)
        self.driver.restart()

    # -- the run's checkpoint --------------------------------------------------------------------
    def run_config(self, trace_bytes: int | None = None) -> dict:
        d = self.driver
        return dict(self.world.run_config(), world=self.world.NAME, scenario=scenario_print(self.sc),
                    world_codes=codes_print(self.sc),
                    iterations=int(d.iterations), rate=float(d.rate), action_timeout=float(d.timeout),
                    trace_bytes=trace_bytes)

    def checkpoint(self, session: str = "") -> dict:
        """The run as a checkpoint envelope (``homeo_decision.checkpoint``): node ``homeo_world``."""
        trace = self.trace
        if trace is not None:
            trace.flush()  # the checkpoint says how much of the trace belongs to the run so far
        pos = self.driver.position()
        rng, state = self.world.state()
        return envelope(WORLD, pos["tick"], 0, pos["run"], self.run_config(trace.tell() if trace is not None else None),
                        rng, {"position": pos, "world": state}, session)

    def restore(self, ck: dict, where: str = "<memory>") -> dict:
        """Go on from a checkpoint of this kind of run; returns the driver's position and takes the
        run's settings from it. Everything is checked before anything changes (CheckpointError)."""
        p, st, ours = ck["params"], ck["state"], self.run_config()
        check_codes(p.get("world_codes"), ours["world_codes"], where)
        try:
            for key in [k for k in ours if k not in RUN_KEYS and k != "trace_bytes"]:
                if p.get(key) != ours[key]:
                    raise CheckpointError(f"a checkpoint of another run ({key} {str(p.get(key))[:40]!r}, this "
                                          f"node's {ours[key]!r})")
            run = {s.name: s.check(p.get(s.name)) for s in RUN_PARAMS}
            tb = p.get("trace_bytes")
            trace_bytes = None if tb is None else TRACE_BYTES.check(tb)
        except ValueError as exc:
            raise CheckpointError(f"{where}: corrupt checkpoint (params: {exc})") from None
        pos = check_world_position(st.get("position"), self.sc, vocabulary(self.sc), where)
        if pos["run"] != ck["run"] or pos["tick"] != ck["ticks"]:
            raise CheckpointError(f"{where}: corrupt checkpoint (the envelope's run and ticks are not the position's)")
        try:
            self.world.set_state(ck.get("rng"), st.get("world"), pos["tick"])
        except CheckpointError as exc:
            raise CheckpointError(f"{where}: corrupt checkpoint ({exc})") from None
        except (ValueError, TypeError, KeyError) as exc:
            raise CheckpointError(f"{where}: corrupt checkpoint ({str(exc)[:200]})") from None
        d = self.driver
        d.iterations, d.rate, d.timeout = run["iterations"], run["rate"], run["action_timeout"]
        return dict(pos, trace_bytes=trace_bytes)

    def go_on(self, run: int, tick: int, pos: dict, lost: int) -> None:
        """After a restart: the driver rejoins ``run`` at ``tick``; ``lost`` ticks since the position
        were never seen (counted as missed)."""
        lost_ticks = iter(range(tick - lost, tick))  # stepped by a world whose time went on: traced as they go
        fields = self.world.rejoin(tick, lost, lambda: self._trace(next(lost_ticks), None, self.world.step(None)))
        outcome = (tick - 1, fields) if fields is not None else pos["outcome"]
        self.driver.rejoin(run, tick, pos["missed"] + lost, pos["elapsed"], outcome)

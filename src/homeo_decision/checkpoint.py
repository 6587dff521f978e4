"""Checkpoints: what a robot node has learned, on disk, so a restart or a new run goes on from it
(no rclpy).

One file per node, ``DIR/<node>.json``, written atomically (``jsonfile.write_atomic``: a crash
leaves the previous checkpoint or the new one, never half a file). The envelope:

    {"schema": "homeo-checkpoint", "version": 1, "node": NAME, "ticks": T, "tick_offset": O,
     "run": R, "session": S, "params": {...}, "rng": {...} | null, "state": {...}}

``ticks``: how many ticks the node has learned in all (a resumed run's schedule starts there);
``tick_offset``: the ticks learned before the current run (a node restarted within the run goes on
with the same offset); ``session``: the launch that wrote it (a restarted node takes only its own
launch's checkpoint, never a stale one of an earlier run); ``state``: the decision's Q-table (``qtable_io``) or the intention model
(``homeo_intention.model_io``). Loading checks everything before it changes anything.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

from . import jsonfile, qtable_io
from .objectq import ObjectQ
from .rng import UniformStream

SCHEMA = "homeo-checkpoint"
VERSION = 1
DECISION_PARAMS = ("dod", "xi", "gamma", "pseudo_update", "feedback", "seed")


class CheckpointError(ValueError):
    """A checkpoint that cannot be written or loaded; the message (one line) says why."""


def path_for(directory: str | Path, node: str) -> Path:
    return Path(directory) / f"{node}.json"


def envelope(node: str, ticks: int, tick_offset: int, run: int, params: dict, rng, state: dict,
             session: str = "") -> dict:
    return {"schema": SCHEMA, "version": VERSION, "node": node, "ticks": int(ticks), "tick_offset": int(tick_offset),
            "run": int(run), "session": session, "params": params, "rng": rng, "state": state}


def save(path: str | Path, ck: dict) -> None:
    jsonfile.write_atomic(path, ck, CheckpointError, "checkpoint")


def load(path: str | Path, node: str) -> dict:
    """The checked envelope of ``path`` (its ``state`` is checked by the restore functions)."""
    raw = jsonfile.read(path, CheckpointError, "checkpoint")
    where = str(path)
    if not isinstance(raw, dict) or raw.get("schema") != SCHEMA:
        raise CheckpointError(f"{where}: not a checkpoint (schema must be {SCHEMA!r})")
    if raw.get("version") != VERSION:
        raise CheckpointError(f"{where}: checkpoint version {raw.get('version')!r} is not supported "
                              f"(this program reads {VERSION})")
    if raw.get("node") != node:
        raise CheckpointError(f"{where}: a checkpoint of {raw.get('node')!r}, not of {node}")
    for key in ("ticks", "tick_offset", "run"):
        v = raw.get(key)
        if not isinstance(v, int) or isinstance(v, bool) or v < 0:
            raise CheckpointError(f"{where}: corrupt checkpoint ({key} must be an integer >= 0, got {v!r})")
    if raw["tick_offset"] > raw["ticks"]:
        raise CheckpointError(f"{where}: corrupt checkpoint (tick_offset {raw['tick_offset']} > ticks {raw['ticks']})")
    if not isinstance(raw.get("params"), dict) or not isinstance(raw.get("state"), dict):
        raise CheckpointError(f"{where}: corrupt checkpoint (params and state must be objects)")
    return raw


def digest(obj) -> str:
    """A short fingerprint of learned state (tests and logs compare a node's memory with a file)."""
    return hashlib.sha256(json.dumps(obj, sort_keys=True, separators=(",", ":")).encode()).hexdigest()[:16]


# -- the decision node ------------------------------------------------------------------------------
def decision_checkpoint(core, ticks: int, run: int, session: str = "") -> dict:
    params = {"dod": core.dod, "xi": core.xi, "gamma": core.gamma, "pseudo_update": core.pseudo,
              "feedback": core.use_feedback, "seed": core.seed}
    return envelope("homeo_decision", ticks, core.tick_offset, run, params, core.rng.state(),
                    qtable_io.to_dict(core.q), session)


def decision_learned(core) -> dict:
    """What the decision has learned: its table and where its random stream stands."""
    return {"q": core.q.q, "rng": core.rng.state()}


def restore_decision(core, ck: dict, where: str = "<memory>", params: bool = False) -> None:
    """Put the checkpoint's table and random stream (and, with ``params``, its parameters) into
    ``core``; everything is checked first, so a bad file leaves ``core`` as it was."""
    q = ObjectQ(core.sc)
    try:
        qtable_io.from_dict(q, ck["state"], where)
    except qtable_io.QTableError as exc:
        raise CheckpointError(str(exc)) from None
    rng = UniformStream(core.seed, "decision")
    try:
        rng.set_state(ck.get("rng"))
    except ValueError as exc:
        raise CheckpointError(f"{where}: corrupt checkpoint (rng: {exc})") from None
    p = ck["params"]
    if params:
        missing = [k for k in DECISION_PARAMS if k not in p]
        if missing:
            raise CheckpointError(f"{where}: corrupt checkpoint (params lack {', '.join(missing)})")
        wrong = [k for k in ("dod", "xi", "gamma") if isinstance(p[k], bool) or not isinstance(p[k], (int, float))]
        wrong += [k for k in ("pseudo_update", "feedback") if not isinstance(p[k], bool)]
        wrong += [] if isinstance(p["seed"], int) and not isinstance(p["seed"], bool) and p["seed"] >= 0 else ["seed"]
        if wrong:
            raise CheckpointError(f"{where}: corrupt checkpoint (params: bad {', '.join(wrong)})")
        try:  # set_params checks everything before it changes anything
            core.set_params(dod=p["dod"], xi=p["xi"], gamma=p["gamma"], pseudo_update=p["pseudo_update"],
                            feedback=p["feedback"])
        except (TypeError, ValueError) as exc:
            raise CheckpointError(f"{where}: corrupt checkpoint (params: {exc})") from None
        core.seed = p["seed"]
    core.q.q = q.q
    core.rng = rng


class Checkpointer:
    """When a node writes its checkpoint: every ``every`` ticks and at shutdown. ``make()`` builds the
    envelope; a failed write is reported through ``log`` and counted, never raised (the robot goes on
    learning; the previous checkpoint stays)."""

    def __init__(self, directory: str, node: str, every: int, make, log=lambda text: None):
        self.path = path_for(directory, node) if directory else None
        self.every, self.make, self.log = max(1, int(every)), make, log
        self.saved = self.failed = 0
        self.last_ticks = -1
        self.last_error = ""

    def after_tick(self, ticks: int) -> None:
        """``ticks``: the node's learned tick count after this tick."""
        if self.path is not None and ticks > 0 and ticks % self.every == 0 and ticks != self.last_ticks:
            self.save()

    def save(self) -> bool:
        if self.path is None:
            return False
        ck = self.make()
        try:
            save(self.path, ck)
        except CheckpointError as exc:
            self.failed += 1
            self.last_error = str(exc)
            self.log(f"checkpoint not written: {exc}")
            return False
        self.saved += 1
        self.last_ticks = ck["ticks"]
        return True

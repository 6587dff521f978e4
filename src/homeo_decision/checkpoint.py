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

import copy
import hashlib
import json
import os
from pathlib import Path

from homeo_msgs_py.learning import LEARNING, SEED
from homeo_msgs_py.params import checked

from . import jsonfile, qtable_io
from .objectq import ObjectQ
from .rng import UniformStream

SCHEMA = "homeo-checkpoint"
VERSION = 1
# the decision's params: its learning parameters and its seed, as declared (homeo_msgs_py.learning)
DECISION_PARAMS = LEARNING + (SEED,)


class CheckpointError(ValueError):
    """A checkpoint that cannot be written or loaded; the message (one line) says why."""


SLOTS_SUFFIX = ".slots"
SLOT_BYTES = 8192
PER_TICK = ("homeo_drives",)  # nodes whose checkpoint is written every tick, in slots


def path_for(directory: str | Path, node: str) -> Path:
    return Path(directory) / (f"{node}{SLOTS_SUFFIX}" if node in PER_TICK else f"{node}.json")


def envelope(node: str, ticks: int, tick_offset: int, run: int, params: dict, rng, state: dict,
             session: str = "") -> dict:
    return {"schema": SCHEMA, "version": VERSION, "node": node, "ticks": int(ticks), "tick_offset": int(tick_offset),
            "run": int(run), "session": session, "params": params, "rng": rng, "state": state}


def save(path: str | Path, ck: dict) -> None:
    jsonfile.write_atomic(path, ck, CheckpointError, "checkpoint")


def load(path: str | Path, node: str) -> dict:
    """The checked envelope of ``path`` (its ``state`` is checked by the restore functions)."""
    if str(path).endswith(SLOTS_SUFFIX):
        return load_slots(path, node)
    return check_envelope(jsonfile.read(path, CheckpointError, "checkpoint"), node, str(path))


def check_envelope(raw, node: str, where: str) -> dict:
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


# -- the world nodes' parts (homeo_sim.checkpoint, pepper_bridge.checkpoint) ----------------------------
def scenario_print(sc) -> str:
    """The scenario a world checkpoint was written under: a restart must run the same one."""
    return digest({"raw": sc.raw, "open": sc.open.printed()})


def codes_print(sc) -> str:
    """How a checkpoint's world codes are numbered (``Scenario.code_layout``): a world code saved under
    another numbering (one written before the world code held the sensed relation, issue 22) would
    be read as another world, so it is refused."""
    return digest(sc.code_layout())


def check_codes(saved, ours: str, where: str) -> None:
    """Refuse (one line) a checkpoint whose world codes are not numbered as ``ours`` (``codes_print``)."""
    if saved != ours:
        why = ("it records none: written before world codes held the human's relation" if saved is None
               else "they are numbered otherwise")
        raise CheckpointError(f"{where}: a checkpoint whose world codes this program would misread ({why})")


def check_int(v, what: str, lo: int = 0, hi: int = 2**62, kind: type = int):
    """A checkpoint's number, checked by its declaration (``params.checked``); CheckpointError (one line)."""
    return checked(v, what, lo, hi, kind, CheckpointError)


def check_world_position(pos, sc, voc, where: str, world_tick: int | None = None) -> dict:
    """The driver's position, checked: the last outcome must be a valid ``homeo/outcome`` of the tick before."""
    try:
        if not isinstance(pos, dict):
            raise CheckpointError("not an object")
        run, tick = check_int(pos.get("run"), "run"), check_int(pos.get("tick"), "tick", 0, 10**9)
        out = {"run": run, "tick": tick, "missed": check_int(pos.get("missed"), "missed", 0, tick),
               "iterations": check_int(pos.get("iterations"), "iterations", 0, 10**9),
               "elapsed": check_int(pos.get("elapsed"), "elapsed", 0.0, 1e9, float), "outcome": None}
        for key in ("done", "started"):
            if type(pos.get(key)) is not bool:
                raise CheckpointError(f"{key} must be true or false")
            out[key] = pos[key]
        if world_tick is not None and world_tick != tick:
            raise CheckpointError(f"tick {tick} is not the environment's {world_tick}")
        o = pos.get("outcome")
        if o is not None:
            if not isinstance(o, list) or len(o) != 2 or o[0] != tick - 1 or not isinstance(o[1], dict):
                raise CheckpointError("outcome must be [the tick before, its fields]")
            from homeo_msgs_py.schemas import Rejected, validate

            try:
                msg = validate(dict(o[1], schema="homeo/outcome", version=1, run=run, tick=tick - 1, stamp=0.0), voc,
                               "homeo/outcome")
            except Rejected as exc:
                raise CheckpointError(f"outcome: {exc}") from None
            out["outcome"] = (tick - 1, msg.fields)
        elif tick > 0:
            raise CheckpointError(f"no outcome of tick {tick - 1}")
        return out
    except CheckpointError as exc:
        raise CheckpointError(f"{where}: corrupt checkpoint (position: {exc})") from None



def digest(obj) -> str:
    """A short fingerprint of learned state (tests and logs compare a node's memory with a file)."""
    return hashlib.sha256(json.dumps(obj, sort_keys=True, separators=(",", ":")).encode()).hexdigest()[:16]


# -- the decision node ------------------------------------------------------------------------------
def decision_checkpoint(core, ticks: int, run: int, session: str = "") -> dict:
    return decision_snapshot(core, ticks, run, session)()


def decision_snapshot(core, ticks: int, run: int, session: str = "") -> "Snapshot":
    """The decision's checkpoint as a copy of its table's rows (tens of microseconds), the random
    stream's state and the parameters; the labelled table (about a millisecond) is built when written."""
    q = copy.copy(core.q)  # the scenario's layout shared; the values copied
    q.q = [[row[:] for row in table] for table in core.q.q]
    params = dict(core.params(), **{SEED.name: core.seed})
    rng, offset = core.rng.state(), core.tick_offset
    return Snapshot(ticks, lambda: envelope("homeo_decision", ticks, offset, run, params, rng, qtable_io.to_dict(q),
                                            session))


def load_table(q: ObjectQ, path: str | Path) -> qtable_io.LoadReport:
    """Load a Q-table into ``q`` from a Q-table file (``--save-q``, ``~/save_q``) or from the decision
    node's checkpoint, which holds its table (a user reaches for it first after a long graph run).
    QTableError (one line) for anything else, a checkpoint of another node among them."""
    raw = jsonfile.read(path, qtable_io.QTableError, "Q-table")
    if isinstance(raw, dict) and raw.get("schema") == SCHEMA:
        try:
            raw = check_envelope(raw, "homeo_decision", str(path))["state"]
        except CheckpointError as exc:
            raise qtable_io.QTableError(f"{exc}: it holds no Q-table") from None
    return qtable_io.from_dict(q, raw, str(path))


def decision_learned(core) -> dict:
    """What the decision has learned: its table and where its random stream stands."""
    return {"q": core.q.q, "rng": core.rng.state()}


def check_decision(sc, ck: dict, where: str = "<memory>", params: bool = False, seed: int = 0) -> tuple:
    """The decision checkpoint's table, random stream and (with ``params``) parameters, each checked
    against the scenario ``sc``: ``(ObjectQ, UniformStream, values or None)``; CheckpointError (one line)."""
    q = ObjectQ(sc)
    try:
        qtable_io.from_dict(q, ck["state"], where)
    except qtable_io.QTableError as exc:
        raise CheckpointError(str(exc)) from None
    rng = UniformStream(seed, "decision")
    try:
        rng.set_state(ck.get("rng"))
    except ValueError as exc:
        raise CheckpointError(f"{where}: corrupt checkpoint (rng: {exc})") from None
    if not params:
        return q, rng, None
    p = ck["params"]
    missing = [s.name for s in DECISION_PARAMS if s.name not in p]
    if missing:
        raise CheckpointError(f"{where}: corrupt checkpoint (params lack {', '.join(missing)})")
    try:  # each as its declaration takes it
        return q, rng, {s.name: s.check(p[s.name]) for s in DECISION_PARAMS}
    except ValueError as exc:
        raise CheckpointError(f"{where}: corrupt checkpoint (params: {exc})") from None


def restore_decision(core, ck: dict, where: str = "<memory>", params: bool = False) -> None:
    """Put the checkpoint's table and random stream (and, with ``params``, its parameters) into
    ``core``; everything is checked first, so a bad file leaves ``core`` as it was."""
    q, rng, values = check_decision(core.sc, ck, where, params, core.seed)
    if values is not None:  # set_params then changes nothing before all are checked
        core.set_params(**{s.name: values[s.name] for s in LEARNING})
        core.seed = values[SEED.name]
    core.q.q = q.q
    core.rng = rng


# -- a checkpoint every tick: two slots of one file ----------------------------------------------------
class SlotWriter:
    """Writes a checkpoint every tick: two fixed-size slots of one file (``DIR/<node>.slots``), each
    write one ``pwrite`` into the slot not holding the newest, so a process killed at any moment leaves
    a whole checkpoint (the newest or the one before). No rename and no fsync: on ext4 a rename over
    a file flushes it (about 2 ms, the cost of a whole tick), a slot write costs tens of microseconds.
    Such a checkpoint serves a restart within the launch; a machine that stops ends the launch."""

    def __init__(self, path: str | Path):
        self.path = Path(path)
        self._fd = None
        self._n = 0

    def write(self, ck: dict) -> None:
        try:
            data = json.dumps(ck, separators=(",", ":"), allow_nan=False).encode()
            if len(data) >= SLOT_BYTES:
                raise ValueError(f"{len(data)} bytes do not fit a slot of {SLOT_BYTES}")
            if self._fd is None:
                self.path.parent.mkdir(parents=True, exist_ok=True)
                self._fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            os.pwrite(self._fd, data.ljust(SLOT_BYTES, b" "), (self._n % 2) * SLOT_BYTES)
            self._n += 1
        except (OSError, ValueError) as exc:
            raise CheckpointError(f"cannot write checkpoint {self.path}: {getattr(exc, 'strerror', None) or exc}") \
                from None

    def close(self) -> None:
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None


def load_slots(path: str | Path, node: str) -> dict:
    """The newest whole checkpoint of a slot file; CheckpointError (one line) when neither slot holds one."""
    where = str(path)
    try:
        with open(path, "rb") as fh:
            raw = fh.read(2 * SLOT_BYTES + 1)
    except FileNotFoundError:
        raise CheckpointError(f"checkpoint file not found: {where}") from None
    except OSError as exc:
        raise CheckpointError(f"cannot read checkpoint {where}: {exc.strerror}") from None
    if len(raw) > 2 * SLOT_BYTES:
        raise CheckpointError(f"{where}: corrupt checkpoint (longer than two slots)")
    found, why = [], "empty"
    for i in (0, 1):
        text = raw[i * SLOT_BYTES:(i + 1) * SLOT_BYTES].strip()
        if not text:
            continue
        try:
            found.append(check_envelope(json.loads(text.decode()), node, where))
        except (UnicodeDecodeError, ValueError) as exc:  # CheckpointError and JSONDecodeError are ValueErrors
            why = str(exc).replace(f"{where}: ", "")[:200]
    if not found:
        raise CheckpointError(f"{where}: corrupt checkpoint (no whole slot: {why})")
    return max(found, key=lambda ck: (ck["run"], ck["ticks"]))


class Checkpointer:
    """When a node writes its checkpoint: every ``every`` ticks and at shutdown. ``make()`` takes the
    snapshot: the envelope, or a call that builds it, from data the node will not change afterwards.
    With ``background`` the snapshot is written by a thread of its own (``checkpoint_writer``), off
    the tick's path; ``close()`` writes what is on its way (at shutdown, before the final one). A
    failed write is reported through ``log`` and counted, never raised (the robot goes on learning;
    the previous checkpoint stays)."""

    def __init__(self, directory: str, node: str, every: int, make, log=lambda text: None,
                 background: bool = False):
        self.path = path_for(directory, node) if directory else None
        self._slots = SlotWriter(self.path) if self.path is not None and node in PER_TICK else None
        self.every, self.make, self.log = max(1, int(every)), make, log
        self.saved = self.failed = 0
        self.last_ticks = -1  # of the newest checkpoint written
        self._handed = -1  # of the newest one handed to the background writer
        self.last_error = ""
        self._thread = None
        self._superseded = 0
        if background and self.path is not None:
            from .checkpoint_writer import BackgroundWriter

            self._thread = BackgroundWriter(self._write, name=f"{node}-checkpoints")

    def after_tick(self, ticks: int) -> None:
        """``ticks``: the node's learned tick count after this tick."""
        if self.path is not None and ticks > 0 and ticks % self.every == 0 and ticks not in (self.last_ticks,
                                                                                              self._handed):
            self.save()

    def save(self) -> bool:
        """Take the snapshot and write it (in the background: hand it over); False when not written."""
        if self.path is None:
            return False
        snap = self.make()
        if self._thread is None:
            return self._write(snap)
        self._handed = snap["ticks"] if isinstance(snap, dict) else snap.ticks
        self._thread.submit(snap)
        return True

    def _write(self, snap) -> bool:
        ck = snap if isinstance(snap, dict) else snap()
        try:
            self._slots.write(ck) if self._slots is not None else save(self.path, ck)
        except CheckpointError as exc:
            self.failed += 1
            self.last_error = str(exc)
            self.log(f"checkpoint not written: {exc}")
            return False
        self.saved += 1
        self.last_ticks = ck["ticks"]
        return True

    @property
    def superseded(self) -> int:
        """Snapshots the background writer dropped for a newer one (a disk slower than the interval)."""
        return self._thread.superseded if self._thread is not None else self._superseded

    def close(self) -> None:
        """Write what is on its way and end the background writer; later saves write in the caller."""
        if self._thread is not None:
            self._thread.close()
            self._superseded, self._thread = self._thread.superseded, None


class Snapshot:
    """A checkpoint taken as a cheap copy in the tick and built into its envelope when written:
    ``ticks`` now, ``build()`` (the envelope) later, in the writer's thread."""

    def __init__(self, ticks: int, build):
        self.ticks, self._build = ticks, build

    def __call__(self) -> dict:
        return self._build()


# -- the drives node ----------------------------------------------------------------------------------
DRIVES = "homeo_drives"


def drives_checkpoint(perception, run: int, tick: int, answer: dict, session: str = "") -> dict:
    """What the drives node carries from tick to tick (``robot.Perception``: the internal drives, the
    world and intention it perceived last, the drives right after the last action) after ``tick``,
    and its answer to that tick (sent again if the world sends the tick again)."""
    p = perception
    state = {"tick": tick, "values": list(p.model.values), "prev_code": p.prev_code, "world_codes": codes_print(p.sc),
             "prev_intention": p.prev_intention, "drives": list(p.drives),
             "after_action": list(p.after_action) if p.after_action is not None else None, "answer": answer}
    return envelope(DRIVES, tick + 1, 0, run, {}, None, state, session)


def drives_learned(perception) -> dict:
    p = perception
    return {"values": list(p.model.values), "prev_code": p.prev_code, "prev_intention": p.prev_intention,
            "after_action": list(p.after_action) if p.after_action is not None else None}


def restore_drives(host, ck: dict, where: str = "<memory>") -> None:
    """Put the checkpoint into a ``hosts.PerceptionHost``: its perception goes on from the state
    after the checkpoint's tick, and its join from the tick after (an input of that tick again is
    answered with the same answer). Everything is checked first."""
    from homeo_msgs_py.schemas import Rejected, validate

    from .codec import vocabulary

    sc, st = host.sc, ck["state"]
    n = len(sc.drives)

    def drive_list(v, what):
        if not isinstance(v, list) or len(v) != n or not all(
                type(x) in (int, float) and 0.0 <= x <= 100.0 for x in v):
            raise CheckpointError(f"{where}: corrupt checkpoint ({what} must be {n} numbers in 0..100)")
        return [float(x) for x in v]

    tick, code, it = st.get("tick"), st.get("prev_code"), st.get("prev_intention")
    check_codes(st.get("world_codes"), codes_print(sc), where)
    if type(tick) is not int or not 0 <= tick < 2**62 or tick + 1 != ck["ticks"]:
        raise CheckpointError(f"{where}: corrupt checkpoint (tick {str(tick)[:20]!r} is not ticks - 1)")
    if code is not None and (type(code) is not int or not 0 <= code < sc.n_codes):
        raise CheckpointError(f"{where}: corrupt checkpoint (prev_code must be a world code or null)")
    if type(it) is not int or not 0 <= it < len(sc.intention_names):
        raise CheckpointError(f"{where}: corrupt checkpoint (prev_intention must be an intention index)")
    values, drives = drive_list(st.get("values"), "values"), drive_list(st.get("drives"), "drives")
    after = None if st.get("after_action") is None else drive_list(st.get("after_action"), "after_action")
    answer = st.get("answer")
    if not isinstance(answer, dict):
        raise CheckpointError(f"{where}: corrupt checkpoint (answer must be an object)")
    try:
        msg = validate(dict(answer, schema="homeo/drives", version=1, run=ck["run"], tick=tick, stamp=0.0),
                       vocabulary(sc), "homeo/drives")
    except Rejected as exc:
        raise CheckpointError(f"{where}: corrupt checkpoint (answer: {str(exc)[:200]})") from None
    p = host.perception
    p.model.values[:] = values
    p.prev_code, p.prev_intention, p.drives = code, it, tuple(drives)
    p.after_action = tuple(after) if after is not None else None
    host.stage.resume_after(ck["run"], tick, msg.fields)

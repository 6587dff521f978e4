"""The message contract, declared once (no rclpy): each payload's fields and their types.

Every message is a ``std_msgs/msg/String`` whose ``data`` is one JSON object::

    {"schema": "homeo/world", "version": 1, "run": 0, "tick": 12, "stamp": 1700000000.25, ...fields}

``run`` counts resets of the simulation (a node that sees a newer run starts its tick count again);
``tick`` is the lockstep tick the payload belongs to; ``stamp`` is wall time in seconds. Field values
that name scenario things (actions, intentions, drives, locations, object states) are checked against
the scenario, so a message from a different world is refused instead of misread.

``PAYLOADS`` declares every payload's fields as types of the scenario's vocabulary; from them msgspec
builds, once per vocabulary, the Struct that decodes and validates a message in one pass in C
(``decode``, ``validate``), and the JSON Schema that describes it (``json_schemas.py``, the live view).
What a type cannot say (presence and relation agree, a posterior sums to 1, a body drive lies in
[0, 100]) a payload's check says, in the same pass. ``decode`` raises :class:`Rejected` with a
one-line reason; nodes count the reason and report it on ``/diagnostics`` and keep running.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from keyword import iskeyword
from typing import Annotated, Any, Callable, Literal, Union

import msgspec
from msgspec import UNSET, Meta, UnsetType

from .learning import LEARNING
from .text import one_line  # noqa: F401  (imported from here by many modules)

VERSION = 1
ENVELOPE = ("schema", "version", "run", "tick", "stamp")
AUTH_KEY = "auth"  # the graph's signature, appended last (``auth.py``); not part of the fields

# Limits of the decode boundary: every payload within them is decoded, every other is refused with a
# reason. The types bound every field but the run status's free ``metrics`` and ``extra``, whose
# depth, size and numbers ``_tree`` bounds. The largest message (a run status with its log) is a few kB.
MAX_TEXT = 64 * 1024  # characters of one message
MAX_DEPTH = 8  # nesting of objects and arrays
MAX_STR = 1024  # characters of one string or key
MAX_ITEMS = 4096  # values in one message
MAX_INT = 2**62  # the ticks and runs of centuries of running
MAX_REASON = 200  # characters of a reason kept for /diagnostics and the log
NOT_UNICODE = "a string that is not valid Unicode (a lone surrogate)"


class Rejected(ValueError):
    """A message that is dropped; ``str()`` is the reason."""


@dataclass(frozen=True)
class Message:
    schema: str
    run: int
    tick: int
    stamp: float
    fields: dict


# -- field types: each a function of the vocabulary (the scenario's names) to a msgspec type ----------------
Type = Callable[["Vocabulary"], Any]


def const(t) -> Type:
    return lambda voc: t


def num(lo: float, hi: float) -> Type:
    return const(Annotated[float, Meta(**{k: x for k, x in (("ge", lo), ("le", hi)) if math.isfinite(x)})])


COUNT = const(Annotated[int, Meta(ge=0, le=MAX_INT)])
BOOL, FEEDBACK, ANY = const(bool), const(Literal[-1, 0, 1]), const(Any)  # ANY: bounded by ``_tree``
TEXT = const(Annotated[str, Meta(max_length=MAX_STR)])
SYMBOL = const(Union[Annotated[str, Meta(min_length=1, max_length=64)], None])  # a cue: a short symbol or null
# body drives by name, plus raw readings (battery_percent, temperature_status, ...): numbers
BODY = const(dict[Annotated[str, Meta(max_length=64)], Annotated[float, Meta(ge=-1e9, le=1e9)]])


def name(kind: str, nullable: bool = False) -> Type:
    """A name from the scenario vocabulary ``kind`` (actions, intentions, ...)."""
    def of(voc):
        names = tuple(voc.names(kind))
        t = Literal[names] if names else Annotated[str, Meta(pattern="(?!)")]  # no names: nothing is one
        return Union[t, None] if nullable else t
    return of


def every(kind: str, value: Type, title: str) -> Type:
    """A value for every name of ``kind`` (all drives, all motivations): an object with each as a field."""
    return lambda voc: voc.struct(title, {n: (value, True) for n in voc.names(kind)})


def by_name(kind: str, value: Type) -> Type:
    """Values by name of ``kind``, some or all."""
    return lambda voc: dict[name(kind)(voc), value(voc)]


def obj(spec: dict, title: str) -> Type:
    """A nested object of named fields, ``{name: (type, required)}``; no unknown keys."""
    return lambda voc: voc.struct(title, spec)


def objects(voc):
    """``{"charger": {"status": "idle"}, ...}``: every scenario object with every variable."""
    return voc.struct("objects", {o: (obj({v: (const(Literal[tuple(vals)]), True) for v, vals in vars_.items()},
                                          f"object {o}"), True) for o, vars_ in voc.object_vars.items()})


DRIVES = every("drives", num(0.0, 100.0), "drives")
HUMAN = {"presence": (name("presences"), True), "relation": (name("relations"), True)}
WORLD_STATE = {"robot": (obj({"location": (name("locations"), True)}, "robot"), True),
               "objects": (objects, True), "human": (obj(HUMAN, "human"), True)}
OUTCOME = {
    "action": (name("actions", nullable=True), True),
    "feedback": (FEEDBACK, True),
    "proposal": (name("actions", nullable=True), True),
    "clarified_intention": (name("intentions", nullable=True), True),
    "body": (BODY, False),  # body right after the action
    # ground truth of the simulated human, for the metrics only (robot nodes never read it)
    "truth": (obj({"intention": (name("intentions"), True), "expressed": (BOOL, True),
                   "satisfied": (BOOL, True)}, "truth"), False),
}


def _param(spec) -> Type:
    """A learning parameter's value as its declaration (``params.ParamSpec``) takes it."""
    if spec.kind is bool:
        return BOOL
    return num(-math.inf if spec.lo is None else spec.lo, math.inf if spec.hi is None else spec.hi)


PAYLOADS: dict[str, dict[str, tuple[Type, bool]]] = {
    # simulation or robot -> intention, drives: what the world looks like at the start of a tick
    "homeo/world": dict(WORLD_STATE, **{
        "body": (BODY, True),
        "final": (BOOL, False),  # the run ends with this tick: learn, do not act
        "outcome": (obj(OUTCOME, "outcome"), False),  # the outcome of tick k-1 (graph.Topic.carries; none at 0)
    }),
    # simulation or robot -> intention: what the robot sees of the human this tick
    "homeo/observation": {
        "intention": (name("intentions", nullable=True), False),  # oracle mode: observed directly
        "gesture": (SYMBOL, False),
        "movement": (SYMBOL, False),
        "keyword": (SYMBOL, False),
        "outcome": (obj(OUTCOME, "outcome"), False),  # the outcome of tick k-1: the intention it revealed
    },
    # intention -> drives: the recognised intention and its posterior (Eq 2.10)
    "homeo/intention": {
        "intention": (name("intentions"), True),
        "posterior": (by_name("intentions", num(0.0, 1.0)), True),
        "mode": (name("modes"), True),
    },
    # drives -> decision: drives, stimuli, intensities (Eq 3.2), dominant motivation (Eq 3.3)
    "homeo/drives": {
        "drives": (DRIVES, True),
        "stimuli": (every("motivations", num(-1e9, 1e9), "stimuli"), True),
        "intensities": (every("motivations", num(-1e9, 1e9), "intensities"), True),
        "m_dom": (name("internal_states"), True),
        "intention": (name("intentions"), True),  # the one the stimuli were computed with
        "world": (obj(WORLD_STATE, "perceived world"), True),  # the world these drives were perceived in
        "after_action": (DRIVES, False),  # drives before the time step
        # what tick k-1's action did, as these drives took it in: the decision learns from it
        "outcome": (obj({"action": (name("actions", nullable=True), True), "feedback": (FEEDBACK, True),
                         "proposal": (name("actions", nullable=True), True)}, "learned outcome"), False),
        "final": (BOOL, False),
    },
    # decision -> simulation or robot: the chosen action (null = none) and the drives it was chosen with
    "homeo/action": {
        "action": (name("actions", nullable=True), True),
        "m_dom": (name("internal_states"), False),
        "tau": (num(0.0, 1e6), False),
        # the learning parameters in force, as declared (homeo_msgs_py.learning)
        "params": (obj({spec.name: (_param(spec), True) for spec in LEARNING}, "params"), False),
        "drives": (DRIVES, False),  # the drives the choice was made with
        "intention": (name("intentions"), False),  # the recognised intention it was made for
        "after_action": (DRIVES, False),
        "final": (BOOL, False),  # the run ended: no action, only the last drives
    },
    # simulation or robot -> everyone: what the action did and what the human said
    "homeo/outcome": OUTCOME,
    # world -> a person in the loop: the action being performed, and what the robot chose it for
    "homeo/last_action": {
        "action": (name("actions", nullable=True), True),  # null: nothing (no action came)
        "intention": (name("intentions"), False),  # the recognised intention it was chosen for
        "m_dom": (name("internal_states"), False),
    },
    # world -> the devices around the robot: a command its config maps an action to (play, switch on)
    "homeo/device": {
        "device": (TEXT, True),
        "command": (TEXT, True),
        "action": (name("actions", nullable=True), True),  # the action being performed
    },
    # world -> launcher: progress and, at the end, the run's metrics
    "homeo/run_status": {
        "iterations": (COUNT, True),
        "done": (BOOL, True),
        "missed": (COUNT, True),
        "state": (TEXT, True),
        "metrics": (ANY, False),
        "extra": (ANY, False),
    },
    # a person -> simulation (``--human person``): typed by hand, so the envelope may be left out
    # (``human_input.decode_human_input``)
    "homeo/human_input": {
        "intention": (name("intentions", nullable=True), False),  # null or "none": no wish
        "feedback": (const(Union[Literal["praise", "scold", -1, 0, 1], None]), False),
        "proposal": (name("actions", nullable=True), False),
    },
}
SCHEMAS = PAYLOADS  # the payloads' field names, by schema (homeo-topic, the docs)
ABSENT = "absent"  # the one value presence and relation share: each is absent iff the other is


# -- what a type cannot say, checked in the same pass (a Struct's __post_init__) ------------------------------
def _human(h) -> None:
    if (h.presence == ABSENT) != (h.relation == ABSENT):
        raise ValueError(f"presence {h.presence!r} contradicts relation {h.relation!r}")


def _posterior(p) -> None:
    s = sum(p.posterior.values())
    if p.posterior and abs(s - 1.0) > 1e-6:
        raise ValueError(f"posterior: probabilities sum to {s:.6f}, not 1")


def _bodies(voc):
    known = set(voc.names("drives"))

    def check(p) -> None:
        for part in (p, getattr(p, "outcome", None)):
            for k, v in (getattr(part, "body", None) or {}).items():
                if k in known and not 0.0 <= v <= 100.0:
                    raise ValueError(f"body.{k} = {v} is outside [0, 100]")
    return check


def _tree(p) -> None:
    """The free JSON of a run status: depth, size, string length, integer size."""
    stack, n = [(p.metrics, 1), (p.extra, 1)], 0
    while stack:
        v, depth = stack.pop()
        n += 1
        if n > MAX_ITEMS:
            raise ValueError(f"more than {MAX_ITEMS} values")
        if isinstance(v, (dict, list)):
            if depth > MAX_DEPTH:
                raise ValueError(f"nested deeper than {MAX_DEPTH}")
            items = list(v.items()) if isinstance(v, dict) else [(None, x) for x in v]
            for k, x in items:
                if k is not None and len(k) > MAX_STR:
                    raise ValueError(f"a key of {len(k)} characters (at most {MAX_STR})")
                stack.append((x, depth + 1))
        elif isinstance(v, str) and len(v) > MAX_STR:
            raise ValueError(f"a string of {len(v)} characters (at most {MAX_STR})")
        elif isinstance(v, int) and not isinstance(v, bool) and abs(v) > MAX_INT:
            raise ValueError(f"an integer beyond {MAX_INT}")


CHECKS = {"human": [_human], "homeo/intention": [_posterior], "homeo/run_status": [_tree],
          "homeo/world": ["body"], "homeo/observation": ["body"], "homeo/outcome": ["body"]}


class Vocabulary:
    """The names that message fields may take: ``kind -> names`` (actions, intentions, drives,
    motivations, locations, presences, relations, modes) and ``object_vars``: object -> variable ->
    values. ``homeo_decision.codec.vocabulary(scenario)`` builds the one of a scenario; without names
    only the scenario-free schemas (run_status) can be checked. It keeps the Structs and decoders
    msgspec builds for it (once each)."""

    def __init__(self, object_vars: dict | None = None, **names):
        from .graph import INTENTION_MODES

        self._names: dict[str, list[str]] = {"modes": list(INTENTION_MODES)}
        self._names.update({k: list(v) for k, v in names.items()})
        # m_dom's values: the motivations, unless the scenario adds "none" (no_activated_motivation)
        self._names.setdefault("internal_states", self._names.get("motivations", []))
        self.object_vars: dict[str, dict[str, list[str]]] = object_vars or {}
        self._structs: dict = {}
        self._decoders: dict = {}

    def names(self, kind: str) -> list[str]:
        return self._names.get(kind, [])

    def struct(self, title: str, spec: dict, envelope: dict | None = None) -> type:
        """The msgspec Struct of an object of named fields ``{name: (type, required)}`` (its fields
        renamed to the JSON keys, which need not be identifiers); built once per vocabulary."""
        if title not in self._structs:  # a title names one object's fields
            fields = dict(envelope or {}, **spec)
            attr = {k: k if k.isidentifier() and not iskeyword(k) and not k.startswith("_") else f"f{i}"
                    for i, k in enumerate(fields)}
            req = [(attr[k], t(self), k) for k, (t, r) in fields.items() if r]
            opt = [(attr[k], Union[t(self), UnsetType], k) for k, (t, r) in fields.items() if not r]
            checks = [_bodies(self) if c == "body" else c for c in CHECKS.get(title, ())]
            ns = {"__post_init__": _run(checks)} if checks else {}
            self._structs[title] = msgspec.defstruct(
                title.replace("/", "_").replace(" ", "_"), [(f, t) for f, t, _ in req] + [(f, t, UNSET) for f, t, _ in opt],
                rename={f: k for f, _, k in req + opt}, forbid_unknown_fields=True, namespace=ns)
        return self._structs[title]

    def message(self, schema: str) -> type:
        """The Struct of a whole message of ``schema``: the envelope and the payload's fields."""
        env = {"schema": (const(Literal[schema]), True), "version": (const(Literal[VERSION]), True),
               "run": (COUNT, True), "tick": (COUNT, True), "stamp": (num(0.0, 1e12), True),
               AUTH_KEY: (const(Annotated[str, Meta(max_length=128)]), False)}  # a reader that checks no signature
        return self.struct(schema, PAYLOADS[schema], env)

    def decoder(self, schema: str) -> msgspec.json.Decoder:
        if schema not in self._decoders:
            self._decoders[schema] = msgspec.json.Decoder(self.message(schema))
        return self._decoders[schema]


def _run(checks: list) -> Callable:
    def post_init(self) -> None:
        for c in checks:
            c(self)
    return post_init



# -- encode, decode ---------------------------------------------------------------------------------
_ENCODER = msgspec.json.Encoder()  # a NaN or an infinity (a metric of no samples) goes out as null


def encode(schema: str, tick: int, fields: dict, run: int = 0, stamp: float | None = None) -> str:
    """One JSON message of ``schema``; the caller's fields are trusted (nodes build them from the core)."""
    env = {"schema": schema, "version": VERSION, "run": run, "tick": tick,
           "stamp": time.time() if stamp is None else stamp}
    env.update(fields)
    return _ENCODER.encode(env).decode()


def finite(obj):
    """``obj`` with every NaN and infinity replaced by None: what JSON can carry (RFC 8259)."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [finite(v) for v in obj]
    return obj


def short(text: str, limit: int = MAX_REASON) -> str:
    """A reason on one line, cut to ``limit`` characters, printable: what a sender put in it (a key that
    msgspec quotes) cannot flood /diagnostics or the log, nor break their encoding (lone surrogates and
    line breaks become escapes)."""
    text = one_line(text).encode("utf-8", "backslashreplace").decode("utf-8")
    return text if len(text) <= limit else text[:limit - 3] + "..."


def parse_json(text, limit: int = MAX_TEXT, what: str = "") -> Any:
    """The JSON value of a message's text (no schema), or :class:`Rejected` with the reason."""
    if not isinstance(text, str):
        raise Rejected("not a string")
    if len(text) > limit:
        raise Rejected(f"message of {len(text)} characters is too long{what}")
    try:
        return msgspec.json.decode(text)
    except RecursionError:
        raise Rejected("nested too deep") from None
    except UnicodeEncodeError:
        raise Rejected(NOT_UNICODE) from None
    except msgspec.DecodeError as exc:  # a ValidationError too: a number out of range
        raise Rejected(short(f"not JSON ({exc})")) from None


def _envelope_reason(obj, expect: str | None) -> str | None:
    """A friendlier reason than the type's for a message of another schema or version."""
    if not isinstance(obj, dict):
        return f"not a JSON object but {type(obj).__name__}"
    schema = obj.get("schema")
    if not isinstance(schema, str) or schema not in PAYLOADS or schema == "homeo/human_input":
        return short(f"unknown schema {schema!r}")
    if expect is not None and schema != expect:
        return f"schema {schema!r} on a topic that carries {expect!r}"
    if obj.get("version") != VERSION:
        return short(f"{schema} version {obj.get('version')!r} is not {VERSION}")
    return None


def _message(m, schema: str) -> Message:
    fields = msgspec.to_builtins(m)
    for k in ENVELOPE:
        del fields[k]
    fields.pop(AUTH_KEY, None)
    return Message(schema, m.run, m.tick, m.stamp, fields)


def decode(text: str, voc: Vocabulary, expect: str | None = None) -> Message:
    """Parse and validate one message (of ``expect``, when given); :class:`Rejected` with the reason."""
    if not isinstance(text, str):
        raise Rejected("not a string")
    if len(text) > MAX_TEXT:
        raise Rejected(f"message of {len(text)} characters is too long")
    schema = expect
    try:
        if schema is None:
            schema = _schema_of(parse_json(text), None)
        return _message(voc.decoder(schema).decode(text), schema)
    except RecursionError:  # in a run status's free JSON
        raise Rejected("nested too deep") from None
    except UnicodeEncodeError:  # a lone surrogate: the text is not Unicode a JSON reader can take
        raise Rejected(NOT_UNICODE) from None
    except msgspec.ValidationError as exc:  # the envelope of another schema or version: said so, else the type's
        try:
            reason = _envelope_reason(msgspec.json.decode(text), expect) or str(exc)
        except (msgspec.DecodeError, RecursionError):
            reason = str(exc)
        raise Rejected(short(reason)) from None
    except msgspec.DecodeError as exc:
        raise Rejected(short(f"not JSON ({exc})")) from None


def _schema_of(obj, expect) -> str:
    reason = _envelope_reason(obj, expect)
    if reason is not None:
        raise Rejected(reason)
    return obj["schema"]


def validate(obj: Any, voc: Vocabulary, expect: str | None = None) -> Message:
    """A message given as Python data (a tool's, a test's), validated as ``decode`` does."""
    schema = _schema_of(obj, expect)
    try:
        return _message(msgspec.convert(obj, voc.message(schema)), schema)
    except msgspec.ValidationError as exc:
        raise Rejected(short(str(exc))) from None
    except UnicodeEncodeError:
        raise Rejected(NOT_UNICODE) from None

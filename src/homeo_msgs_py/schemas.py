"""The message contract: one JSON schema per payload, encode/decode with validation (no rclpy).

Every message is a ``std_msgs/msg/String`` whose ``data`` is one JSON object::

    {"schema": "homeo/world", "version": 1, "run": 0, "tick": 12, "stamp": 1700000000.25, ...fields}

``run`` counts resets of the simulation (a node that sees a newer run starts its tick
count again); ``tick`` is the lockstep tick the payload belongs to; ``stamp`` is wall time
in seconds. Field values that name scenario things (actions, intentions, drives,
locations, object states) are checked against the scenario, so a message from a
different world is rejected instead of misread.

``decode`` raises :class:`Rejected` with a one-line reason; nodes count the reason and
report it on ``/diagnostics`` (see ``homeo_msgs_py.diagnostics``) and keep running.
"""

from __future__ import annotations

import json
import math
import re
import time
from dataclasses import dataclass
from typing import Any, Callable

from .learning import LEARNING
from .text import one_line  # noqa: F401  (imported from here by many modules)

VERSION = 1
ENVELOPE = ("schema", "version", "run", "tick", "stamp")
AUTH_KEY = "auth"  # the graph's signature, appended last (``auth.py``); not part of the fields

# Limits of the decode boundary: every payload within them is decoded, every other is refused
# with a reason. The largest message of the graph (a run status with its metrics) is about 3 kB.
MAX_TEXT = 64 * 1024  # characters of one message
MAX_DEPTH = 8  # nesting of objects and arrays
MAX_STR = 1024  # characters of one string or key
MAX_ITEMS = 4096  # values in one message
MAX_INT_DIGITS = 18  # |n| < 10**18: the ticks and runs of centuries of running
_INT_LIMIT = 10 ** MAX_INT_DIGITS  # computed once: every number of every message is compared with it
MAX_REASON = 200  # characters of a reason kept for /diagnostics and the log


_SURROGATE = re.compile(r"\\u[dD][89a-fA-F][0-9a-fA-F]{2}")


class Rejected(ValueError):
    """A message that is dropped; ``str()`` is the reason."""


@dataclass(frozen=True)
class Message:
    schema: str
    run: int
    tick: int
    stamp: float
    fields: dict


# -- value checks -------------------------------------------------------------
# A check takes (value, vocabulary, where) and returns the value kept or raises Rejected. Each also
# carries ``check.json(voc)``: the JSON Schema of the values it accepts (``json_schemas.py`` walks
# SCHEMAS with it, for viewers such as Foxglove). What a schema cannot say (probabilities that sum
# to 1) only the check knows; a value the check accepts the schema accepts too.
Check = Callable[[Any, "Vocabulary", str], Any]


def _schema(of: Callable[["Vocabulary"], dict]):
    """Attach ``of`` (vocabulary -> JSON Schema) to a check as its ``json``: a function attribute
    costs the decode nothing."""
    def attach(check):
        check.json = of
        return check
    return attach


def _bounds(lo: float, hi: float) -> dict:
    return {k: x for k, x in (("minimum", lo), ("maximum", hi)) if math.isfinite(x)}


def _num(lo: float, hi: float) -> Check:
    @_schema(lambda voc: {"type": "number", **_bounds(lo, hi)})
    def check(v, voc, where):
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise Rejected(f"{where} must be a number, got {type(v).__name__}")
        if isinstance(v, int) and abs(v) >= _INT_LIMIT:  # float() of it could overflow
            raise Rejected(f"{where}: an integer of more than {MAX_INT_DIGITS} digits")
        if not math.isfinite(v) or not lo <= v <= hi:
            raise Rejected(f"{where} = {v} is outside [{lo:g}, {hi:g}]")
        return float(v)
    return check


def _int(lo: int, hi: int) -> Check:
    @_schema(lambda voc: {"type": "integer", "minimum": lo, "maximum": hi})
    def check(v, voc, where):
        if isinstance(v, bool) or not isinstance(v, int):
            raise Rejected(f"{where} must be an integer, got {type(v).__name__}")
        if not lo <= v <= hi:
            raise Rejected(f"{where} = {v} is outside [{lo}, {hi}]" if hi < 2**53 else f"{where} = {v} is below {lo}")
        return v
    return check


@_schema(lambda voc: {"type": "boolean"})
def _bool(v, voc, where):
    if not isinstance(v, bool):
        raise Rejected(f"{where} must be true or false, got {type(v).__name__}")
    return v


@_schema(lambda voc: {"type": "string"})
def _str(v, voc, where):
    if not isinstance(v, str):
        raise Rejected(f"{where} must be a string, got {type(v).__name__}")
    return v


def _one_of(kind: str, nullable: bool = False) -> Check:
    """A name from the scenario vocabulary ``kind`` (actions, intentions, ...)."""
    @_schema(lambda voc: {"enum": voc.names(kind) + [None]} if nullable else {"type": "string", "enum": list(voc.names(kind))})
    def check(v, voc, where):
        if v is None and nullable:
            return None
        known = voc.names(kind)
        if not isinstance(v, str) or v not in known:
            raise Rejected(f"{where}: unknown {kind[:-1]} {v!r}; known: {', '.join(known)}")
        return v
    return check


@_schema(lambda voc: {"enum": [-1, 0, 1]})
def _feedback(v, voc, where):
    if isinstance(v, bool) or v not in (-1, 0, 1):
        raise Rejected(f"{where} must be +1, -1 or 0, got {v!r}")
    return int(v)


def _map(key_kind: str, value: Check, complete: bool = False, extra: Check | None = None) -> Check:
    """A JSON object keyed by names of ``key_kind``; ``extra`` admits other keys (e.g. raw readings)."""
    def schema(voc):
        names = voc.names(key_kind)
        out = {"type": "object", "properties": {n: value.json(voc) for n in names},
               "additionalProperties": extra.json(voc) if extra is not None else False}
        return out | ({"required": list(names)} if complete else {})

    @_schema(schema)
    def check(v, voc, where):
        if not isinstance(v, dict):
            raise Rejected(f"{where} must be an object, got {type(v).__name__}")
        known = voc.names(key_kind)
        out = {}
        for k, x in v.items():
            if k in known:
                out[k] = value(x, voc, f"{where}.{k}")
            elif extra is not None:
                out[k] = extra(x, voc, f"{where}.{k}")
            else:
                raise Rejected(f"{where}: unknown {key_kind[:-1]} {k!r}; known: {', '.join(known)}")
        if complete:
            missing = [k for k in known if k not in out]
            if missing:
                raise Rejected(f"{where}: missing {', '.join(missing)}")
        return out
    return check


def object_schema(spec: dict[str, tuple[Check, bool]], voc: "Vocabulary") -> dict:
    """The JSON Schema of an object of named fields (a payload, a nested object)."""
    return {"type": "object", "properties": {k: c.json(voc) for k, (c, _) in spec.items()},
            "required": [k for k, (_, required) in spec.items() if required], "additionalProperties": False}


def _obj(spec: dict[str, tuple[Check, bool]]) -> Check:
    """A nested object with named fields; ``(check, required)`` per field; no unknown keys."""
    @_schema(lambda voc: object_schema(spec, voc))
    def check(v, voc, where):
        if not isinstance(v, dict):
            raise Rejected(f"{where} must be an object, got {type(v).__name__}")
        return _fields(v, spec, voc, where)
    return check


def _fields(v: dict, spec, voc, where: str) -> dict:
    out = {}
    for k, x in v.items():
        if k not in spec:
            raise Rejected(f"{where}: unexpected field {k!r}")
        out[k] = spec[k][0](x, voc, f"{where}.{k}" if where else k)
    for k, (_, required) in spec.items():
        if required and k not in out:
            raise Rejected(f"{where + ': ' if where else ''}missing field {k!r}")
    return out


def _objects_schema(voc: "Vocabulary") -> dict:
    objects = voc.object_vars
    return {"type": "object", "additionalProperties": False, "required": list(objects), "properties": {
        o: {"type": "object", "additionalProperties": False, "required": list(vars_),
            "properties": {var: {"enum": list(values)} for var, values in vars_.items()}}
        for o, vars_ in objects.items()}}


@_schema(_objects_schema)
def _objects(v, voc, where):
    """``{"charger": {"status": "idle"}, ...}``: every scenario object with every variable."""
    if not isinstance(v, dict):
        raise Rejected(f"{where} must be an object, got {type(v).__name__}")
    out = {}
    for o, vars_ in voc.object_vars.items():
        got = v.get(o)
        if not isinstance(got, dict):
            raise Rejected(f"{where}: missing object {o!r}" if got is None else f"{where}.{o} must be an object")
        out[o] = {}
        for var, values in vars_.items():
            x = got.get(var)
            if x not in values:
                raise Rejected(f"{where}.{o}.{var} = {x!r} is not one of {', '.join(values)}")
            out[o][var] = x
        unknown = set(got) - set(vars_)
        if unknown:
            raise Rejected(f"{where}.{o}: unknown variable {sorted(unknown)[0]!r}")
    unknown = set(v) - set(voc.object_vars)
    if unknown:
        raise Rejected(f"{where}: unknown object {sorted(unknown)[0]!r}; known: {', '.join(voc.object_vars)}")
    return out


_HUMAN_FIELDS = _obj({"presence": (_one_of("presences"), True), "relation": (_one_of("relations"), True)})
_ABSENT = "absent"  # the one value presence and relation share: each is absent iff the other is


def _human_json(voc) -> dict:
    """Presence and relation, and their agreement: both absent, or neither."""
    both = {k: {"const": _ABSENT} for k in ("presence", "relation")}
    neither = {k: {"not": {"const": _ABSENT}} for k in ("presence", "relation")}
    return dict(_HUMAN_FIELDS.json(voc), oneOf=[{"properties": both}, {"properties": neither}])


@_schema(_human_json)
def _human(v, voc, where):
    """The human of a world: presence and relation, which must agree (absent iff absent)."""
    out = _HUMAN_FIELDS(v, voc, where)
    if (out["presence"] == _ABSENT) != (out["relation"] == _ABSENT):
        raise Rejected(f"{where}: presence {out['presence']!r} contradicts relation {out['relation']!r}")
    return out


@_schema(lambda voc: {"type": ["string", "null"], "minLength": 1, "maxLength": 64})
def _symbol(v, voc, where):
    if v is not None and (not isinstance(v, str) or not v or len(v) > 64):
        raise Rejected(f"{where} must be a short symbol or null, got {v!r}")
    return v


def _prob_map(kind: str) -> Check:
    probabilities = _map(kind, _num(0.0, 1.0))

    @_schema(probabilities.json)  # that they sum to 1 only the check says
    def check(v, voc, where):
        out = probabilities(v, voc, where)
        s = sum(out.values())
        if out and abs(s - 1.0) > 1e-6:
            raise Rejected(f"{where}: probabilities sum to {s:.6f}, not 1")
        return out
    return check


PRAISE_SCOLD = {"praise": 1, "scold": -1}


@_schema(lambda voc: {"enum": list(PRAISE_SCOLD) + [None, -1, 0, 1]})
def _praise_scold(v, voc, where):
    """A person's answer: "praise" or "scold" (or +1 / -1), null or 0 for none; kept as +1/-1/0."""
    if v is None:
        return 0
    if isinstance(v, str) and v in PRAISE_SCOLD:
        return PRAISE_SCOLD[v]
    if not isinstance(v, bool) and v in (-1, 0, 1):
        return int(v)
    raise Rejected(f"{where} must be \"praise\", \"scold\" or null, got {v!r}")


@_schema(lambda voc: {})
def _any_json(v, voc, where):
    return v


def _param(spec) -> Check:
    """A parameter's value as its declaration (``params.ParamSpec``) takes it: a number in its range,
    a truth value."""
    if spec.kind is float:
        return _num(-math.inf if spec.lo is None else spec.lo, math.inf if spec.hi is None else spec.hi)
    if spec.kind is bool:
        return _bool
    raise TypeError(f"parameter {spec.name}: no message check for {spec.kind.__name__}")


COUNT = _int(0, 2**62)  # the envelope's run and tick
STAMP = _num(0.0, 1e12)  # the envelope's wall time, s
DRIVE = _num(0.0, 100.0)
ANY_NUMBER = _num(-1e9, 1e9)

OUTCOME_FIELDS = {
    "action": (_one_of("actions", nullable=True), True),
    "feedback": (_feedback, True),
    "proposal": (_one_of("actions", nullable=True), True),
    "clarified_intention": (_one_of("intentions", nullable=True), True),
    "body": (_map("drives", DRIVE, extra=ANY_NUMBER), False),  # body right after the action
    # ground truth of the simulated human, for the metrics only (robot nodes never read it)
    "truth": (_obj({"intention": (_one_of("intentions"), True), "expressed": (_bool, True),
                    "satisfied": (_bool, True)}), False),
}
_OUTCOME = _obj(OUTCOME_FIELDS)

SCHEMAS: dict[str, dict[str, tuple[Check, bool]]] = {
    # simulation or robot -> drives, decision: what the world looks like at the start of a tick
    "homeo/world": {
        "robot": (_obj({"location": (_one_of("locations"), True)}), True),
        "objects": (_objects, True),
        "human": (_human, True),
        # body drives by name, plus raw readings (battery_percent, temperature_status, ...)
        "body": (_map("drives", DRIVE, extra=ANY_NUMBER), True),
        "final": (_bool, False),  # the run ends with this tick: learn, do not act
        "outcome": (_OUTCOME, False),  # the outcome of tick k-1 (graph.Topic.carries; none at tick 0)
    },
    # simulation or robot -> intention: what the robot sees of the human this tick
    "homeo/observation": {
        "intention": (_one_of("intentions", nullable=True), False),  # oracle mode: observed directly
        "gesture": (_symbol, False),
        "movement": (_symbol, False),
        "keyword": (_symbol, False),
        "outcome": (_OUTCOME, False),  # the outcome of tick k-1: the intention its answer revealed
    },
    # intention -> drives: the recognised intention and its posterior (Eq 2.10)
    "homeo/intention": {
        "intention": (_one_of("intentions"), True),
        "posterior": (_prob_map("intentions"), True),
        "mode": (_one_of("modes"), True),
    },
    # drives -> decision: drives, stimuli, intensities (Eq 3.2), dominant motivation (Eq 3.3)
    "homeo/drives": {
        "drives": (_map("drives", DRIVE, complete=True), True),
        "stimuli": (_map("motivations", ANY_NUMBER, complete=True), True),
        "intensities": (_map("motivations", ANY_NUMBER, complete=True), True),
        "m_dom": (_one_of("internal_states"), True),
        "intention": (_one_of("intentions"), True),  # the one the stimuli were computed with
        # the world these drives were perceived in (robot, objects, human of homeo/world)
        "world": (_obj({"robot": (_obj({"location": (_one_of("locations"), True)}), True),
                        "objects": (_objects, True),
                        "human": (_human, True)}), True),
        "after_action": (_map("drives", DRIVE, complete=True), False),  # drives before the time step
        # what tick k-1's action did, as these drives took it in: the decision learns from it
        "outcome": (_obj({"action": (_one_of("actions", nullable=True), True), "feedback": (_feedback, True),
                          "proposal": (_one_of("actions", nullable=True), True)}), False),
        "final": (_bool, False),
    },
    # decision -> simulation or robot: the chosen action (null = none) and the drives it was chosen with
    "homeo/action": {
        "action": (_one_of("actions", nullable=True), True),
        "m_dom": (_one_of("internal_states"), False),
        "tau": (_num(0.0, 1e6), False),
        # the learning parameters in force, as declared (homeo_msgs_py.learning)
        "params": (_obj({spec.name: (_param(spec), True) for spec in LEARNING}), False),
        "drives": (_map("drives", DRIVE, complete=True), False),  # the drives the choice was made with
        "intention": (_one_of("intentions"), False),  # the recognised intention it was made for
        "after_action": (_map("drives", DRIVE, complete=True), False),
        "final": (_bool, False),  # the run ended: no action, only the last drives
    },
    # simulation or robot -> everyone: what the action did and what the human said
    "homeo/outcome": OUTCOME_FIELDS,
    # a person -> simulation (``--human person``): a wish, and the answer to the robot's last action.
    # Sent by hand (ros2 topic pub, homeo-topic pub, Foxglove), so the envelope may be left out:
    # ``homeo_msgs_py.human_input.decode_human_input``
    "homeo/human_input": {
        "intention": (_one_of("intentions", nullable=True), False),  # null or "none": no wish
        "feedback": (_praise_scold, False),
        "proposal": (_one_of("actions", nullable=True), False),
    },
    # world -> a person in the loop: the action being performed, and what the robot chose it for
    "homeo/last_action": {
        "action": (_one_of("actions", nullable=True), True),  # null: nothing (no action came)
        "intention": (_one_of("intentions"), False),  # the recognised intention it was chosen for
        "m_dom": (_one_of("internal_states"), False),
    },
    # world -> the devices around the robot: a command its config maps an action to (play, switch on)
    "homeo/device": {
        "device": (_str, True),
        "command": (_str, True),
        "action": (_one_of("actions", nullable=True), True),  # the action being performed
    },
    # world -> launcher: progress and, at the end, the run's metrics
    "homeo/run_status": {
        "iterations": (_int(0, 2**62), True),
        "done": (_bool, True),
        "missed": (_int(0, 2**62), True),
        "state": (_str, True),
        "metrics": (_any_json, False),
        "extra": (_any_json, False),
    },
}


class Vocabulary:
    """The names that message fields may take: ``kind -> names`` (actions, intentions, drives,
    motivations, locations, presences, relations, modes) and ``object_vars``: object -> variable ->
    values. ``homeo_decision.codec.vocabulary(scenario)`` builds the one of a scenario; without
    names only the envelope and the scenario-free schemas (run_status) can be checked."""

    def __init__(self, object_vars: dict | None = None, **names):
        from .graph import INTENTION_MODES

        self._names: dict[str, list[str]] = {"modes": list(INTENTION_MODES)}
        self._names.update({k: list(v) for k, v in names.items()})
        # m_dom's values: the motivations, unless the scenario adds "none" (no_activated_motivation)
        self._names.setdefault("internal_states", self._names.get("motivations", []))
        self.object_vars: dict[str, dict[str, list[str]]] = object_vars or {}

    def names(self, kind: str) -> list[str]:
        return self._names.get(kind, [])


def encode(schema: str, tick: int, fields: dict, run: int = 0, stamp: float | None = None) -> str:
    """One JSON message of ``schema``; the caller's fields are trusted (nodes build them from the core)."""
    env = {"schema": schema, "version": VERSION, "run": run, "tick": tick,
           "stamp": time.time() if stamp is None else stamp}
    env.update(fields)
    try:
        return json.dumps(env, separators=(",", ":"), allow_nan=False)
    except ValueError:  # a NaN or an infinity in the fields (a metric of no samples): null
        return json.dumps(finite(env), separators=(",", ":"), allow_nan=False)


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
    """A reason cut to ``limit`` characters, printable: what a sender put in it cannot flood
    /diagnostics or the log, nor break their encoding (lone surrogates become escapes)."""
    text = text.encode("utf-8", "backslashreplace").decode("utf-8")
    return text if len(text) <= limit else text[:limit - 3] + "..."


def _parse_constant(name: str):
    raise Rejected(f"{name} is not JSON (use null)")


def _check_tree(value: Any, text: str) -> None:
    """Depth, number of values, string length, integer size and finite numbers of ``value``,
    parsed from ``text``. The text's length says whether a string or the count can break a limit
    (parse hooks per number would cost three times the parse)."""
    strings = len(text) > MAX_STR
    count = text.count(",") + text.count(":") + 1 >= MAX_ITEMS  # a bound on the number of values
    n = 0
    stack = [(value, 1)]
    while stack:
        v, depth = stack.pop()
        t = type(v)
        if t is dict or t is list:
            if depth > MAX_DEPTH:
                raise Rejected(f"nested deeper than {MAX_DEPTH}")
            if t is dict:
                if strings:
                    for k in v:
                        if len(k) > MAX_STR:
                            raise Rejected(f"a key of {len(k)} characters (at most {MAX_STR})")
                items = v.values()
            else:
                items = v
            if count:
                n += len(v)
                if n > MAX_ITEMS:
                    raise Rejected(f"more than {MAX_ITEMS} values")
            for x in items:
                tx = type(x)
                if tx is dict or tx is list:
                    stack.append((x, depth + 1))
                elif tx is str:
                    if strings and len(x) > MAX_STR:
                        raise Rejected(f"a string of {len(x)} characters (at most {MAX_STR})")
                elif tx is float:
                    if x - x != 0.0:  # inf (1e999 parses to it) or nan
                        raise Rejected("a number out of range")
                elif tx is int and not -_INT_LIMIT < x < _INT_LIMIT:
                    _check_number(x)
        elif t is str:
            if len(v) > MAX_STR:
                raise Rejected(f"a string of {len(v)} characters (at most {MAX_STR})")
        elif t is int or t is float:
            _check_number(v)


def _check_number(x) -> None:
    if type(x) is float:
        if x - x != 0.0:  # inf (1e999 parses to it) or nan
            raise Rejected("a number out of range")
    elif not -_INT_LIMIT < x < _INT_LIMIT:
        raise Rejected(f"an integer of {len(str(abs(x)))} digits (at most {MAX_INT_DIGITS})")


def parse_json(text, limit: int = MAX_TEXT, what: str = "") -> Any:
    """The JSON value of a message's text, or :class:`Rejected` with the reason: not a string,
    too long, not JSON, or beyond a limit (depth, string length, integer digits, non-finite
    numbers, text that is not valid Unicode)."""
    if not isinstance(text, str):
        raise Rejected("not a string")
    if len(text) > limit:
        raise Rejected(f"message of {len(text)} characters is too long{what}")
    if "\\u" in text and _SURROGATE.search(text):
        raise Rejected("a \\u escape of a surrogate (send the character itself)")
    try:
        value = json.loads(text, parse_constant=_parse_constant)
    except Rejected:
        raise
    except RecursionError:  # the parser's own limit (about 1000 levels)
        raise Rejected(f"nested deeper than {MAX_DEPTH}") from None
    except ValueError as exc:  # JSONDecodeError is one; so is an integer of more than 4300 digits
        if "digits" in str(exc):
            raise Rejected(f"an integer of more than 4300 digits (at most {MAX_INT_DIGITS})") from None
        raise Rejected(short(f"not JSON ({exc.msg if hasattr(exc, 'msg') else exc})")) from None
    _check_tree(value, text)
    return value


def decode(text: str, voc: Vocabulary, expect: str | None = None) -> Message:
    """Parse and validate one message; raises :class:`Rejected` with the reason."""
    return validate(parse_json(text), voc, expect)


def validate(obj: Any, voc: Vocabulary, expect: str | None = None) -> Message:
    if not isinstance(obj, dict):
        raise Rejected(f"not a JSON object but {type(obj).__name__}")
    schema = obj.get("schema")
    if not isinstance(schema, str) or schema not in SCHEMAS:
        raise Rejected(short(f"unknown schema {schema!r}"))
    if expect is not None and schema != expect:
        raise Rejected(f"schema {schema!r} on a topic that carries {expect!r}")
    if obj.get("version") != VERSION:
        raise Rejected(short(f"{schema} version {obj.get('version')!r} is not {VERSION}"))
    run = COUNT(obj.get("run"), voc, "run")
    tick = COUNT(obj.get("tick"), voc, "tick")
    stamp = STAMP(obj.get("stamp"), voc, "stamp")
    body = {k: v for k, v in obj.items() if k not in ENVELOPE and k != AUTH_KEY}
    fields = _fields(body, SCHEMAS[schema], voc, "")
    return Message(schema, run, tick, stamp, fields)

"""Holds any world to the contract of ``world_api.WorldBackend``, as Gymnasium's ``check_env`` does.

It knows no world by name: what it expects of a world comes from what the world declares (its
parameters and capabilities), and a world that reaches the outside (a robot) is checked against the
stand-in its ``test_double`` gives. A robot's own package imports it in its tests::

    from homeo_decision.world_check import check_world
    assert check_world("tiago", qi_url="tcp://127.0.0.1:9559") == []   # each failure is one line

    python -m homeo_decision.world_check NAME [--param K=V ...] [--scenario FILE]
    # exit 0 when the world conforms; 1 with each failure in one line; 2 for a usage mistake (an unknown
    # world, a parameter it does not have or a value its declaration refuses)
"""

from __future__ import annotations

import copy
import json
import time
from contextlib import ExitStack

from homeo_msgs_py.graph import INTENTION_MODES, NODES, WORLD
from homeo_msgs_py.learning import LEARNING
from homeo_msgs_py.params import ParamSpec
from homeo_msgs_py.schemas import validate
from homeo_msgs_py.text import one_line

from . import codec
from .world_api import WORLD_PARAMS, WorldBackend, WorldConfigError, world_class

READY_S = 20.0  # a world that reaches a robot: how long it may take to be ready
CAPABILITIES = ("blocking", "KEEPS_STATE", "RESETS", "SEEDED", "FAILS_STEPS", "DROPS_LINK")


class Failure(AssertionError):
    """One broken rule, in one line."""


def _expect(ok: bool, text: str) -> None:
    if not ok:
        raise Failure(text)


def check_world(world, scenario=None, **params) -> list[str]:
    """Every rule of the contract on ``world`` (a registry name or a WorldBackend class) with ``params``
    (its parameters: values, or text as on a command line); a list of failures, each one line (empty:
    it conforms). ``scenario``: a Scenario or a file (default: the thesis's)."""
    from .scenario import ScenarioError, Scenario, load_scenario

    try:
        cls = world_class(world)
        sc = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
    except (WorldConfigError, ScenarioError) as exc:
        return [one_line(str(exc))]
    failures = _declaration(cls, world)
    try:
        values = _values(cls, params)
        cls.check(sc, values)
        with _Worlds(cls, sc, values) as ws:  # a world that cannot be built with these values: said once
            ws.make(0)
    except Exception as exc:  # noqa: BLE001 - a parameter refused, a WorldConfigError, whatever the world raises
        return failures + [_reason(exc, typed=not isinstance(exc, ValueError))]
    for check in (_contract, _seeding, _state, _link):
        try:
            check(cls, sc, values)
        except Failure as exc:
            failures.append(f"{check.__name__[1:]}: {_reason(exc, typed=False)}")
        except Exception as exc:  # noqa: BLE001 - whatever a world raises is a failure to report, not a crash
            failures.append(f"{check.__name__[1:]}: {_reason(exc)}")
    return failures


def _reason(exc: BaseException, typed: bool = True) -> str:
    """An exception as one line of the checker's list: its text with any line break escaped (it may quote a
    value the user gave), or, ``typed``, its type and the first line of its text (whatever a world raises)."""
    if not typed:
        return one_line(str(exc))
    return f"{type(exc).__name__}: {one_line(str(exc).splitlines()[0]) if str(exc) else ''}"


def _declaration(cls, name) -> list[str]:
    out = []
    if isinstance(name, str) and cls.NAME != name:
        out.append(f"NAME is {cls.NAME!r}, not its registry name {name!r}")
    for group in ("PARAMS", "LAUNCH"):
        specs = getattr(cls, group)
        if not all(isinstance(s, ParamSpec) for s in specs):
            out.append(f"{group} must hold homeo_msgs_py.params.ParamSpec declarations")
            continue
        names = [s.name for s in specs]
        clash = sorted(set(names) & {s.name for s in WORLD_PARAMS} | {n for n in names if names.count(n) > 1})
        if clash:
            out.append(f"{group} declares {', '.join(clash)} twice or over the world node's own")
    if not (isinstance(cls.INTENTIONS, dict) and cls.INTENTIONS and set(cls.INTENTIONS.values()) <= set(INTENTION_MODES)):
        out.append(f"INTENTIONS must map option values to the intention node's modes ({', '.join(INTENTION_MODES)})")
    ticks = cls.TICKS
    if not (isinstance(ticks, tuple) and len(ticks) == 2 and isinstance(ticks[0], str) and type(ticks[1]) is int
            and ticks[1] >= 0):
        out.append("TICKS must be (option name, default ticks >= 0)")
    out += [f"{c} must be true or false" for c in CAPABILITIES if type(getattr(cls, c)) is not bool]
    return out


def _values(cls, params: dict) -> dict:
    """The node's values of the world: the defaults, ``params`` over them, each checked by its declaration."""
    specs = {s.name: s for s in (*WORLD_PARAMS, *cls.PARAMS)}
    values = {n: s.default for n, s in specs.items()}
    values.update(intention_learns=True, world=cls.NAME)
    for k, v in params.items():
        if k not in specs:
            raise ValueError(f"no parameter {k!r}; the world's: {', '.join(s.name for s in cls.PARAMS) or 'none'}")
        values[k] = specs[k].parse(v) if isinstance(v, str) and specs[k].kind is not str else specs[k].check(v)
    return values


class _Worlds(ExitStack):
    """Worlds built as the node builds them, each on a test double of its own (a stand-in robot per world:
    two worlds with one seed meet the same outside world); all closed, and their doubles, at the end."""

    def __init__(self, cls, sc, values):
        super().__init__()
        self.cls, self.sc, self.values = cls, sc, values

    def make(self, seed: int) -> WorldBackend:
        values, drop = self.enter_context(self.cls.test_double(self.sc, dict(self.values, seed=seed)))
        w = self.cls(self.sc, values)
        self.callback(w.close)
        w.checker_drop = drop
        end = time.monotonic() + READY_S
        while w.ready() and time.monotonic() < end:
            time.sleep(0.05)
        _expect(not w.ready(), f"not ready within {READY_S:g} s: {'; '.join(w.ready())}")
        return w


def _message(schema: str, fields, voc, tick: int) -> dict:
    _expect(isinstance(fields, dict), f"{schema} fields must be an object, not {type(fields).__name__}")
    try:
        return validate(dict(fields, schema=schema, version=1, run=0, tick=tick, stamp=1.0), voc, schema).fields
    except ValueError as exc:
        raise Failure(f"tick {tick}: not a valid {schema}: {exc}") from None


def _action(sc, k: int, none_every: int = 0) -> dict | None:
    """The decision's message of tick k, as the decision node sends it; None every ``none_every`` ticks."""
    if none_every and k % none_every == none_every - 1:
        return None
    drives = {n: float((7 * k + 13 * i) % 100) for i, n in enumerate(sc.drive_names)}
    return {"action": sc.action_names[(5 * k + 3) % len(sc.action_names)], "m_dom": sc.internal_states[0],
            "tau": 1.0, "drives": drives, "after_action": drives, "intention": sc.intention_names[k % len(sc.intention_names)],
            "params": {s.name: s.default for s in LEARNING}}


def _run(w: WorldBackend, sc, ticks: int, none_every: int = 0, first: int = 0) -> list:
    """Observe, act and step ``ticks`` ticks, every message and rule checked; the messages, as JSON."""
    voc = codec.vocabulary(sc)
    trace = []
    for k in range(first, first + ticks):
        world, seen = w.observe(False)
        world, seen = _message("homeo/world", world, voc, k), _message("homeo/observation", seen, voc, k)
        a = _action(sc, k, none_every)
        if a is not None:
            w.check_action(a, k)  # a well-formed action of the vocabulary is taken
        out = _message("homeo/outcome", w.step(a), voc, k)
        if a is None:
            _expect(out["action"] is None and out["feedback"] == 0 and out["proposal"] is None,
                    f"tick {k}: no action came, yet the outcome says {out['action']!r}, feedback {out['feedback']}, "
                    f"proposal {out['proposal']!r}")
        else:
            _expect(out["action"] in (a["action"], None), f"tick {k}: asked {a['action']}, did {out['action']}")
            if out["action"] is None:
                _expect(out["feedback"] == 0 and out["proposal"] is None,
                        f"tick {k}: nothing was done, yet feedback {out['feedback']}, proposal {out['proposal']!r}")
        _expect(not (out["feedback"] == 1 and out["proposal"] is not None), f"tick {k}: a praise with a proposal")
        _expect(type(w.last_missed) is bool and (w.last_failure is None or isinstance(w.last_failure, str)),
                "last_missed must be true or false, last_failure text or None")
        w.record(a)
        for d in w.devices():
            tick = d.pop("tick", None)
            _expect(type(tick) is int and 0 <= tick <= k, f"a device command's tick {tick!r} is not a tick so far")
            _message("homeo/device", d, voc, tick)
        trace.append((world, seen, out))
    return json.loads(json.dumps(trace))  # as it goes over the wire: two runs are compared message by message


def _ticks(cls) -> int:
    return 6 if cls.blocking else 40  # a world that waits for the outside is slow


def _contract(cls, sc, values) -> None:
    with _Worlds(cls, sc, values) as ws:
        w = ws.make(3)
        _expect(set(w.inputs()) <= set(NODES[WORLD].external), f"inputs() reads {sorted(w.inputs())}, not topics "
                f"of the graph's external ones ({', '.join(NODES[WORLD].external)})")
        w.start()
        n = _ticks(cls)
        _run(w, sc, n, none_every=4)
        _expect(type(w.finished()) is bool, "finished() must be true or false")
        status = dict(w.status(False), iterations=n, done=False, missed=0, state="running")
        _message("homeo/run_status", status, codec.vocabulary(sc), n)
        json.dumps(status, allow_nan=True)
        for d in w.diagnostics():
            _expect(isinstance(d, dict) and set(d) == {"name", "hardware_id", "level", "message", "values"}
                    and d["level"] in (0, 1, 2, 3) and all(isinstance(k, str) and isinstance(v, str)
                                                           for k, v in d["values"].items()),
                    f"a diagnostic is not a DiagnosticStatus dict: {str(d)[:120]}")
        for level, text in w.poll():
            _expect(level in ("info", "warning", "burst") and isinstance(text, str), f"a bad notice {level!r}")
        if not cls.FAILS_STEPS:
            try:
                w.step_failed(_action(sc, n), "checked")
            except Exception:  # noqa: BLE001 - what it raises is its own: a world that cannot fail must raise
                pass
            else:
                raise Failure("step_failed gave an outcome, but the world does not declare FAILS_STEPS")


def _seeding(cls, sc, values) -> None:
    n = _ticks(cls)
    with _Worlds(cls, sc, values) as ws:
        a = ws.make(7)
        a.start()
        first = _run(a, sc, n)
        b = ws.make(7)
        b.start()
        _expect(_run(b, sc, n) == first, "two worlds with one seed answered the same actions differently")
        if cls.RESETS:
            a.reset(7)
            a.start()
            _expect(_run(a, sc, n) == first, "reset(seed) did not start the same run again (RESETS)")
        if cls.SEEDED:
            other = ws.make(8)
            other.start()
            _expect(_run(other, sc, n) != first, "another seed gave the same run (SEEDED)")


def _state(cls, sc, values) -> None:
    tick = 4 if cls.blocking else 33
    with _Worlds(cls, sc, values) as ws:
        a = ws.make(5)
        a.start()
        _run(a, sc, tick, none_every=5)
        rng, state = json.loads(json.dumps(a.state()))  # through the checkpoint file
        b = ws.make(5)
        b.set_state(copy.deepcopy(rng), copy.deepcopy(state), tick)
        _expect(json.loads(json.dumps(b.state())) == [rng, state], "a world set to a state does not give it back")
        if state:
            try:
                b.set_state(copy.deepcopy(rng), copy.deepcopy(state), tick + 1)
            except ValueError:
                pass
            else:
                raise Failure("set_state took a state at another tick than its own")
        if cls.KEEPS_STATE:
            _expect(_run(b, sc, 20, first=tick) == _run(a, sc, 20, first=tick),
                    "a world set to another's state did not go on as the other (KEEPS_STATE)")


def _link(cls, sc, values) -> None:
    if not cls.DROPS_LINK:
        return
    with _Worlds(cls, sc, values) as ws:
        w = ws.make(1)
        _expect(w.checker_drop is not None, "DROPS_LINK, but test_double gives no way to drop the link")
        w.start()
        _run(w, sc, 1)
        w.checker_drop(3.0)
        end, failed = time.monotonic() + 10.0, False
        while time.monotonic() < end and not failed:
            try:
                w.observe(False)
                time.sleep(0.2)
            except Exception:  # noqa: BLE001 - what the lockstep retries: whatever the world raises
                failed = True
        _expect(failed, "the reads went on while the link was down")
        _expect(bool(w.ready()), "ready() says nothing while the link is down")
        end = time.monotonic() + 15.0
        while w.ready() and time.monotonic() < end:
            time.sleep(0.1)
        _expect(not w.ready(), "the link did not come back")
        out = w.step_failed(_action(sc, 1), "the link dropped")
        _expect(out["action"] is None and out["feedback"] == 0 and w.last_missed,
                "the outcome of a step cut by the drop must say nothing was done, and last_missed")
        _run(w, sc, 1, first=2)  # back: the run goes on


def main(argv=None) -> int:
    from homeo_msgs_py.cli_args import Parser, UserError, key_value, run_command, user_path

    def command() -> int:
        ap = Parser(prog="world_check", description="Hold a world of the homeo_robot.worlds registry to the contract.")
        ap.add_argument("world", help="its registry name")
        ap.add_argument("--param", metavar="K=V", type=key_value, action="append", default=[],
                        help="one of the world's parameters, as on a command line (repeat for more)")
        ap.add_argument("--scenario", metavar="FILE", type=user_path, help="scenario JSON (default: the thesis's)")
        a = ap.parse_args(argv)
        try:
            cls = world_class(a.world)
            _values(cls, dict(a.param))
        except (WorldConfigError, ValueError) as exc:
            raise UserError(str(exc)) from None
        failures = check_world(a.world, a.scenario, **dict(a.param))
        print("\n".join(f"{a.world}: {f}" for f in failures) or f"{a.world}: conforms")
        return 1 if failures else 0

    return run_command("world_check", command)


if __name__ == "__main__":
    import sys

    from homeo_msgs_py.cli_args import leave

    code = main()
    if "qi" in sys.modules:  # a Pepper's check ran a libqi session on loopback: its teardown may abort
        leave(code)
    raise SystemExit(code)

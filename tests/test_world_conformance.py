"""Every registered world keeps the world contract (``homeo_decision.world_api``), in the spirit of
Gymnasium's ``check_env``: run on each entry of the ``homeo_robot.worlds`` registry, the Pepper on a
stand-in robot over a real libqi session on loopback.

- the declaration: the name is the registry's, the parameters are declarations that accept their
  own defaults, the topics read from outside are the graph's;
- reset / observe / step: every world, observation and outcome is a valid message of the contract
  (``schemas.validate`` against the scenario's vocabulary), the outcome's fields say what was done
  and how the human answered, the status is a valid run status;
- seeding: two worlds with one seed answer the same actions with the same messages, and a reset to
  the seed starts the same run again;
- the run's checkpoint: the state is JSON, a new world set to it goes on exactly as the old one;
- a dropped robot: a tick with no action (the decision never answered) is a valid outcome and the
  run goes on; a Pepper whose link drops fails its reads until the robot is back, then observes again.
"""

from __future__ import annotations

import copy
import json
import time

import pytest

from homeo_decision import codec
from homeo_decision.world_api import WorldBackend, registered, world_class
from homeo_msgs_py.graph import NODES, WORLD
from homeo_msgs_py.params import ParamSpec
from homeo_msgs_py.schemas import validate

WORLDS = sorted(registered())


def test_the_registry_holds_the_three_shipped_worlds():
    assert {"sim", "pepper", "day"} <= set(WORLDS)


@pytest.fixture
def make(thesis):
    """``make(name, seed)`` -> a world as the world node builds it (the Pepper on its own stand-in,
    time frozen, with the field test's scripted user); all are closed after the test."""
    made = []

    def build(name: str, seed: int = 0):
        cls = world_class(name)
        values = {s.name: s.default for s in cls.PARAMS}
        values.update(seed=seed, intention_learns=True)
        if name == "pepper":
            from pepper_bridge.config import load_config
            from pepper_bridge.standin import StandinRobot
            from pepper_bridge.user import load_script

            robot = StandinRobot(load_config(scenario=thesis), load_script("field_user.json"), seed=seed,
                                 time_scale=0.0, scenario=thesis)
            values.update(qi_url=robot.start(), collect_window=2.0, collect_quiet=0.15)
            made.append(robot)
        w = cls(thesis, values)
        made.append(w)
        if name == "pepper":
            assert w.bridge.wait_connected(10.0), w.bridge.status()
            w.standin = made[-2]
        return w

    yield build
    for x in reversed(made):
        x.close()


def _message(schema: str, fields: dict, voc, tick: int = 0) -> dict:
    return validate(dict(fields, schema=schema, version=1, run=0, tick=tick, stamp=1.0), voc, schema).fields


def _action(sc, k: int, none_every: int = 0) -> dict | None:
    """The decision's message of tick k, as the decision node sends it; None every ``none_every``
    ticks (the robot dropped: no action came)."""
    if none_every and k % none_every == none_every - 1:
        return None
    drives = {n: float((7 * k + 13 * i) % 100) for i, n in enumerate(sc.drive_names)}
    return {"action": sc.action_names[(5 * k + 3) % len(sc.action_names)], "m_dom": sc.internal_states[0],
            "tau": 1.0, "drives": drives, "after_action": drives, "intention": sc.intention_names[k % 3],
            "params": {"dod": 0.25, "xi": 1.0, "gamma": 0.5, "feedback": True, "pseudo_update": True}}


def _run(world: WorldBackend, sc, ticks: int, none_every: int = 0) -> list:
    """Observe, act and step ``ticks`` ticks; every message checked against the contract; the messages."""
    voc = codec.vocabulary(sc)
    trace = []
    for k in range(ticks):
        w, seen = world.observe(False)
        w, seen = _message("homeo/world", w, voc, k), _message("homeo/observation", seen, voc, k)
        a = _action(sc, k, none_every)
        if a is not None:
            world.check_action(a, k)  # a well-formed action of the vocabulary is taken
            _message("homeo/action", a, voc, k)
        out = _message("homeo/outcome", world.step(a), voc, k)
        if a is None or out["action"] is None:  # nothing done: nothing to answer
            assert out["feedback"] == 0 and out["proposal"] is None, out
        else:
            assert out["action"] == a["action"], (a, out)
        if out["feedback"] == 1:
            assert out["proposal"] is None  # a proposal comes with a scolding (Sec 3.2.6)
        world.record(a)
        for d in world.devices():
            tick = d.pop("tick")
            assert type(tick) is int and 0 <= tick <= k
            _message("homeo/device", d, voc, tick)
        trace.append((w, seen, out))
    return trace


def _json(trace: list) -> list:
    """A trace as it goes over the wire (tuples become lists): two runs are compared message by message."""
    return json.loads(json.dumps(trace))


@pytest.mark.qi
@pytest.mark.parametrize("name", WORLDS)
def test_the_world_declares_itself_as_the_node_needs(name):
    cls = world_class(name)
    assert cls.NAME == name and issubclass(cls, WorldBackend)
    assert all(isinstance(s, ParamSpec) and s.check(s.default) == s.default for s in cls.PARAMS)
    assert len({s.name for s in cls.PARAMS}) == len(cls.PARAMS)


@pytest.mark.qi
@pytest.mark.parametrize("name", WORLDS)
def test_reset_observe_step_speak_the_contract(make, thesis, name):
    w = make(name, 3)
    assert set(w.inputs()) <= set(NODES[WORLD].external)
    assert isinstance(w.ready(), list) and all(isinstance(x, str) for x in w.ready())
    w.start()
    n = 6 if name == "pepper" else 40
    trace = _run(w, thesis, n, none_every=4)
    assert len(trace) == n and type(w.finished()) is bool
    assert type(w.last_missed) is bool
    st = w.status(False)
    validate(dict(st, iterations=n, done=False, missed=0, state="running", schema="homeo/run_status", version=1,
                  run=0, tick=n, stamp=1.0), codec.vocabulary(thesis), "homeo/run_status")
    for d in w.diagnostics():
        assert set(d) == {"name", "hardware_id", "level", "message", "values"} and d["level"] in (0, 1, 2, 3)
        assert all(isinstance(k, str) and isinstance(v, str) for k, v in d["values"].items())
    json.dumps(st, allow_nan=True)  # what the node encodes (schemas.encode: a NaN goes out as null)


@pytest.mark.qi
@pytest.mark.parametrize("name", WORLDS)
def test_one_seed_one_run_and_a_reset_starts_it_again(make, thesis, name):
    n = 5 if name == "pepper" else 60
    a = make(name, 7)
    a.start()
    first = _json(_run(a, thesis, n))
    b = make(name, 7)
    b.start()
    assert _json(_run(b, thesis, n)) == first
    if name == "pepper":
        return  # the robot's world goes on; its reset starts a new log, not a new world
    a.reset(7)
    a.start()
    assert _json(_run(a, thesis, n)) == first
    other = make(name, 8)
    other.start()
    if name == "sim":  # the simulated human draws from its seed (a day's person follows the script)
        assert _json(_run(other, thesis, n)) != first


@pytest.mark.qi
@pytest.mark.parametrize("name", WORLDS)
def test_a_world_set_to_its_state_goes_on_as_the_old_one(make, thesis, name):
    a = make(name, 5)
    a.start()
    _run(a, thesis, 4 if name == "pepper" else 33, none_every=5)
    rng, state = a.state()
    rng, state = json.loads(json.dumps(rng)), json.loads(json.dumps(state))  # through the file
    tick = 4 if name == "pepper" else 33
    b = make(name, 5)
    b.set_state(copy.deepcopy(rng), copy.deepcopy(state), tick)
    assert json.loads(json.dumps(b.state())) == [rng, state]
    with pytest.raises(ValueError):
        b.set_state(rng, state, tick + 1)  # another tick than the state's
    if name == "pepper":
        return  # the robot's world lives on the robot: the state is the log, checked above
    assert _json(_run(b, thesis, 20)) == _json(_run(a, thesis, 20))


@pytest.mark.qi
def test_a_pepper_whose_link_drops_fails_its_reads_until_the_robot_is_back(make, thesis):
    w = make("pepper", 1)
    w.start()
    _run(w, thesis, 1)
    from pepper_bridge.environment import NotReady
    from pepper_bridge.naoqi_link import RobotUnavailable

    w.standin.drop_for(3.0)
    end = time.monotonic() + 10.0
    failed = False
    while time.monotonic() < end and not failed:
        try:
            w.observe(False)
            time.sleep(0.2)
        except (RobotUnavailable, NotReady):  # what the lockstep driver retries
            failed = True
    assert failed, "the reads went on while the robot was away"
    assert w.ready(), "a dropped robot is not ready"
    assert w.bridge.wait_connected(15.0), w.bridge.status()
    out = w.step_failed(_action(thesis, 1), "robot dropped")  # the tick the drop cut: nothing done
    assert out["action"] is None and out["feedback"] == 0 and w.last_missed
    _run(w, thesis, 1)  # back: the run goes on

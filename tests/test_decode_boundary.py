"""The decode boundary is total (issue 11): any payload of any size or shape becomes a valid
message or a rejection with a reason, and no valid-looking message makes a node's handler fail
in any other way. Property-based (``hypothesis``) over every schema, every input of every node,
the launcher's own subscriptions and the person's input; the same handlers as the nodes run
(``homeo_msgs_py.lockstep``, ``homeo_decision.hosts``, ``homeo_intention.recognition``).
"""

from __future__ import annotations

import json

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from homeo_decision.agent import DecisionCore
from homeo_decision.codec import vocabulary
from homeo_decision.hosts import DecisionHost, PerceptionHost
from homeo_intention.recognition import RecognitionHost
from homeo_msgs_py.auth import Signer
from homeo_msgs_py.graph import BAYES, GRAPH, NODES, TOPICS
from homeo_msgs_py.human_input import decode_human_input
from homeo_msgs_py.lockstep import LockstepDriver
from homeo_msgs_py.schemas import (ENVELOPE, MAX_REASON, SCHEMAS, Message, Rejected, Vocabulary, decode, encode,
                                   parse_json, short)
from homeo_sim.world_backend import SimWorld

# JSON values with the shapes that crashed nodes before: huge integers, non-finite floats, lone
# surrogates, deep nesting, long strings, wrong containers
SCALARS = (st.none() | st.booleans() | st.integers() | st.integers(min_value=10**17, max_value=10**500)
           | st.floats(allow_nan=True, allow_infinity=True) | st.text(max_size=40)
           | st.sampled_from(["\ud800", "x" * 5000, "Chat", "none", "H", "NAch", "Serving", "idle", "praise"]))
JSON = st.recursive(SCALARS, lambda inner: st.lists(inner, max_size=4)
                    | st.dictionaries(st.text(max_size=12) | st.sampled_from(["\udfff", "schema", "run"]), inner,
                                      max_size=4), max_leaves=20)


def _sample_messages(sc) -> dict[str, list[str]]:
    """Real messages of each topic from a short run of the graph's logic (the bus of test_graph_stages)."""
    from homeo_ops.bus import Bus, graph_readers, robot_hosts

    bus = Bus(vocabulary(sc), 0)
    side = SimWorld(sc, {"seed": 1, "intention_learns": True})
    sent: dict[str, list[str]] = {}

    def send(key, tick, fields, run=0):
        bus.send(key, tick, fields, run)
        sent.setdefault(key, []).append(bus.queue[-1][1])

    driver = LockstepDriver(side, send, iterations=3)
    hosts, readers = robot_hosts(sc, BAYES, 1), graph_readers(True)
    driver.begin()
    for _ in range(40):
        for key, m in bus.drain():
            for n in readers.get(key, []):
                if n == "homeo_world":
                    driver.on_action(m)
                else:
                    for k, fields in hosts[n].stage.put(key, m):
                        send(NODES[n].publishes[0], k, fields)
    send("run_status", driver.tick, driver.status_fields(), 0)
    return sent


@pytest.fixture(scope="module")
def world(thesis):
    """Every node's handler, as the node wires it, on one scenario; and real messages to mutate."""
    voc = vocabulary(thesis)
    side = SimWorld(thesis, {"seed": 2, "intention_learns": True})
    driver = LockstepDriver(side, lambda *a: None, iterations=50)
    driver.begin()
    intention = RecognitionHost(thesis, BAYES)

    def on_observation(m):  # homeo_intention.node: check, then join
        try:
            intention.check(m.fields)
        except ValueError as exc:
            raise Rejected(str(exc)) from None
        intention.stage.put("observation", m)

    drives, decision = PerceptionHost(thesis), DecisionHost(thesis, DecisionCore(thesis, 2))
    handlers = {
        ("homeo_world", "action"): driver.on_action,
        ("homeo_intention", "observation"): on_observation,
        **{("homeo_drives", k): (lambda m, k=k: drives.stage.put(k, m)) for k in ("world", "intention")},
        ("homeo_decision", "drives"): lambda m: decision.stage.put("drives", m),
    }
    # every input of every node of the graph has its handler here
    assert set(handlers) == {(n, i.topic) for n in GRAPH for i in NODES[n].reads(True)}
    return voc, handlers, _sample_messages(thesis)


def _total(text, voc, schema):
    """decode's contract: a Message or Rejected with a one-line reason; nothing else."""
    try:
        m = decode(text, voc, schema)
    except Rejected as exc:
        reason = short(str(exc))
        assert "\n" not in reason and len(reason) <= MAX_REASON
        return None
    assert isinstance(m, Message) and m.schema == schema
    encode(m.schema, m.tick, m.fields, run=m.run)  # what was accepted can be sent on (no NaN, no surrogate)
    return m


def _handle(handlers, key, m):
    for (node, k), h in handlers.items():
        if k == key and m is not None:
            try:
                h(m)
            except Rejected:
                pass


@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(key=st.sampled_from(sorted(TOPICS)), text=st.text(max_size=200) | JSON.map(json.dumps))
def test_any_text_is_a_message_or_a_reason(world, key, text):
    voc, handlers, _ = world
    _handle(handlers, key, _total(text, voc, TOPICS[key].schema))


@settings(max_examples=600, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(data=st.data())
def test_a_real_message_with_any_field_changed_is_handled_or_refused(world, data):
    voc, handlers, samples = world
    key = data.draw(st.sampled_from(sorted(samples)))
    obj = json.loads(data.draw(st.sampled_from(samples[key])))
    names = sorted(set(obj) | set(SCHEMAS[obj["schema"]]) | set(ENVELOPE))
    field = data.draw(st.sampled_from(names))
    how = data.draw(st.sampled_from(["set", "delete", "nest"]))
    if how == "delete":
        obj.pop(field, None)
    elif how == "set":
        obj[field] = data.draw(JSON)
    elif isinstance(obj.get(field), dict) and obj[field]:  # change one value inside a nested object
        inner = data.draw(st.sampled_from(sorted(obj[field])))
        obj[field][inner] = data.draw(JSON)
    _handle(handlers, key, _total(json.dumps(obj), voc, TOPICS[key].schema))


@settings(max_examples=300, deadline=None)
@given(text=st.text(max_size=300) | JSON.map(json.dumps))
def test_the_launchers_status_and_the_person_input_are_total(text):
    voc = Vocabulary()
    signer = Signer(b"k" * 32)
    for t in (text, signer.sign(text) if text.endswith("}") else text):
        try:  # homeo_launch.monitor: the run status, signed by the graph
            decode(signer.verify(t), voc, "homeo/run_status")
        except Rejected:
            pass
    try:
        decode_human_input(text, voc)
    except Rejected:
        pass


@pytest.mark.parametrize("text, reason", [
    ('{"a": ' + "1" * 5000 + "}", "Integer value out of range"),
    ("[" * 5000 + "]" * 5000, "nested too deep"),
    ('{"a": 1e999}', "out of range"),
    ('{"a": NaN}', "not JSON"),
    ('{"\\ud83d": 1}', "not JSON"),
    ("x" * 70000, "too long"),
], ids=["digits", "depth", "overflow", "nan", "surrogate", "size"])
def test_each_limit_has_its_reason(text, reason):
    with pytest.raises(Rejected, match=reason):
        parse_json(text)


@pytest.mark.parametrize("extra, reason", [
    ({"x": "y" * 2000}, "a string of 2000 characters"), ({"x": [[[[[[[[[1]]]]]]]]]}, "nested deeper than 8"),
    ({"x": list(range(5000))}, "more than 4096 values"), ({"x": 2**63}, "an integer beyond"),
])
def test_the_free_json_of_a_run_status_is_bounded(extra, reason):
    """The run status's ``extra`` is any JSON (a robot's log): its size, depth and numbers are bounded."""
    text = encode("homeo/run_status", 1, {"iterations": 1, "done": False, "missed": 0, "state": "running", "extra": extra})
    with pytest.raises(Rejected, match=reason):
        decode(text, Vocabulary(), "homeo/run_status")


def test_nan_never_leaves_a_node():
    text = encode("homeo/run_status", 1, {"iterations": 1, "done": True, "missed": 0, "state": "done",
                                         "metrics": {"HSR": float("nan"), "x": [float("inf"), 1.0]}})
    assert "NaN" not in text and "Infinity" not in text
    assert json.loads(text)["metrics"] == {"HSR": None, "x": [None, 1.0]}
    # the launcher reads null back as "no value" (a run interrupted before any sample)
    import math

    from homeo_sim.stats import describe

    assert math.isnan(describe([None])["mean"]) and describe([None, 2.0])["per_seed"][1] == 2.0


def test_signatures_hand_computed():
    import hashlib
    import hmac

    s = Signer(b"0123456789abcdef")
    body = '{"schema":"homeo/action","tick":1}'
    want = hmac.new(b"0123456789abcdef", body.encode(), hashlib.sha256).hexdigest()
    signed = s.sign(body)
    assert signed == body[:-1] + ',"auth":"' + want + '"}'
    assert s.verify(signed) == body and json.loads(signed)["auth"] == want
    for bad in (body, signed.replace("tick\":1", "tick\":2"), signed[:-3] + '0"}',
                Signer(b"another key 1234").sign(body)):
        with pytest.raises(Rejected):
            s.verify(bad)

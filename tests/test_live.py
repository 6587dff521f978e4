"""``--foxglove``: a Foxglove WebSocket client sees the topics advertised with their JSON schemas,
subscribes and receives the run live. Plus the JSON schemas against the contract."""

from __future__ import annotations

import asyncio
import json
import os
import signal
import socket
import struct
import subprocess
import sys
import time

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from homeo_decision import codec
from homeo_msgs_py.json_schemas import fields, json_schema
from homeo_msgs_py.schemas import ENVELOPE, SCHEMAS, Rejected, validate


def test_every_json_schema_has_exactly_the_contracts_fields(thesis):
    voc = codec.vocabulary(thesis)
    for name, spec in SCHEMAS.items():
        js = json_schema(name, voc)
        assert set(js["properties"]) == set(spec) | set(ENVELOPE), name
        assert set(js["required"]) - set(ENVELOPE) == {k for k, (_, required) in spec.items() if required}, name
    drives = json_schema("homeo/drives", voc)["properties"]
    assert set(drives["drives"]["properties"]) == set(thesis.drive_names)
    assert sorted(drives["m_dom"]["enum"]) == sorted(thesis.motivation_names)
    assert set(fields("homeo/human_input", voc)) == {"intention", "feedback", "proposal"}
    params = json_schema("homeo/action", voc)["properties"]["params"]["properties"]
    assert params["xi"] == {"type": "number", "minimum": 0.0, "maximum": 1e6}  # from homeo_msgs_py.learning
    assert params["pseudo_update"] == {"type": "boolean"}


def _conforms(value, schema: dict) -> bool:
    """``value`` against the JSON Schema keywords json_schemas.py emits (type, enum, const, minimum,
    maximum, minLength, maxLength, properties, required, additionalProperties)."""
    types = schema.get("type")
    if types is not None:
        kinds = {"number": lambda v: type(v) in (int, float), "integer": lambda v: type(v) is int,
                 "boolean": lambda v: type(v) is bool, "string": lambda v: type(v) is str,
                 "object": lambda v: type(v) is dict, "null": lambda v: v is None}
        if not any(kinds[t](value) for t in ([types] if isinstance(types, str) else types)):
            return False
    if "enum" in schema and not any(value == e and type(value) is type(e) or (value is None and e is None)
                                    for e in schema["enum"]):
        return False
    if "const" in schema and value != schema["const"]:
        return False
    if type(value) in (int, float) and not (schema.get("minimum", value) <= value <= schema.get("maximum", value)):
        return False
    if type(value) is str and not schema.get("minLength", 0) <= len(value) <= schema.get("maxLength", len(value)):
        return False
    if type(value) is dict:
        props = schema.get("properties", {})
        if any(k not in value for k in schema.get("required", ())):
            return False
        extra = schema.get("additionalProperties", True)
        for k, v in value.items():
            sub = props.get(k, extra)
            if sub is False or (isinstance(sub, dict) and not _conforms(v, sub)):
                return False
    return True


def test_the_checker_of_the_test_refuses_what_a_schema_excludes():
    s = {"type": "object", "properties": {"a": {"type": "integer", "minimum": 0, "maximum": 3}},
         "required": ["a"], "additionalProperties": False}
    assert _conforms({"a": 2}, s)
    assert not any(_conforms(v, s) for v in ({"a": 4}, {"a": True}, {}, {"a": 1, "b": 0}, [], {"a": 1.5}))
    assert not _conforms(None, {"enum": ["x"]}) and _conforms(None, {"enum": ["x", None]})


@pytest.fixture(scope="module")
def samples(thesis):
    from test_decode_boundary import _sample_messages

    return codec.vocabulary(thesis), _sample_messages(thesis)


def test_every_real_message_conforms_to_its_json_schema(samples):
    voc, sent = samples
    assert sent
    for key, texts in sent.items():
        for text in texts:
            obj = json.loads(text)
            obj.pop("auth", None)  # the signature is not described
            assert _conforms(obj, json_schema(obj["schema"], voc)), (key, text)


@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_a_message_its_json_schema_refuses_the_contract_refuses_too(samples, data):
    """The JSON Schemas say no less than the checks they come from: a value the viewer's schema
    refuses is refused by ``validate`` (what the check knows beyond the schema, such as
    probabilities summing to 1, may refuse more)."""
    from test_decode_boundary import JSON

    voc, sent = samples
    key = data.draw(st.sampled_from(sorted(sent)))
    obj = json.loads(data.draw(st.sampled_from(sent[key])))
    obj.pop("auth", None)
    schema = json_schema(obj["schema"], voc)
    target = obj
    path = [data.draw(st.sampled_from(sorted(set(obj) | set(schema["properties"]))))]
    while isinstance(target.get(path[-1]), dict) and target[path[-1]] and data.draw(st.booleans()):
        target = target[path[-1]]
        path.append(data.draw(st.sampled_from(sorted(target))))
    if data.draw(st.booleans()):
        target.pop(path[-1], None)
    else:
        target[path[-1]] = data.draw(JSON | st.sampled_from([-1, 2, 1e6 + 1, 101.0, "none", None, True]))
    if not _conforms(obj, schema):
        with pytest.raises(Rejected):
            validate(obj, voc, obj.get("schema"))


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


async def _watch(port: int, topic: str, want: int, bound: float):
    import websockets

    end = time.monotonic() + bound
    while True:  # the launcher takes a few seconds to serve
        try:
            ws = await websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=["foxglove.sdk.v1"])
            break
        except OSError:
            if time.monotonic() > end:
                raise
            await asyncio.sleep(0.3)
    async with ws:
        channel, got = None, []
        while len(got) < want:
            msg = await asyncio.wait_for(ws.recv(), max(0.1, end - time.monotonic()))
            if isinstance(msg, str):
                op = json.loads(msg)
                if op["op"] == "advertise" and channel is None:
                    for ch in op["channels"]:
                        if ch["topic"] == topic:
                            channel = ch
                            await ws.send(json.dumps({"op": "subscribe",
                                                      "subscriptions": [{"id": 7, "channelId": ch["id"]}]}))
            elif msg[0] == 1:  # message data: opcode, subscription id, timestamp, payload
                sub_id, _stamp = struct.unpack_from("<IQ", msg, 1)
                assert sub_id == 7
                got.append(json.loads(msg[13:]))
        return channel, got


@pytest.mark.ros
def test_a_websocket_client_sees_drives_advertised_with_its_schema_and_receives_the_run(tmp_path):
    from rosgraph import fresh_domain

    from homeo_launch.processes import graph_env

    port = _free_port()
    proc = subprocess.Popen([sys.executable, "-m", "homeo_launch.cli", "sim", "--iterations", "0", "--rate", "20",
                             "--quiet", "--foxglove", str(port)], env=graph_env(fresh_domain()),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        channel, got = asyncio.run(_watch(port, "/homeo/drives", 10, 90.0))
    finally:
        os.killpg(proc.pid, signal.SIGINT)
        out, err = proc.communicate(timeout=30)
    assert channel["encoding"] == "json" and channel["schemaEncoding"] == "jsonschema"
    assert channel["schemaName"] == "homeo/drives"
    schema = json.loads(channel["schema"])
    assert {"drives", "intensities", "m_dom"} <= set(schema["properties"])
    assert len(got) >= 10 and all(m["schema"] == "homeo/drives" for m in got)
    ticks = [m["tick"] for m in got]
    assert ticks == sorted(ticks) and len(set(ticks)) == len(ticks)
    assert proc.returncode == 0, err  # Ctrl-C of an unbounded run: the metrics so far, exit 0
    assert "HSR" in out


def test_foxglove_option_is_checked():
    from homeo_launch.cli import main

    assert main(["sim", "--foxglove", "host:notaport"]) == 2
    assert main(["sim", "--foxglove", "70000"]) == 2


def test_the_layout_in_docs_is_current_and_plots_what_the_schemas_offer(thesis):
    from pathlib import Path

    from homeo_record.foxglove_layout import layout

    doc = json.loads((Path(__file__).parents[1] / "docs" / "foxglove-layout.json").read_text())
    assert doc == layout(thesis)  # regenerate: python -m homeo_record.foxglove_layout > docs/foxglove-layout.json
    voc = codec.vocabulary(thesis)
    for panel in doc["configById"].values():
        for p in panel.get("paths", []):
            topic, *path = p["value"].lstrip("/").split(".")
            props = json_schema(topic, voc)["properties"]
            head = path[0]
            assert head in props, p["value"]
            if len(path) == 2 and "properties" in props[head] and head != "metrics":
                assert path[1] in props[head]["properties"], p["value"]


@pytest.mark.ros
# Once intermittent: a client that advertised its channel before the launcher named the accepted topics
# (the server is up before ``attach``) had its channel ignored for the whole session. The client here
# connects as early as it can, which is what found it.
def test_foxglove_publish_plays_the_human_and_the_bag_keeps_it(tmp_path):
    """A client publishes a wish on /homeo/human_input (Foxglove's Publish panel does this): the run,
    which waits for the person's first word, starts, and the bag records the input and its effect."""
    from rosgraph import fresh_domain

    from homeo_record.bag import load_run
    from homeo_launch.processes import graph_env

    port, bag = _free_port(), tmp_path / "bag"
    proc = subprocess.Popen([sys.executable, "-m", "homeo_launch.cli", "sim", "--human", "person", "--intention", "oracle",
                             "--iterations", "2", "--human-timeout", "1", "--quiet", "--json", "--record", str(bag),
                             "--foxglove", str(port)], env=graph_env(fresh_domain()),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)

    async def speak():
        import websockets

        end = time.monotonic() + 90
        while True:
            try:
                ws = await websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=["foxglove.sdk.v1"])
                break
            except OSError:
                assert time.monotonic() < end
                await asyncio.sleep(0.3)
        async with ws:
            info = json.loads(await asyncio.wait_for(ws.recv(), 10))
            assert "clientPublish" in info["capabilities"]
            await ws.send(json.dumps({"op": "advertise", "channels": [
                {"id": 5, "topic": "/homeo/human_input", "encoding": "json", "schemaName": "homeo/human_input"}]}))
            # as a person would: speak once the run status says the world waits for the first word, and
            # say it again until heard (the server has no acknowledgement of a client's advertisement)
            state = None
            said, said_at = 0, 0.0
            while state not in ("running", "finishing", "done"):
                timeout = max(0.1, min(1.0, end - time.monotonic()))
                try:
                    msg = await asyncio.wait_for(ws.recv(), timeout)
                except asyncio.TimeoutError:
                    msg = None
                assert time.monotonic() < end, f"the run never started (state {state}, said {said} times)"
                if isinstance(msg, str):
                    op = json.loads(msg)
                    for ch in op.get("channels", []) if op["op"] == "advertise" else []:
                        if ch["topic"] == "/homeo/run_status":
                            await ws.send(json.dumps({"op": "subscribe", "subscriptions": [{"id": 1, "channelId": ch["id"]}]}))
                elif msg is not None and msg[0] == 1:
                    state = json.loads(msg[13:])["state"]
                if state == "starting" and time.monotonic() - said_at > 1.0:
                    await ws.send(b"\x01" + struct.pack("<I", 5) + json.dumps({"intention": "light"}).encode())
                    said, said_at = said + 1, time.monotonic()
            await asyncio.sleep(1.0)

    try:
        asyncio.run(speak())
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert proc.returncode == 0, err
    run = load_run(bag)
    outs = run.by_tick("outcome")
    assert outs[0]["truth"]["intention"] == "light"  # the client's wish was tick 0's
    assert outs[1]["truth"]["intention"] in ("light", "none")  # then silence (or the wish said again)

"""``--foxglove [HOST:]PORT``: the run served live to the Foxglove app (Foxglove WebSocket protocol).

A tap sink (``tap.py``) over ``foxglove-sdk``'s server: each homeo topic is a channel with JSON
encoding and the payload's JSON Schema (``homeo_msgs_py.json_schemas``), so the app plots
``/homeo/drives.drives.<drive>``, intensities, m_dom and the run status's HSR and RSR by name; the
payload is the message's own JSON text, passed on without re-encoding. ``/diagnostics`` goes out as
the CDR it came in, with its ``ros2msg`` definition. The server binds 127.0.0.1 unless told
otherwise. ``docs/foxglove-layout.json`` is a layout with those plots and the interaction log.

With ``--human person`` the app's Publish panel can play the human: a client channel on
``/homeo/human_input`` is forwarded to that topic (``on_message``).
"""

from __future__ import annotations

import json
import time

from homeo_msgs_py.graph import TOPICS, key_of

from .tap import DIAG_KEY, Tapped, string_data

SERVER_NAME = "homeo-robot"


MATCH_WAIT_S = 10.0  # how long a client's message waits for the topic's reader


class _Listener:
    """The server's callbacks: client-published messages on an accepted topic go to ``on_message``."""

    def __init__(self, accept: dict):
        self.accept = accept  # topic -> callback(text)
        self.channels: dict = {}  # (client id, client channel id) -> topic

    def on_client_advertise(self, client, channel) -> None:
        # every channel, accepted or not yet: a client may advertise as soon as the server is up, before
        # ``attach`` names the topics (that race lost a client's channel for its whole session)
        self.channels[(client.id, channel.id)] = channel.topic

    def on_client_unadvertise(self, client, client_channel_id: int) -> None:
        self.channels.pop((client.id, client_channel_id), None)

    def on_subscribe(self, client, channel) -> None:
        pass

    def on_unsubscribe(self, client, channel) -> None:
        pass

    def on_message_data(self, client, client_channel_id: int, data: bytes) -> None:
        forward = self.accept.get(self.channels.get((client.id, client_channel_id)))
        if forward is not None:  # a topic not accepted (or not yet: before attach) is dropped
            try:
                forward(bytes(data).decode("utf-8"))
            except UnicodeDecodeError:
                pass  # not text: the topic's own decoder would refuse it anyway


class FoxgloveSink:
    def __init__(self, where: tuple[str, int], sc, topics: list[Tapped] | None = None, person: bool = False):
        import foxglove
        from foxglove import Channel, Context, Schema
        from foxglove.websocket import Capability
        from rosbags.typesys import Stores, get_typestore

        from homeo_decision import codec
        from homeo_msgs_py.json_schemas import json_schema

        from .tap import tapped_topics

        host, port = where
        voc = codec.vocabulary(sc)
        self.ctx = Context()  # its own: two servers in one process never share channels
        self.channels: dict = {}
        for t in topics or tapped_topics():
            if t.key == DIAG_KEY:
                msgdef = get_typestore(Stores.ROS2_JAZZY).generate_msgdef(t.msgtype, ros_version=2)[0]
                schema = Schema(name=t.msgtype, encoding="ros2msg", data=msgdef.encode())
                self.channels[t.name] = (Channel(t.name, schema=schema, message_encoding="cdr", context=self.ctx), False)
            else:
                name = TOPICS[t.key].schema if t.key in TOPICS else f"homeo/{t.key}"
                schema = Schema(name=name, encoding="jsonschema", data=json.dumps(json_schema(name, voc)).encode())
                self.channels[t.name] = (Channel(t.name, schema=schema, message_encoding="json", context=self.ctx), True)
        self.listener = _Listener({})  # filled in by attach: the launcher's node publishes what a client sends
        self.person = person
        caps = [Capability.ClientPublish] if person else []
        try:
            self.server = foxglove.start_server(name=SERVER_NAME, host=host, port=port, context=self.ctx,
                                                capabilities=caps, supported_encodings=["json"] if person else None,
                                                server_listener=self.listener)
        except Exception as exc:  # noqa: BLE001 - the SDK raises its own error types for a bind failure
            from homeo_msgs_py.cli_args import UserError

            raise UserError(f"--foxglove {host}:{port}: cannot serve there ({exc})") from None
        self.port = self.server.port

    def attach(self, node) -> None:
        """With a person as the human: what a client (Foxglove's Publish panel) sends on
        /homeo/human_input is published there by ``node``; the simulation decodes it as any input."""
        if not self.person:
            return
        from std_msgs.msg import String

        from homeo_msgs_py.qos import pub_qos

        name = next((n for n in self.channels if key_of(n) == "human_input"), "/" + TOPICS["human_input"].name)
        pub = node.create_publisher(String, name, pub_qos("human_input"))

        def forward(text: str) -> None:
            # a volatile event is lost if published before the simulation's reader matched (the person's
            # first word starts the run): hold it until then, bounded (this is the server's thread)
            end = time.monotonic() + MATCH_WAIT_S
            while pub.get_subscription_count() < 1 and time.monotonic() < end:
                time.sleep(0.05)
            pub.publish(String(data=text))  # rcl publish is thread-safe

        self.listener.accept[name] = forward

    def write(self, t: Tapped, stamp_ns: int, raw: bytes) -> None:
        entry = self.channels.get(t.name)
        if entry is None:
            return
        ch, is_json = entry
        if not ch.has_sinks():
            return  # nobody watches: skip the copy
        if is_json:
            try:
                ch.log(string_data(raw).encode(), log_time=stamp_ns)
            except ValueError:
                pass
        else:
            ch.log(bytes(raw), log_time=stamp_ns)

    def close(self) -> None:
        if self.server is not None:
            s, self.server = self.server, None
            s.stop()

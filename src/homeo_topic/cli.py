"""``homeo-topic``: look at and poke the graph without the ``ros2`` CLI.

    homeo-topic list [--wait S]
    homeo-topic echo TOPIC [--count N] [--timeout S] [--compact]
    homeo-topic pub TOPIC JSON [--times N] [--rate HZ] [--wait S]
    homeo-topic param NODE NAME [VALUE]          (get, or set: VALUE is JSON, e.g. 0.3 or true)
    homeo-topic call SERVICE                     (a std_srvs/Trigger service, e.g. /homeo_decision/save_q)

All take [--scenario FILE] [--set KEY=VALUE]: the scenario that names the actions and
intentions ``pub`` and ``echo`` check against. ``pub`` fills in what the envelope lacks
(schema, version, run 0, tick 0, stamp now) and refuses a message the nodes would drop.
With a full ROS 2 install, ``ros2 topic echo /homeo/drives`` and ``ros2 param set
/homeo_decision dod 0.3`` do the same: the graph uses only std_msgs, std_srvs and
standard parameters.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

from homeo_decision.codec import vocabulary
from homeo_msgs_py.cli_args import Parser, UserError, float_in, int_at_least, setting
from homeo_msgs_py.graph import DIAGNOSTICS, TOPICS, key_of
from homeo_msgs_py.schemas import SCHEMAS, VERSION, Rejected, Vocabulary, decode, validate

PROG = "homeo-topic"


def _key(topic: str) -> str:
    key = key_of(topic)
    if key is None:
        raise UserError(f"{topic} is not a homeo topic; known: {', '.join(t.name for t in TOPICS.values())}")
    return key


def _vocabulary(args) -> Vocabulary:
    from homeo_decision.scenario import load_scenario

    # --set parsed as every command parses it (cli_args.setting); the scenario validates the values
    return vocabulary(load_scenario(args.scenario, overrides=dict(args.set)))


class _Ros:
    def __init__(self):
        import rclpy
        from rclpy.signals import SignalHandlerOptions

        from homeo_msgs_py.qos import dds_defaults

        os.environ.update(dds_defaults())
        rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
        self.rclpy = rclpy
        self.node = rclpy.create_node(f"homeo_topic_{os.getpid()}")

    def spin_for(self, seconds: float, until=None) -> bool:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.rclpy.spin_once(self.node, timeout_sec=min(0.05, max(0.0, end - time.monotonic())))
            if until is not None and until():
                return True
        return until() if until is not None else True

    def close(self):
        self.node.destroy_node()
        self.rclpy.try_shutdown()


def cmd_list(args) -> int:
    ros = _Ros()
    try:
        ros.spin_for(args.wait)
        n = ros.node
        me = n.get_name()
        topics = sorted(n.get_topic_names_and_types())
        nodes = sorted(x for x in n.get_node_names() if x != me)
        print("nodes:")
        for name in nodes:
            print(f"  {name}")
        print("topics:")
        for name, types in topics:
            pubs = [i.node_name for i in n.get_publishers_info_by_topic(name) if i.node_name != me]
            subs = [i.node_name for i in n.get_subscriptions_info_by_topic(name) if i.node_name != me]
            if not pubs and not subs:
                continue
            key = key_of(name)
            schema = f"  [{TOPICS[key].schema}]" if key else ""
            print(f"  {name}  {', '.join(types)}{schema}")
            print(f"      writers: {', '.join(pubs) or '-'}   readers: {', '.join(subs) or '-'}")
    finally:
        ros.close()
    return 0


def _diag_text(msg) -> dict:
    return {"stamp": msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9,
            "status": [{"name": s.name, "level": int.from_bytes(s.level, "little") if isinstance(s.level, bytes)
                        else int(s.level), "message": s.message, "values": {kv.key: kv.value for kv in s.values}}
                       for s in msg.status]}


def cmd_echo(args) -> int:
    voc = _vocabulary(args)
    ros = _Ros()
    seen = [0]
    try:
        if args.topic == DIAGNOSTICS:
            from diagnostic_msgs.msg import DiagnosticArray

            def on_diag(msg):
                seen[0] += 1
                print(json.dumps(_diag_text(msg), indent=None if args.compact else 2), flush=True)

            ros.node.create_subscription(DiagnosticArray, DIAGNOSTICS, on_diag, 10)
        else:
            from std_msgs.msg import String

            from homeo_msgs_py.qos import sub_qos

            key = _key(args.topic)
            schema = TOPICS[key].schema

            def on_msg(msg):
                seen[0] += 1
                try:
                    decode(msg.data, voc, schema)
                    note = None
                except Rejected as exc:
                    note = str(exc)
                try:
                    text = json.dumps(json.loads(msg.data), indent=None if args.compact else 2)
                except json.JSONDecodeError:
                    text = msg.data
                if note:
                    print(f"# invalid: {note}", flush=True)
                print(text, flush=True)

            ros.node.create_subscription(String, TOPICS[key].name, on_msg, sub_qos(key))
        end = time.monotonic() + args.timeout if args.timeout else None
        while (not args.count or seen[0] < args.count) and (end is None or time.monotonic() < end):
            ros.rclpy.spin_once(ros.node, timeout_sec=0.1)
        if args.count and seen[0] < args.count:
            print(f"{PROG}: {seen[0]} of {args.count} messages within {args.timeout:g} s", file=sys.stderr)
            return 1
    finally:
        ros.close()
    return 0


def build_message(topic: str, text: str, voc: Vocabulary) -> str:
    """The JSON to publish: envelope filled in, then validated as the nodes will."""
    schema = TOPICS[_key(topic)].schema
    try:
        obj = json.loads(text)
    except json.JSONDecodeError as exc:
        raise UserError(f"the message is not JSON: {exc.msg} at column {exc.colno}") from None
    if not isinstance(obj, dict):
        raise UserError("the message must be a JSON object")
    obj.setdefault("schema", schema)
    obj.setdefault("version", VERSION)
    obj.setdefault("run", 0)
    obj.setdefault("tick", 0)
    obj.setdefault("stamp", time.time())
    try:
        validate(obj, voc, schema)
    except Rejected as exc:
        fields = ", ".join(SCHEMAS[schema])
        raise UserError(f"{topic} would drop this message: {exc} (fields of {schema}: {fields})") from None
    return json.dumps(obj)


def cmd_pub(args) -> int:
    voc = _vocabulary(args)
    text = build_message(args.topic, args.json, voc)
    from std_msgs.msg import String

    from homeo_msgs_py.qos import pub_qos

    key = _key(args.topic)
    name = TOPICS[key].name
    ros = _Ros()
    try:
        pub = ros.node.create_publisher(String, name, pub_qos(key))
        # every reader the graph knows of, matched: publishing when the first matched (``ros2 topic
        # pub --once``) loses the message for a reader that matches later (a volatile topic), and a
        # person's wish has two (the world node and the recorder of --record); a short settle lets a
        # reader discovered a moment later count too
        def all_matched() -> bool:
            n = pub.get_subscription_count()
            return n > 0 and n >= ros.node.count_subscribers(name)

        if not ros.spin_for(args.wait, all_matched):
            print(f"{PROG}: note: not every reader of {args.topic} matched within {args.wait:g} s; publishing anyway",
                  file=sys.stderr)
        else:
            ros.spin_for(0.3)
            ros.spin_for(args.wait, all_matched)
        for i in range(args.times):
            pub.publish(String(data=text))
            if i + 1 < args.times:
                ros.spin_for(1.0 / args.rate)
        # the readers may not have matched this publisher yet when it matched them (discovery runs both
        # ways): wait until every reader acknowledged, so the message is not lost with the publisher
        from rclpy.duration import Duration

        if not pub.wait_for_all_acked(Duration(seconds=args.wait)):
            print(f"{PROG}: note: not every reader acknowledged within {args.wait:g} s", file=sys.stderr)
        print(f"published {args.times} message{'s' if args.times != 1 else ''} on {args.topic}")
    finally:
        ros.close()
    return 0


def cmd_param(args) -> int:
    from rcl_interfaces.srv import GetParameters, SetParameters
    from rclpy.parameter import Parameter, parameter_value_to_python

    node = args.node if args.node.startswith("/") else "/" + args.node
    ros = _Ros()
    try:
        if args.value is None:
            cli = ros.node.create_client(GetParameters, f"{node}/get_parameters")
            req = GetParameters.Request(names=[args.name])
        else:
            try:
                value = json.loads(args.value)
            except json.JSONDecodeError:
                value = args.value
            cli = ros.node.create_client(SetParameters, f"{node}/set_parameters")
            req = SetParameters.Request(parameters=[Parameter(args.name, value=value).to_parameter_msg()])
        if not cli.wait_for_service(timeout_sec=args.wait):
            raise UserError(f"node {node} is not running (no parameter service within {args.wait:g} s)")
        fut = cli.call_async(req)
        if not ros.spin_for(args.wait, fut.done):
            raise UserError(f"{node} did not answer within {args.wait:g} s")
        res = fut.result()
        if args.value is None:
            if not res.values or res.values[0].type == 0:
                raise UserError(f"{node} has no parameter {args.name!r}")
            print(json.dumps(parameter_value_to_python(res.values[0])))
            return 0
        r = res.results[0]
        if not r.successful:
            raise UserError(f"{node} refused {args.name}={args.value}: {r.reason}")
        print(f"set {node} {args.name} = {args.value}")
    finally:
        ros.close()
    return 0


def cmd_call(args) -> int:
    from std_srvs.srv import Trigger

    ros = _Ros()
    try:
        cli = ros.node.create_client(Trigger, args.service)
        if not cli.wait_for_service(timeout_sec=args.wait):
            raise UserError(f"service {args.service} is not available (waited {args.wait:g} s)")
        fut = cli.call_async(Trigger.Request())
        if not ros.spin_for(args.wait, fut.done):
            raise UserError(f"{args.service} did not answer within {args.wait:g} s")
        res = fut.result()
        print(f"{'ok' if res.success else 'failed'}: {res.message}")
        return 0 if res.success else 1
    finally:
        ros.close()


WAIT = float_in(0.0, 3600.0)  # seconds of discovery or of a service's answer


def build_parser() -> argparse.ArgumentParser:
    ap = Parser(prog=PROG, description="Inspect the homeo graph (no ros2 CLI needed).")
    sub = ap.add_subparsers(dest="cmd", required=True, parser_class=Parser)

    def scen(p):
        p.add_argument("--scenario", metavar="FILE", default=None, help="scenario JSON (default: the thesis)")
        p.add_argument("--set", metavar="KEY=VALUE", type=setting, action="append", default=[],
                       help="open-choice override")

    ls = sub.add_parser("list", help="nodes and topics with their writers and readers")
    ls.add_argument("--wait", type=WAIT, default=3.0, help="seconds of discovery before listing (default 3)")
    e = sub.add_parser("echo", help="print a topic's messages as JSON")
    e.add_argument("topic")
    e.add_argument("--count", type=int_at_least(0), default=0, help="stop after N messages (default: until Ctrl-C)")
    e.add_argument("--timeout", type=float_in(0.0, 1e9), default=0.0, help="stop after S seconds (default: never)")
    e.add_argument("--compact", action="store_true", help="one line per message")
    scen(e)
    p = sub.add_parser("pub", help="validate a JSON message and publish it")
    p.add_argument("topic")
    p.add_argument("json")
    p.add_argument("--times", type=int_at_least(1, 10 ** 6), default=1)
    p.add_argument("--rate", type=float_in(1e-3, 1e4), default=10.0, help="messages per second with --times (default 10)")
    p.add_argument("--wait", type=WAIT, default=3.0, help="seconds to wait for a reader (default 3)")
    scen(p)
    pa = sub.add_parser("param", help="get or set a node's parameter")
    pa.add_argument("node")
    pa.add_argument("name")
    pa.add_argument("value", nargs="?")
    pa.add_argument("--wait", type=WAIT, default=5.0)
    c = sub.add_parser("call", help="call a std_srvs/Trigger service")
    c.add_argument("service")
    c.add_argument("--wait", type=WAIT, default=5.0)
    return ap


def main(argv=None) -> int:
    from homeo_decision.scenario import ScenarioError

    try:
        args = build_parser().parse_args(argv)
        return {"list": cmd_list, "echo": cmd_echo, "pub": cmd_pub, "param": cmd_param, "call": cmd_call}[args.cmd](args)
    except (UserError, ScenarioError) as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130
    except BrokenPipeError:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141


if __name__ == "__main__":
    sys.exit(main())

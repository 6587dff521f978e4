"""Microseconds to decode and validate one message, per topic, with this tree's ``homeo_msgs_py.schemas.decode``.

The messages are a recorded bag's (``homeo-launch sim --iterations 20 --record DIR``), read with rosbags; the
``outcome`` field (issue 29's contract) and the signature are taken out so that a tree of the contract before
decodes the very same texts. The best of five passes of 200 over the bag's messages:

    .venv/bin/python tools/decode_bench.py DIR
    git worktree add /tmp/old 0cd9795 && PYTHONPATH=/tmp/old/src .venv/bin/python tools/decode_bench.py DIR
"""

import json
import sys
import time

from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore

from homeo_decision.codec import vocabulary
from homeo_decision.scenario.load import load_scenario
from homeo_msgs_py import schemas


def texts_by_topic(bag: str) -> dict:
    ts = get_typestore(Stores.ROS2_JAZZY)
    out: dict = {}
    with Reader(bag) as r:
        for c, _, raw in r.messages():
            if c.topic.startswith("/homeo/") and c.topic != "/homeo/run_status":
                d = json.loads(ts.deserialize_cdr(raw, c.msgtype).data)
                d.pop("outcome", None)
                d.pop("auth", None)
                out.setdefault(c.topic, []).append(json.dumps(d, separators=(",", ":")))
    return out


def main(bag: str) -> None:
    voc = vocabulary(load_scenario())
    for topic, texts in sorted(texts_by_topic(bag).items()):
        schema = json.loads(texts[0])["schema"]
        best = float("inf")
        for _ in range(5):
            t0 = time.perf_counter()
            for _ in range(200):
                for x in texts:
                    schemas.decode(x, voc, schema)
            best = min(best, (time.perf_counter() - t0) / (200 * len(texts)))
        print(f"{topic:22s} {best * 1e6:6.1f} us")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: tools/decode_bench.py BAG_DIR")
    try:
        main(sys.argv[1])
    except Exception as exc:  # noqa: BLE001 - not a bag rosbags can read (rosbags' own error), or no homeo message
        sys.exit(f"decode_bench: {sys.argv[1]}: {str(exc).splitlines()[0] if str(exc) else type(exc).__name__}")

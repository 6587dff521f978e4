"""Command-line options of the launcher's tap, shared by ``sim`` and ``pepper``."""

from __future__ import annotations

import argparse


def add_live_options(p) -> None:
    """--record and --foxglove, shared by sim and pepper."""
    p.add_argument("--record", metavar="DIR", help="record every topic as a rosbag2 bag (MCAP) in this new folder")
    p.add_argument("--record-from", choices=("writers", "tap"), default="writers",
                   help="writers (default): each node keeps what it sends, merged into the bag after the run (stamped "
                        "when sent; costs the tick a few microseconds a message); tap: the launcher subscribes to "
                        "every topic (stamped when received, strangers' messages kept; costs the tick about 10-30%%)")
    p.add_argument("--foxglove", metavar="[HOST:]PORT", type=host_port, default=None,
                   help="serve the run live to the Foxglove app over WebSocket (host 127.0.0.1 unless given)")


def host_port(text: str) -> tuple[str, int]:
    """``PORT`` or ``HOST:PORT``; the host defaults to loopback (nothing leaves the machine unasked)."""
    host, _, port = text.rpartition(":")
    host = host.strip("[]") or "127.0.0.1"
    try:
        n = int(port)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not [HOST:]PORT") from None
    if not 0 <= n <= 65535:
        raise argparse.ArgumentTypeError(f"port {n} is outside 0..65535")
    return host, n

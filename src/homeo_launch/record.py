"""``--record DIR``: the run as a rosbag2 bag (``metadata.yaml`` + MCAP storage, CDR messages).

Written with ``rosbags`` (pure Python, no ROS install): every topic of the graph as
``std_msgs/msg/String`` and ``/diagnostics`` as ``diagnostic_msgs/msg/DiagnosticArray``, each with
its writers' QoS in the metadata, so ``ros2 bag play`` republishes the latched topics latched.
Messages are the CDR bytes the tap received (``tap.py``), stamped with their arrival time, as
``ros2 bag record`` does. The run's settings (graph, ticks, seed, the scenario itself) go into the
metadata's ``custom_data`` so that ``homeo-replay`` needs the bag alone.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from homeo_msgs_py.cli_args import UserError

from .tap import Tapped, pub_qos_of

RUN_INFO_KEY = "homeo.run"  # metadata.yaml custom_data: the run's settings as JSON
BAG_VERSION = 9  # rosbag2 metadata version of ROS 2 Jazzy


def check_new_bag(path: str) -> Path:
    """The bag folder to create; a one-line error for an existing path or a missing parent."""
    p = Path(path)
    if p.exists():
        raise UserError(f"--record {path}: already exists (a bag is never overwritten)")
    parent = p.absolute().parent
    if not parent.is_dir():
        raise UserError(f"--record {path}: the directory {parent} does not exist")
    if not os.access(parent, os.W_OK):
        raise UserError(f"--record {path}: {parent} is not writable")
    return p


def _bag_qos(profile):
    """An rclpy QoS profile as rosbags describes it (both use the rmw enum values)."""
    from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime

    def t(d):
        ns = d.nanoseconds
        return QosTime(ns // 1_000_000_000, ns % 1_000_000_000)

    return Qos(QosHistory(int(profile.history)), profile.depth, QosReliability(int(profile.reliability)),
               QosDurability(int(profile.durability)), t(profile.deadline), t(profile.lifespan),
               QosLiveliness(int(profile.liveliness)), t(profile.liveliness_lease_duration),
               bool(profile.avoid_ros_namespace_conventions))


class BagSink:
    """A tap sink writing a rosbag2 bag; ``close`` writes the index and metadata.yaml."""

    def __init__(self, path: str | Path, info: dict, topics: list[Tapped]):
        from rosbags.rosbag2 import StoragePlugin, Writer
        from rosbags.typesys import Stores, get_typestore

        self.path = Path(path)
        self.writer = Writer(self.path, version=BAG_VERSION, storage_plugin=StoragePlugin.MCAP)
        self.writer.open()
        self.writer.set_custom_data(RUN_INFO_KEY, json.dumps(info, separators=(",", ":")))
        store = get_typestore(Stores.ROS2_JAZZY)
        self.conns = {t.name: self.writer.add_connection(t.name, t.msgtype, typestore=store,
                                                         offered_qos_profiles=[_bag_qos(pub_qos_of(t))])
                      for t in topics}
        self.count = 0

    def write(self, t: Tapped, stamp_ns: int, raw: bytes) -> None:
        self.writer.write(self.conns[t.name], stamp_ns, raw)
        self.count += 1

    def close(self) -> None:
        if self.writer is not None:
            w, self.writer = self.writer, None
            w.close()


def run_info(graph: str, iterations: int, seed: int, sc, overrides, **extra) -> dict:
    """What homeo-replay needs besides the messages: the run's settings and its scenario's text
    (``sc``: the loaded scenario, whose ``source`` is its file)."""
    return dict(extra, graph=graph, iterations=iterations, seed=seed, overrides=dict(overrides),
                scenario_source=str(sc.source), scenario=json.loads(Path(sc.source).read_text()))

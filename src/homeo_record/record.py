"""``--record DIR``: the run as a rosbag2 bag (``metadata.yaml`` + MCAP storage, CDR messages).

Written with ``rosbags`` (pure Python, no ROS install): every topic of the graph as
``std_msgs/msg/String`` and ``/diagnostics`` as ``diagnostic_msgs/msg/DiagnosticArray``, each with
its writers' QoS in the metadata, so ``ros2 bag play`` republishes the latched topics latched.
Two ways to fill it (``--record-from``): ``WriterBag`` (default) merges what each node kept of what it
sent (``homeo_msgs_py.spool``), stamped with the send time; ``BagSink`` takes the CDR bytes the
launcher's tap received (``tap.py``), stamped with their arrival time, as ``ros2 bag record`` does. The run's settings (graph, ticks, seed, the scenario itself) go into the
metadata's ``custom_data`` so that ``homeo-replay`` needs the bag alone.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from homeo_decision import jsonfile
from homeo_msgs_py.cli_args import UserError
from homeo_msgs_py.schemas import one_line
from homeo_msgs_py.graph import NODES, WORLD

from .tap import DIAG_KEY, DIAGNOSTIC_ARRAY, STRING, Tapped, pub_qos_of

RUN_INFO_KEY = "homeo.run"  # metadata.yaml custom_data: the run's settings as JSON
BAG_VERSION = 9  # rosbag2 metadata version of ROS 2 Jazzy


def check_new_bag(path: str) -> Path:
    """The bag folder to create (its parent made if missing); a one-line error for an existing path
    or a parent that cannot be made or written."""
    p = Path(path)
    if p.exists():
        raise UserError(f"--record {path}: already exists (a bag is never overwritten)")
    parent = p.absolute().parent
    try:
        parent.mkdir(parents=True, exist_ok=True)  # --record runs/me makes runs/, as a user expects
    except OSError as exc:
        raise UserError(f"--record {path}: {parent}: {exc.strerror}") from None
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


def new_bag(path, info: dict, topics: list[Tapped], record_from: str = "writers"):
    """The bag ``--record`` writes, filled as ``--record-from`` says: ``WriterBag`` or ``BagSink``."""
    return (WriterBag if record_from == "writers" else BagSink)(path, info, topics)


def run_info(graph: str, iterations: int, seed: int, sc, overrides, **extra) -> dict:
    """What homeo-replay needs besides the messages: the run's settings and its scenario's text
    (``sc``: the loaded scenario, whose ``source`` is its file)."""
    return dict(extra, graph=graph, iterations=iterations, seed=seed, overrides=dict(overrides),
                scenario_source=str(sc.source), scenario=json.loads(Path(sc.source).read_text()))


class WriterBag:
    """``--record`` at the writers (the default; ``homeo_msgs_py.spool``): every node appends what it
    sends to a spool of its own, the launcher what it publishes (/diagnostics of restarts) and what
    its tap takes from outside the graph (``homeo/human_input``, a person's); ``close`` merges them
    in the order they were sent into a rosbag2 bag written as ``BagSink`` writes one, then deletes
    the spools. The graph never waits for a recorder: there is none on the wire."""

    at_writers = True
    OUTSIDE = NODES[WORLD].external  # written by no node of the graph: taken by the tap

    def __init__(self, path: str | Path, info: dict, topics: list[Tapped]):
        self.path, self.info, self.topics = Path(path), info, topics
        self.tap_topics = [t for t in topics if t.key in self.OUTSIDE]
        self.spool_dir: Path | None = None
        self.own = None  # the launcher's spool
        self.count = 0

    def prepare(self, data_dir: str) -> str:
        """The spool folder, made inside the nodes' data directory (where they accept a path)."""
        import tempfile

        from homeo_msgs_py.spool import SpoolWriter

        if self.spool_dir is None:
            os.makedirs(data_dir, exist_ok=True)
            self.spool_dir = Path(tempfile.mkdtemp(prefix=SPOOL_PREFIX, dir=data_dir))
            write_manifest(self.spool_dir, self.path, self.info, self.topics)
            self.own = SpoolWriter(self.spool_dir, "homeo_launch")
        return str(self.spool_dir)

    def write(self, t: Tapped, stamp_ns: int, raw: bytes) -> None:
        """A message the tap took (one of ``tap_topics``), kept with its arrival stamp."""
        if self.own is not None and t in self.tap_topics:
            self.own.cdr(t.name, raw, stamp_ns)

    def close(self) -> None:
        """Merge the spools into the bag (also after Ctrl-C: what was sent is kept), then delete them."""
        import shutil

        if self.spool_dir is None:
            return
        self.own.close()
        self.count = merge_spools(self.spool_dir, self.path, self.info, self.topics)
        shutil.rmtree(self.spool_dir, ignore_errors=True)
        self.spool_dir = None


def spools_to_bag(folder: Path, bag: Path, info: dict, topics: list[Tapped]) -> int:
    """``merge_spools``, then the spool folder deleted; if it fails no half bag is left to block a
    second try (``homeo-launch recover``): a one-line ``NotRecovered`` for a full disk or a folder not
    writable, and the folder kept."""
    import shutil

    from rosbags.rosbag2 import WriterError

    try:
        n = merge_spools(folder, bag, info, topics)
    except BaseException as exc:  # Ctrl-C too
        shutil.rmtree(bag, ignore_errors=True)
        if isinstance(exc, (OSError, WriterError)):
            raise NotRecovered(f"{folder}: writing {bag}: {getattr(exc, 'strerror', None) or exc}") from None
        raise
    shutil.rmtree(folder, ignore_errors=True)
    return n


def merge_spools(spool_dir: Path, path: Path, info: dict, topics: list[Tapped]) -> int:
    """The spools of ``spool_dir`` merged in the order sent into a new bag at ``path`` (as ``BagSink``
    writes one); the number of messages written. Topics outside ``topics`` are left out."""
    from rosbags.typesys import Stores, get_typestore

    from homeo_msgs_py.spool import TEXT, read_spools

    records, torn = read_spools(spool_dir)
    store = get_typestore(Stores.ROS2_JAZZY)
    String = store.types[STRING]
    by_name = {t.name: t for t in topics}
    raws, unreadable = [], 0
    for r in records:
        t = by_name.get(r.topic)
        if t is None:
            continue  # a topic outside the bag's list
        if r.kind != TEXT:
            raws.append((t, r.stamp_ns, r.payload))  # CDR as sent
            continue
        try:  # a String's text; a spool is a file on disk: it may have been spoilt
            if t.msgtype != STRING:
                raise ValueError("text on a topic that is not a std_msgs/String")
            raws.append((t, r.stamp_ns, bytes(store.serialize_cdr(String(data=r.payload.decode("utf-8")), STRING))))
        except ValueError:  # UnicodeDecodeError included
            unreadable += 1
    sink = BagSink(path, dict(info, recorded_at="writers", torn_bytes=torn, unreadable_records=unreadable), topics)
    try:
        for t, stamp, raw in raws:
            sink.write(t, stamp, raw)
    finally:
        sink.close()
    return sink.count


# -- what a spool folder says of itself (for ``homeo-launch recover``) ---------------------------
SPOOL_PREFIX = ".homeo-record-"  # the spool folders, inside the data directory
MANIFEST = "bag.json"  # in a spool folder: the bag it is for, and what the merge needs
MANIFEST_SCHEMA, MANIFEST_VERSION = "homeo-record-spool", 1


def proc_start(pid: int) -> int | None:
    """When process ``pid`` started (clock ticks since boot, /proc/PID/stat field 22; proc(5)), or
    None if no such process runs (a zombie has ended): with the pid, it names one process, never a
    later one given the same pid."""
    from .procfs import stat_fields

    fields = stat_fields(int(pid))
    try:
        return None if fields[0] in ("Z", "X") else int(fields[19])  # fields[0] is field 3
    except (TypeError, ValueError, IndexError):  # TypeError: no such process
        return None


def write_manifest(spool_dir: Path, path: Path, info: dict, topics: list[Tapped]) -> None:
    """Written before any node appends: a launcher killed outright leaves a folder that says which
    bag it was recording, how, and who was recording it (so a live recording is never taken)."""
    from homeo_decision.jsonfile import write_atomic

    write_atomic(spool_dir / MANIFEST, {
        "schema": MANIFEST_SCHEMA, "version": MANIFEST_VERSION, "bag": str(Path(path).absolute()),
        "launcher": [os.getpid(), proc_start(os.getpid())], "info": info,
        "topics": [[t.key, t.name, t.msgtype, t.kind] for t in topics]}, UserError, "the recording's manifest")


KINDS = ("state", "event", "diagnostics")
MAX_MANIFEST = 16 << 20  # bytes: the run's settings and its scenario's text, with room to spare


class NotRecovered(Exception):
    """A spool folder whose manifest cannot be used (``str()``: why, on one line)."""


def read_manifest(folder: Path) -> tuple[Path, list, dict, list[Tapped]]:
    """The bag path, the launcher (pid, start), the run's settings and the topics a spool folder's
    manifest names; anything else is a one-line ``NotRecovered``."""
    where = folder / MANIFEST
    if not where.exists():
        raise NotRecovered(f"{folder}: no {MANIFEST} (an older version's recording, or one killed before it began); "
                           "its spools are in the format of homeo_msgs_py/spool.py")
    try:
        if where.stat().st_size > MAX_MANIFEST:
            raise NotRecovered(f"{where}: larger than a manifest ({MAX_MANIFEST} bytes)")
        raw = jsonfile.read(where, NotRecovered, "recording manifest")
    except RecursionError:
        raise NotRecovered(f"{where}: nested too deeply for a manifest") from None
    except OSError as exc:
        raise NotRecovered(f"{where}: {exc.strerror or exc}") from None
    if not isinstance(raw, dict) or raw.get("schema") != MANIFEST_SCHEMA or raw.get("version") != MANIFEST_VERSION:
        raise NotRecovered(f"{where}: not a {MANIFEST_SCHEMA} manifest of version {MANIFEST_VERSION}")
    bag, launcher, info, topics = (raw.get(k) for k in ("bag", "launcher", "info", "topics"))
    if not (isinstance(bag, str) and bag.startswith("/") and "\0" not in bag and Path(bag).name):
        raise NotRecovered(f"{where}: 'bag' is not an absolute folder path")
    if not (isinstance(launcher, list) and len(launcher) == 2 and type(launcher[0]) is int
            and (launcher[1] is None or type(launcher[1]) is int)):
        raise NotRecovered(f"{where}: 'launcher' is not [pid, start]")
    if not isinstance(info, dict):
        raise NotRecovered(f"{where}: 'info' is not an object")
    if not isinstance(topics, list) or not topics:
        raise NotRecovered(f"{where}: 'topics' is not a list of topics")
    out, names = [], set()
    for t in topics:
        if not (isinstance(t, list) and len(t) == 4 and all(isinstance(x, str) for x in t)):
            raise NotRecovered(f"{where}: a topic is not [key, name, type, kind]")
        key, name, msgtype, kind = t
        want = DIAGNOSTIC_ARRAY if key == DIAG_KEY else STRING
        if not name.startswith("/") or name in names or msgtype != want or kind not in KINDS:
            raise NotRecovered(f"{where}: topic {one_line(name)!s:.80} is not one a bag of the graph holds")
        names.add(name)
        out.append(Tapped(key, name, msgtype, kind))
    return Path(bag), launcher, info, out

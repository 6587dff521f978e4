"""Recording at the writers: each node appends every message it sends to a file of its own (a
spool); after the run the launcher merges the spools into the rosbag2 bag (``homeo_record.record``).

Why: a recorder subscribed to every topic costs the launcher 0.6-0.8 ms of DDS receiving a tick
(docs/GRAPH.md), which on two busy cores lands on the tick; an append costs the writer a few
microseconds. The price: a message is stamped when it is sent, not when it is received, and what
strangers send on the graph's topics is not kept (the graph refuses it: docs/SECURITY.md). The one
topic the graph reads from outside, ``homeo/human_input``, is still taken by the launcher's tap.

A spool is this program's scratch file, deleted once merged; its records, little-endian::

    int64 stamp (ns since the epoch) | uint8 kind | uint16 topic length | uint32 payload length
    | topic (UTF-8, absolute) | payload

kind 0: the text of a ``std_msgs/String`` (the merge CDR-encodes it with ``rosbags``), kind 1: a
message already CDR-serialised. One record is one ``write()`` on a file opened ``O_APPEND``, so a node
that dies has lost nothing it sent; a torn last record (a disk that filled) is dropped by the reader.
"""

from __future__ import annotations

import os
import struct
import time
from dataclasses import dataclass
from pathlib import Path

HEADER = struct.Struct("<qBHI")
TEXT, CDR = 0, 1
SUFFIX = ".spool"


@dataclass(frozen=True)
class Record:
    stamp_ns: int
    topic: str
    kind: int
    payload: bytes


class SpoolWriter:
    """Appends records to ``DIR/WHO-PID.spool`` (a restarted node gets a file of its own)."""

    def __init__(self, directory: str | os.PathLike, who: str):
        self.path = Path(directory) / f"{who}-{os.getpid()}{SUFFIX}"
        self._fd: int | None = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_APPEND | os.O_CLOEXEC, 0o600)
        self.count = 0

    def text(self, topic: str, text: str, stamp_ns: int | None = None) -> None:
        self.add(TEXT, topic, text.encode("utf-8"), stamp_ns)

    def cdr(self, topic: str, raw: bytes, stamp_ns: int | None = None) -> None:
        self.add(CDR, topic, bytes(raw), stamp_ns)

    def add(self, kind: int, topic: str, payload: bytes, stamp_ns: int | None = None) -> None:
        if self._fd is None:
            return
        t = topic.encode("utf-8")
        rec = HEADER.pack(time.time_ns() if stamp_ns is None else stamp_ns, kind, len(t), len(payload)) + t + payload
        view = memoryview(rec)
        while view:  # a regular file takes it whole; a short write (disk nearly full) goes on
            view = view[os.write(self._fd, view):]
        self.count += 1

    def close(self) -> None:
        if self._fd is not None:
            fd, self._fd = self._fd, None
            os.close(fd)


def read_spool(path: str | os.PathLike) -> tuple[list[Record], int]:
    """The records of one spool, and how many bytes of a torn tail were dropped."""
    data = Path(path).read_bytes()
    out, i = [], 0
    while i + HEADER.size <= len(data):
        stamp, kind, tl, pl = HEADER.unpack_from(data, i)
        end = i + HEADER.size + tl + pl
        if end > len(data) or kind not in (TEXT, CDR):
            break
        j = i + HEADER.size
        out.append(Record(stamp, data[j:j + tl].decode("utf-8", "replace"), kind, data[j + tl:end]))
        i = end
    return out, len(data) - i


def read_spools(directory: str | os.PathLike) -> tuple[list[Record], int]:
    """Every record of the spools in ``directory`` in the order they were sent (by stamp; a tie in
    one file keeps that file's order), and the torn bytes dropped in all."""
    rows, torn = [], 0
    for n, p in enumerate(sorted(Path(directory).glob("*" + SUFFIX))):
        recs, t = read_spool(p)
        torn += t
        rows += [(r.stamp_ns, n, k, r) for k, r in enumerate(recs)]
    rows.sort(key=lambda x: x[:3])
    return [r for *_, r in rows], torn

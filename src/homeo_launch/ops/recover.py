"""``homeo-launch recover``: the bags a launcher killed outright was recording.

``--record`` at the writers (``record.WriterBag``) keeps every message in a spool folder,
``DATA_DIR/.homeo-record-*``, and merges it into the bag when the run ends, Ctrl-C included. A
launcher killed outright (SIGKILL, the OOM killer, a power cut) never merges. This does, later,
from the folder alone: its manifest (``bag.json``, written before any node appended) names the bag,
the run's settings and the topics. The folder is deleted once its bag is written; a folder whose
launcher still runs is a live recording and is left alone; an existing bag is never overwritten.
"""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

from homeo_decision import jsonfile
from homeo_msgs_py import data_dir
from homeo_msgs_py.cli_args import UserError
from homeo_msgs_py.schemas import one_line

from ..record import MANIFEST, MANIFEST_SCHEMA, MANIFEST_VERSION, SPOOL_PREFIX, merge_spools, proc_start
from ..tap import DIAG_KEY, DIAGNOSTIC_ARRAY, STRING, Tapped

KINDS = ("state", "event", "diagnostics")
MAX_MANIFEST = 16 << 20  # bytes: the run's settings and its scenario's text, with room to spare


class NotRecovered(Exception):
    """A spool folder that is not turned into a bag (``str()``: why, on one line)."""


def add_parser(sub) -> None:
    r = sub.add_parser("recover", help="write the bags of recordings whose launcher was killed outright "
                                       "(the spool folders DATA_DIR/.homeo-record-*)")
    r.add_argument("--data-dir", metavar="DIR", default=data_dir.DEFAULT,
                   help=f"the --data-dir of the recorded runs (default {data_dir.DEFAULT})")


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


def recover_folder(folder: Path) -> str:
    """Write the bag of one spool folder and delete the folder: what was done, on one line; a
    one-line ``NotRecovered`` otherwise (the folder is then left as it was)."""
    bag, (pid, start), info, topics = read_manifest(folder)
    if start is not None and proc_start(pid) == start:
        raise NotRecovered(f"{folder}: still recording (its launcher, process {pid}, is running)")
    if bag.exists() or bag.is_symlink():
        raise NotRecovered(f"{folder}: its bag {bag} already exists (a bag is never overwritten); "
                           "move that away and run recover again")
    if not bag.parent.is_dir():
        raise NotRecovered(f"{folder}: the folder of its bag, {bag.parent}, is gone")
    from rosbags.rosbag2 import WriterError

    try:
        n = merge_spools(folder, bag, info, topics)
    except BaseException as exc:  # Ctrl-C too: no half bag left to block a second try
        shutil.rmtree(bag, ignore_errors=True)
        if isinstance(exc, (OSError, WriterError)):  # a full disk, a folder not writable
            raise NotRecovered(f"{folder}: writing {bag}: {getattr(exc, 'strerror', None) or exc}") from None
        raise
    shutil.rmtree(folder, ignore_errors=True)
    return f"{bag}: {n} messages (from {folder.name})"


def cmd_recover(a) -> int:
    """One line per spool folder of ``--data-dir``: exit 0 if every one became a bag (or there were
    none), 1 if one was left."""
    d = Path(a.data_dir)
    if not d.is_dir():
        raise UserError(f"--data-dir {one_line(a.data_dir)}: not a directory")
    folders = sorted(p for p in d.glob(SPOOL_PREFIX + "*") if p.is_dir() and not p.is_symlink())
    if not folders:
        print(f"nothing to recover in {d}")
        return 0
    left = 0
    for f in folders:
        try:
            print("recovered " + recover_folder(f))
        except NotRecovered as exc:
            print(f"not recovered: {one_line(str(exc))}", file=sys.stderr)
            left += 1
    return 1 if left else 0

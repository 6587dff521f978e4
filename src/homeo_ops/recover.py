"""``homeo-launch recover``: the bags a launcher killed outright was recording.

``--record`` at the writers (``record.WriterBag``) keeps every message in a spool folder,
``DATA_DIR/.homeo-record-*``, and merges it into the bag when the run ends, Ctrl-C included. A
launcher killed outright (SIGKILL, the OOM killer, a power cut) never merges. This does, later,
from the folder alone: its manifest (``bag.json``, written before any node appended) names the bag,
the run's settings and the topics. The folder is deleted once its bag is written; a folder whose
launcher still runs is a live recording and is left alone; an existing bag is never overwritten.
"""

from __future__ import annotations

import sys
from pathlib import Path

from homeo_msgs_py import data_dir
from homeo_msgs_py.cli_args import UserError
from homeo_msgs_py.schemas import one_line

from homeo_record.record import SPOOL_PREFIX, NotRecovered, proc_start, read_manifest, spools_to_bag

def add_parser(sub) -> None:
    r = sub.add_parser("recover", help="write the bags of recordings whose launcher was killed outright "
                                       "(the spool folders DATA_DIR/.homeo-record-*)")
    r.add_argument("--data-dir", metavar="DIR", default=data_dir.DEFAULT,
                   help=f"the --data-dir of the recorded runs (default {data_dir.DEFAULT})")


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
    n = spools_to_bag(folder, bag, info, topics)
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

"""Reading and writing the project's JSON files (Q-tables, intention models) with one-line errors."""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path


def write_atomic(path: str | Path, obj, error: type[Exception], what: str) -> None:
    """Write ``obj`` as compact JSON atomically, so a crash never leaves half a file: a temporary
    file in the same folder, flushed to disk, then renamed over the target (POSIX rename is atomic).
    The temporary file is removed on any failure, Ctrl-C included; only SIGKILL between its creation
    and the rename can leave one behind (``*.tmp``, never under the target's name)."""
    p = Path(path)
    tmp = None
    try:
        data = json.dumps(obj, separators=(",", ":"), allow_nan=False)
        if p.is_dir():
            raise IsADirectoryError(21, "is a directory")
        p.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=p.parent, prefix=f"{p.name}.", suffix=".tmp")
        with os.fdopen(fd, "w") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())  # the data is on disk before the name points at it
        os.replace(tmp, p)
        tmp = None
        _fsync_dir(p.parent)  # and the rename itself survives a power loss
    except (OSError, ValueError) as exc:  # ValueError: a NaN, which JSON cannot hold
        raise error(f"cannot write {what} {p}: {getattr(exc, 'strerror', None) or exc}") from None
    finally:
        if tmp is not None:  # a failed write leaves nothing behind
            try:
                os.unlink(tmp)
            except OSError:
                pass


def _fsync_dir(d: Path) -> None:
    try:
        fd = os.open(d, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def shipped(path: str | Path, folder: Path) -> Path:
    """``path``, or for a bare name that is no file here (``example``, ``field_user.json``) the file
    ``NAME.json`` or ``NAME`` shipped with the package in ``folder``."""
    p = Path(path)
    if not p.exists() and p.parent == Path(".") and str(p):
        p = next((q for q in (folder / f"{p}.json", folder / p.name) if q.is_file()), p)
    return p


def read(path: str | Path, error: type[Exception], what: str, limit: int = 64 << 20):
    """The parsed JSON of ``path``; a missing, unreadable, too large or corrupt file (a folder too) raises
    ``error`` in one line."""
    p = Path(path)
    try:
        if p.stat().st_size > limit:
            raise error(f"{what} {p}: larger than {limit} bytes")
        return json.loads(p.read_text())
    except FileNotFoundError:
        raise error(f"{what} file not found: {p}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise error(f"cannot read {what} {p}: {getattr(exc, 'strerror', None) or exc}") from None
    except json.JSONDecodeError as exc:
        raise error(f"{p}: corrupt {what} (not JSON: {exc.msg} at line {exc.lineno})") from None

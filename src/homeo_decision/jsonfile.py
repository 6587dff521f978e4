"""Reading and writing the project's JSON files (Q-tables, intention models) with one-line errors."""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path


def write_atomic(path: str | Path, obj, error: type[Exception], what: str) -> None:
    """Write ``obj`` as compact JSON atomically, so a crash never leaves half a file."""
    p = Path(path)
    data = json.dumps(obj, separators=(",", ":"))
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=p.parent, prefix=p.name, suffix=".tmp")
        with os.fdopen(fd, "w") as fh:
            fh.write(data)
        os.replace(tmp, p)
    except OSError as exc:
        raise error(f"cannot write {what} {p}: {exc.strerror or exc}") from None


def read(path: str | Path, error: type[Exception], what: str):
    """The parsed JSON of ``path``; a missing, unreadable or corrupt file raises ``error``."""
    p = Path(path)
    try:
        return json.loads(p.read_text())
    except FileNotFoundError:
        raise error(f"{what} file not found: {p}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise error(f"cannot read {what} {p}: {exc}") from None
    except json.JSONDecodeError as exc:
        raise error(f"{p}: corrupt {what} (not JSON: {exc.msg} at line {exc.lineno})") from None

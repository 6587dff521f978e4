"""What /proc says of a process (proc(5)), read in one place."""

from __future__ import annotations

from pathlib import Path


def stat_fields(pid: int | str = "self") -> list[str] | None:
    """The fields of ``/proc/PID/stat`` from field 3 (state) on, or None if there is no such process.
    They follow the last ')': the command name before it may hold spaces and parentheses."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rpartition(")")[2].split()
    except (OSError, ValueError):
        return None


def rss_mb(pid: int | str = "self") -> float | None:
    """Resident memory of a process in MiB (``/proc/PID/status``' VmRSS), or None."""
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    except (OSError, ValueError):
        pass
    return None

"""Counting rejected messages and what a node reports on /diagnostics (no rclpy here)."""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

OK, WARN, ERROR = 0, 1, 2  # diagnostic_msgs/DiagnosticStatus levels
RECENT = 8


@dataclass
class RejectLog:
    """Per-topic counts of dropped messages and the last reason, for logs and /diagnostics."""

    node: str
    counts: Counter = field(default_factory=Counter)
    last: dict = field(default_factory=dict)
    recent: dict = field(default_factory=dict)  # topic -> the last few distinct reasons
    notes: Counter = field(default_factory=Counter)  # other counted events, e.g. missed ticks
    changed: bool = False

    def reject(self, topic: str, reason: str) -> str:
        """Count one dropped message; returns the reason as kept (cut: a sender's text must not
        flood /diagnostics or the log)."""
        from .schemas import short

        reason = short(reason)
        self.counts[topic] += 1
        self.last[topic] = reason
        r = self.recent.setdefault(topic, [])
        if reason not in r:
            r.append(reason)
            del r[:-RECENT]
        self.changed = True
        return reason

    def note(self, what: str, n: int = 1) -> None:
        self.notes[what] += n
        self.changed = True

    @property
    def total(self) -> int:
        return sum(self.counts.values())

    def status(self) -> dict:
        """Level, message and key/values of one DiagnosticStatus."""
        values = {f"rejected {t}": str(n) for t, n in sorted(self.counts.items())}
        values.update({f"last reason {t}": r for t, r in sorted(self.last.items())})
        values.update({f"recent reasons {t}": " | ".join(r) for t, r in sorted(self.recent.items())})
        values.update({k: str(v) for k, v in sorted(self.notes.items())})
        if self.total:
            msg = f"dropped {self.total} bad message{'s' if self.total != 1 else ''}"
        else:
            msg = "ok"
        extra = [f"{k}: {v}" for k, v in sorted(self.notes.items()) if v]
        if extra:
            msg += "; " + ", ".join(extra)
        level = WARN if self.total or extra else OK
        return {"name": f"{self.node}: inputs", "hardware_id": self.node, "level": level, "message": msg,
                "values": values}

"""Q-tables on disk: versioned JSON that records the scenario it was learned in.

A table loads into a scenario when both agree on motivations, intentions and relations,
and every object they share has the same states and actions. Objects the file lacks
(an object added to the scenario) keep their initial values; objects the scenario lacks
are dropped and reported (Section 3.2.2: adding or removing an object leaves the others).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from . import jsonfile
from .objectq import ObjectQ
from .scenario import RELATIONS

SCHEMA = "homeo-qtable"
VERSION = 1


class QTableError(ValueError):
    """A Q-table file that cannot be loaded; the message says why."""


@dataclass
class LoadReport:
    loaded: list = field(default_factory=list)
    new: list = field(default_factory=list)  # in the scenario, not in the file: initial values
    dropped: list = field(default_factory=list)  # in the file, not in the scenario


def _state_labels(q: ObjectQ, o: int) -> list[str]:
    sc = q.sc
    out = []
    for m in sc.internal_states:
        for it in sc.intention_names:
            for rel in RELATIONS:
                for s in sc.c.obj_state_labels[o]:
                    out.append(f"{m}|{it}|{rel}|{s}")
    return out


def to_dict(q: ObjectQ, meta: dict | None = None) -> dict:
    sc = q.sc
    tables = {}
    for o, name in enumerate(sc.object_names):
        acts = [sc.actions[a].name for a in sc.c.obj_actions[o]]
        tables[name] = {lbl: dict(zip(acts, row)) for lbl, row in zip(_state_labels(q, o), q.q[o])}
    return {
        "schema": SCHEMA,
        "version": VERSION,
        "scenario": {"name": sc.name, "fingerprint": sc.fingerprint(), "layout": sc.q_layout()},
        "meta": dict(meta or {}),
        "tables": tables,
    }


def save(q: ObjectQ, path: str | Path, meta: dict | None = None) -> None:
    """Write atomically, so a crash never leaves half a table."""
    jsonfile.write_atomic(path, to_dict(q, meta), QTableError, "Q-table")


def load(q: ObjectQ, path: str | Path) -> LoadReport:
    return from_dict(q, jsonfile.read(path, QTableError, "Q-table"), str(path))


def from_dict(q: ObjectQ, raw, where: str = "<memory>") -> LoadReport:
    sc = q.sc
    if not isinstance(raw, dict) or raw.get("schema") != SCHEMA:
        raise QTableError(f"{where}: not a Q-table file (schema must be {SCHEMA!r})")
    if raw.get("version") != VERSION:
        raise QTableError(f"{where}: Q-table version {raw.get('version')!r} is not supported (this program reads {VERSION})")
    try:
        layout = raw["scenario"]["layout"]
        tables = raw["tables"]
        if not isinstance(tables, dict) or not isinstance(layout.get("objects"), dict):
            raise TypeError
    except (KeyError, TypeError, AttributeError):
        raise QTableError(f"{where}: corrupt Q-table (missing scenario layout or tables)") from None
    mine = sc.q_layout()
    learned_in = raw["scenario"].get("name", "?")
    for key in ("motivations", "intentions", "relations"):
        if layout.get(key) != mine[key]:
            raise QTableError(
                f"{where}: learned in an incompatible scenario ({learned_in!r}): {key} differ "
                f"(table: {layout.get(key)}, scenario: {mine[key]})")
    report = LoadReport()
    staged = {}
    for name, lay in layout["objects"].items():
        if name not in mine["objects"]:
            report.dropped.append(name)
            continue
        if lay != mine["objects"][name]:
            raise QTableError(
                f"{where}: learned in an incompatible scenario ({learned_in!r}): object {name!r} has other "
                f"states/actions (table: {lay}, scenario: {mine['objects'][name]})")
        o = sc.object_names.index(name)
        acts = lay["actions"]
        tab = tables.get(name)
        if not isinstance(tab, dict):
            raise QTableError(f"{where}: corrupt Q-table (no values for object {name!r})")
        rows = []
        for lbl in _state_labels(q, o):
            row = tab.get(lbl)
            if not isinstance(row, dict) or set(row) != set(acts):
                raise QTableError(f"{where}: corrupt Q-table ({name} state {lbl!r} missing or with wrong actions)")
            vals = [row[a] for a in acts]
            if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in vals):
                raise QTableError(f"{where}: corrupt Q-table ({name} state {lbl!r} has a non-numeric value)")
            rows.append([float(v) for v in vals])
        staged[o] = rows
    for o, rows in staged.items():
        q.q[o] = rows
        report.loaded.append(sc.object_names[o])
    report.new = [n for n in sc.object_names if n not in layout["objects"]]
    return report

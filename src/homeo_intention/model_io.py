"""Intention models on disk, with the Q-table's rules (``homeo_decision.qtable_io``).

Versioned JSON that records the layout it was learned with (intentions and the three alphabets);
a file loads only into a scenario with the same layout. The file holds the CPDs and every count
seen, so learning continues where it stopped.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from homeo_decision import jsonfile
from homeo_decision.scenario import OBS_CHANNELS

from .em import Params

SCHEMA = "homeo-intention-model"
VERSION = 1


class IntentionModelError(ValueError):
    """An intention-model file that cannot be loaded; the message says why."""


def layout(model) -> dict:
    return {"intentions": list(model.names)} | model.sc.observations.layout()


def to_dict(model, meta: dict | None = None) -> dict:
    coder = model.coder
    counts = []  # sparse: [intention or null, gesture, movement, keyword, count]
    for k in range(model.K):
        for c in np.flatnonzero(model.labelled[k]):
            counts.append([model.names[k], *coder.symbols(int(c)).values(), float(model.labelled[k, c])])
    for c in np.flatnonzero(model.unlabelled):
        counts.append([None, *coder.symbols(int(c)).values(), float(model.unlabelled[c])])
    return {
        "schema": SCHEMA,
        "version": VERSION,
        "scenario": {"name": model.sc.name, "layout": layout(model)},
        "meta": dict(meta or {}) | {"threshold": model.threshold, "prior_strength": model.strength,
                                    "em_runs": model.em_runs},
        "cpds": model.cpds(),
        "counts": counts,
    }


def save(model, path: str | Path, meta: dict | None = None) -> None:
    """Write atomically, so a crash never leaves half a model."""
    jsonfile.write_atomic(path, to_dict(model, meta), IntentionModelError, "intention model")


def load(model, path: str | Path) -> None:
    from_dict(model, jsonfile.read(path, IntentionModelError, "intention model"), str(path))


def _dist(values, what: str, where: str) -> np.ndarray:
    if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v >= 0 for v in values):
        raise IntentionModelError(f"{where}: corrupt intention model ({what} has a value that is not a probability)")
    a = np.array(values, float)
    if abs(a.sum() - 1.0) > 1e-6:
        raise IntentionModelError(f"{where}: corrupt intention model ({what} sums to {a.sum():g}, not 1)")
    return a


def from_dict(model, raw, where: str = "<memory>") -> None:
    """Load ``raw`` into ``model``: all checks first, then the CPDs and counts replace the model's."""
    if not isinstance(raw, dict) or raw.get("schema") != SCHEMA:
        raise IntentionModelError(f"{where}: not an intention-model file (schema must be {SCHEMA!r})")
    if raw.get("version") != VERSION:
        raise IntentionModelError(f"{where}: intention-model version {raw.get('version')!r} is not supported "
                                  f"(this program reads {VERSION})")
    try:
        theirs = raw["scenario"]["layout"]
        cpds, counts = raw["cpds"], raw["counts"]
        learned_in = raw["scenario"].get("name", "?")
        if not isinstance(theirs, dict) or not isinstance(cpds, dict) or not isinstance(counts, list):
            raise TypeError
    except (KeyError, TypeError, AttributeError):
        raise IntentionModelError(f"{where}: corrupt intention model (missing layout, cpds or counts)") from None
    mine = layout(model)
    for key in mine:
        if theirs.get(key) != mine[key]:
            raise IntentionModelError(f"{where}: learned in an incompatible scenario ({learned_in!r}): {key} differ "
                                      f"(file: {theirs.get(key)}, scenario: {mine[key]})")
    names = model.names
    try:
        pi = _dist([cpds["intention"][n] for n in names], "P(intention)", where)
        rho = [cpds["revealed"][n] for n in names]
        if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and 0.0 <= v <= 1.0 for v in rho):
            raise IntentionModelError(f"{where}: corrupt intention model (P(revealed | intention) is not a probability)")
        likes = []
        for ch, alpha in zip(OBS_CHANNELS, model.coder.alphabets):
            likes.append(np.array([_dist([cpds[ch][n][s] for s in alpha], f"P({ch} | {n})", where) for n in names]))
    except (KeyError, TypeError):
        raise IntentionModelError(f"{where}: corrupt intention model (a CPD misses an intention or symbol)") from None
    labelled = np.zeros_like(model.labelled)
    unlabelled = np.zeros_like(model.unlabelled)
    for row in counts:
        if not isinstance(row, list) or len(row) != 5:
            raise IntentionModelError(f"{where}: corrupt intention model (a count row is not [intention, gesture, "
                                      "movement, keyword, count])")
        it, n = row[0], row[4]
        if not isinstance(n, (int, float)) or isinstance(n, bool) or not math.isfinite(n) or n < 0:
            raise IntentionModelError(f"{where}: corrupt intention model (count {n!r} in {row})")
        try:
            c = model.coder.cell(dict(zip(OBS_CHANNELS, row[1:4])))
        except ValueError as exc:
            raise IntentionModelError(f"{where}: corrupt intention model ({exc})") from None
        if it is None:
            unlabelled[c] += n
        elif it in names:
            labelled[names.index(it), c] += n
        else:
            raise IntentionModelError(f"{where}: corrupt intention model (unknown intention {it!r} in the counts)")
    model.labelled, model.unlabelled = labelled, unlabelled
    model.em_runs = int(raw.get("meta", {}).get("em_runs", 0) or 0)
    model.set_params(Params(pi, likes, np.array(rho, float)))

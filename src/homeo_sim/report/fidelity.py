"""The fidelity score: how close a run set comes to the published numbers and statements.

Two parts, both from the scenario's ``reference`` block (no thesis name lives in this code):

- ``table_score``: per published number (Table 4.5), whether it lies inside our 95% interval
  and how far our mean is from it in half-widths of that interval. The half-width used for the
  distance is at least ``HALF_WIDTH_FLOOR`` of the published value, so that a very narrow
  interval (e.g. HSR over 20 seeds) does not turn a small miss into a huge distance.
- ``criteria_score``: per statement of the text about the sweeps, its criterion (data in
  ``reference.criteria``, written from the text) and whether our numbers meet it.

``M`` is always ``{label: aggregate}`` with labels ``base`` (the default run) and
``<sweep>=<value>`` (e.g. ``xi=0.0``, ``pseudo=False``); an aggregate is the layout of
``stats.aggregate`` (``{"HSR": {"mean", "ci95", "per_seed"}, "CDA": {drive: ...}, ...}``).
"""

from __future__ import annotations

from typing import Mapping, Sequence

HALF_WIDTH_FLOOR = 0.05  # the distance's half-width is at least this fraction of the published value


# -- Table 4.5 ----------------------------------------------------------------------------

def reference_numbers(metrics: Mapping) -> list[tuple[str, float]]:
    """The published numbers as ``(path, value)``, paths like ``HSR`` or ``CDA.<drive>``, in table order."""
    out = []
    for k in ("HSR", "RSR"):
        if k in metrics:
            out.append((k, float(metrics[k])))
    for k in ("CDA", "CEDA"):
        for dn, v in metrics.get(k, {}).items():
            out.append((f"{k}.{dn}", float(v)))
    return out


def value_at(agg: Mapping, path: str) -> dict:
    """The summary ``{"mean", "ci95", ...}`` of ``path`` (``HSR``, ``CDA.all``) in an aggregate."""
    x = agg
    for p in path.split("."):
        x = x[p]
    return x


def table_score(agg: Mapping, metrics: Mapping, floor: float = HALF_WIDTH_FLOOR) -> list[dict]:
    """Per published number: ours, the interval, inside or not, and the distance in half-widths."""
    rows = []
    for path, ref in reference_numbers(metrics):
        d = value_at(agg, path)
        lo, hi = d["ci95"]
        half = max((hi - lo) / 2, floor * abs(ref))
        dist = abs(d["mean"] - ref) / half if half > 0 else (0.0 if d["mean"] == ref else float("inf"))
        rows.append({"metric": path, "thesis": ref, "mean": d["mean"], "ci95": [lo, hi],
                     "inside": bool(lo <= ref <= hi), "distance": dist})
    return rows


# -- statements about the sweeps -----------------------------------------------------------

def _mean(M, label, path):
    return value_at(M[label], path)["mean"]


def _overlap(a: dict, b: dict) -> bool:
    return a["ci95"][0] <= b["ci95"][1] and b["ci95"][0] <= a["ci95"][1]


def _sweep(M, c, sweeps, base_value):
    """``[(value, label)]`` of the criterion's sweep that were run, plus the default run at its value."""
    name = c["sweep"]
    pts = [(float(v), f"{name}={v}") for v in sweeps.get(name, ()) if f"{name}={v}" in M]
    if base_value is not None and name in base_value and "base" in M:
        pts.append((float(base_value[name]), "base"))
    return sorted(pts)


def _product_mean(agg, paths) -> float:
    """Mean over seeds of the per-seed product of the metrics (e.g. HSR x RSR)."""
    seeds = [value_at(agg, p)["per_seed"] for p in paths]
    prods = [1.0] * len(seeds[0])
    for s in seeds:
        prods = [a * float(b) for a, b in zip(prods, s)]
    return sum(prods) / len(prods)


def _check(c: Mapping, M: Mapping, sweeps: Mapping, base_value: Mapping | None) -> tuple[str, bool]:
    """Our number(s) for one criterion, as a text, and whether the criterion holds."""
    k = c["kind"]
    if k == "below":
        x = _mean(M, c["at"], c["metric"])
        return f"{c['metric']}({c['at']}) = {x:.3f}", x < c["value"]
    if k == "near":
        x = _mean(M, c["at"], c["metric"])
        return f"{c['metric']}({c['at']}) = {x:.3f}", abs(x - c["value"]) <= c["tol"]
    if k == "change_between":
        a, b = _mean(M, c["from"], c["metric"]), _mean(M, c["to"], c["metric"])
        return (f"{c['metric']}: {a:.3f} ({c['from']}) -> {b:.3f} ({c['to']}), {b - a:+.3f}",
                c["lo"] < b - a < c["hi"])
    if k == "decreases":
        parts, ok = [], True
        for p in c["metrics"]:
            a, b = _mean(M, c["from"], p), _mean(M, c["to"], p)
            parts.append(f"{p}: {a:.2f} -> {b:.2f}")
            ok = ok and b < a
        return f"{'; '.join(parts)} ({c['from']} -> {c['to']})", ok
    if k == "same":
        a, b = value_at(M[c["a"]], c["metric"]), value_at(M[c["b"]], c["metric"])
        return (f"{c['metric']}: {a['mean']:.3f} ({c['a']}), {b['mean']:.3f} ({c['b']}); 95% intervals "
                f"{'overlap' if _overlap(a, b) else 'apart'}", _overlap(a, b))
    pts = _sweep(M, c, sweeps, base_value)
    if k == "first_below":
        below = [v for v, lab in pts if _mean(M, lab, c["metric"]) < c["level"]]
        return (f"{c['metric']} < {c['level']:g} from {c['sweep']} {below[0]:g} on" if below else
                f"{c['metric']} never below {c['level']:g}"), bool(below) and abs(below[0] - c["value"]) <= c["tol"] + 1e-9
    if k == "linear":
        lo, mid, hi = (f"{c['sweep']}={v}" for v in c["points"])
        a, m, b = _mean(M, lo, c["metric"]), _mean(M, mid, c["metric"]), _mean(M, hi, c["metric"])
        return (f"{c['metric']}({mid}) = {m:.3f}; the straight line from {a:.3f} to {b:.3f} gives {(a + b) / 2:.3f}",
                abs(m - (a + b) / 2) <= c["tol"])
    if k == "best_near":
        best_v, _ = max(((v, _product_mean(M[lab], c["product"])) for v, lab in pts), key=lambda p: p[1])
        return (f"{' x '.join(c['product'])} is highest at {c['sweep']} {best_v:g}",
                abs(best_v - c["value"]) <= c["tol"] + 1e-9)
    raise ValueError(f"unknown criterion kind {k!r}")


def criteria_score(criteria: Sequence[Mapping], M: Mapping, sweeps: Mapping,
                   base_value: Mapping | None = None) -> list[dict]:
    """Each criterion with our numbers and whether it holds. ``sweeps``: the values run per sweep;
    ``base_value``: the default run's value of each swept parameter (it joins that sweep)."""
    out = []
    for c in criteria:
        ours, ok = _check(c, M, sweeps, base_value)
        out.append({"id": c["id"], "figure": c["figure"], "thesis": c["says"], "criterion": c["criterion"],
                    "ours": ours, "agrees": bool(ok)})
    return out


def needed_labels(criteria: Sequence[Mapping], sweeps: Mapping) -> set[str]:
    """The run labels the criteria read (so that a search runs only those)."""
    out = {"base"}
    for c in criteria:
        out |= {c[k] for k in ("at", "from", "to", "a", "b") if k in c}
        if "points" in c:
            out |= {f"{c['sweep']}={v}" for v in c["points"]}
        elif "sweep" in c:
            out |= {f"{c['sweep']}={v}" for v in sweeps.get(c["sweep"], ())}
    return out


# -- the whole score -----------------------------------------------------------------------

def fidelity(reference, M: Mapping, sweeps: Mapping, base_value: Mapping | None = None) -> dict:
    """Table score, criteria score and a one-line summary (``reference``: a ``ReferenceSpec`` or None)."""
    if reference is None:
        return {"table": [], "statements": [], "summary": "no reference block: no fidelity score"}
    table = table_score(M["base"], reference.metrics)
    crit = criteria_score(reference.criteria or (), M, sweeps, base_value)
    inside = sum(r["inside"] for r in table)
    met = sum(s["agrees"] for s in crit)
    return {"table": table, "table_inside": inside, "table_total": len(table),
            "table_mean_distance": sum(r["distance"] for r in table) / len(table) if table else 0.0,
            "statements": crit, "statements_met": met, "statements_total": len(crit),
            "half_width_floor": HALF_WIDTH_FLOOR,
            "summary": f"Table 4.5: {inside}/{len(table)} inside CI; statements: {met}/{len(crit)}"}

"""The fidelity score: how close a run set comes to the published numbers and statements.

From the scenario's ``reference`` block (no thesis name lives in this code), two parts that do not
reward noise (issue 25):

- the published numbers (Table 4.5): per number, the relative error of our mean over all the seeds
  run, (ours - published) / published; summed up as the mean absolute error and the largest one.
  More seeds only make our mean firmer. (``table_score`` also keeps, per number, whether it lies
  inside our 95% interval and the distance in half-widths, the score of issue 15: with more seeds
  the interval narrows and fewer numbers are "inside", so that count is not the score any more.)
- the statements of the text about its figures (``criteria_score``: each statement's criterion, data
  in ``reference.criteria``, written from the text; a criterion may read part of a run, ``label_aggregates``):
  each is checked on every one of the disjoint
  sets of ``SET_SIZE`` consecutive seeds (``seed_sets``), the size the criteria were written for;
  per statement, the share of sets on which it holds, and per set, how many statements hold.

``GOALS`` are the targets of issue 25 for both parts; ``fidelity`` says which are met.

``M`` is always ``{label: aggregate}`` with labels ``base`` (the default run) and
``<sweep>=<value>`` (e.g. ``xi=0.0``, ``pseudo=False``); an aggregate is the layout of
``stats.aggregate`` (``{"HSR": {"mean", "ci95", "per_seed"}, "CDA": {drive: ...}, ...}``).
"""

from __future__ import annotations

import math
from typing import Mapping, Sequence

from ..stats import aggregate, describe

HALF_WIDTH_FLOOR = 0.05  # the distance's half-width is at least this fraction of the published value
SET_SIZE = 20  # the statements are checked on disjoint sets of this many seeds
# issue 25's targets: the mean absolute relative error, every number's, the headline rates' (HSR, RSR), and
# the statements that hold on each set (a fraction of them, 0.9 = 9 of 10)
GOALS = {"mean_error": 0.08, "each_error": 0.15, "headline_error": 0.05, "headline": ("HSR", "RSR"),
         "statements_per_set": 0.9}


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


def relative_errors(agg: Mapping, metrics: Mapping) -> list[dict]:
    """Per published number: our mean and its relative error (ours - published) / published."""
    rows = []
    for path, ref in reference_numbers(metrics):
        mean = value_at(agg, path)["mean"]
        err = (mean - ref) / ref if ref else (0.0 if mean == ref else float("inf"))
        rows.append({"metric": path, "thesis": ref, "mean": mean, "error": err})
    return rows


def error_summary(rows: Sequence[Mapping], goals: Mapping = GOALS) -> dict:
    """The mean absolute relative error, the largest (and which), the headline rates' errors, the goals met."""
    if not rows:
        return {}
    errs = {r["metric"]: r["error"] for r in rows}
    worst = max(errs, key=lambda k: abs(errs[k]))
    mae = sum(abs(e) for e in errs.values()) / len(errs)
    head = {k: errs[k] for k in goals["headline"] if k in errs}
    return {"mean_abs_error": mae, "largest": worst, "largest_error": errs[worst], "headline_errors": head,
            "within_each": sum(abs(e) <= goals["each_error"] for e in errs.values()), "of": len(errs),
            "goals": {"mean_error": mae <= goals["mean_error"],
                      "each_error": all(abs(e) <= goals["each_error"] for e in errs.values()),
                      "headline_error": all(abs(e) <= goals["headline_error"] for e in head.values())}}


def seed_sets(seeds: Sequence[int], size: int = SET_SIZE) -> list[list[int]]:
    """Disjoint sets of ``size`` consecutive seeds (seeds past the last full set are in none); fewer
    seeds than ``size``: one set of all of them."""
    seeds = list(seeds)
    if len(seeds) < size:
        return [seeds] if seeds else []
    return [seeds[i:i + size] for i in range(0, len(seeds) - size + 1, size)]


def set_aggregates(runs: Mapping[str, Sequence[Mapping]], drive_names: Sequence[str],
                   labels: set[str] | None = None) -> list[dict]:
    """``M`` per seed set (``seed_sets``), from ``runs``: ``{label: per-seed metrics}``, every label over the
    same seeds in the same order; only the ``labels`` given (default: all; staged ones: ``label_aggregates``)."""
    # by position, not by seed: the runs of one label are in seed order, so the sets are the same
    n_seeds = len(next(iter(runs.values()), ()))
    return [label_aggregates(runs, drive_names, labels, pos) for pos in seed_sets(range(n_seeds))]


# -- stages: the metrics over part of a run (issue 31) ------------------------------------------------
# ``<run>@<a>-<b>``: the run's metrics over its iterations a+1..b (``<run>@<b>``: 1..b), with the unserved
# intentions (``misses``) and insecure iterations (``insecure``) counted; ``<run>@curve``: the metrics after each
# tick of ``metrics.stage_marks``, the mean over the seeds (the curves of Figs 4.1-4.2). Both come from the
# running sums a run keeps after those ticks (its per-seed ``stages``).

def _window(stages: Sequence[Mapping], st: str, names: Sequence[str]) -> dict:
    lo, _, hi = st.rpartition("-")
    at = {x["n"]: x for x in stages}
    lo, hi = int(lo or 0), int(hi)
    if hi not in at or (lo and lo not in at) or lo >= hi:
        raise ValueError(f"a run of {max(at, default=0)} iterations has no stage {st}")
    b = at[hi]
    a = at[lo] if lo else {k: [0.0] * len(v) if isinstance(v, list) else 0 for k, v in b.items()}
    n, ints, sat = b["n"] - a["n"], b["intentions"] - a["intentions"], b["satisfied"] - a["satisfied"]
    out = {"HSR": sat / ints if ints else math.nan, "RSR": (b["secure"] - a["secure"]) / n, "misses": ints - sat,
           "insecure": n - b["secure"] + a["secure"]}
    for k, key in (("CDA", "sum"), ("CEDA", "excess")):
        per = [(y - x) / n for x, y in zip(a[key], b[key])]
        out[k] = dict(zip(names, per), all=sum(per) / len(per))
    return out


def label_aggregates(runs: Mapping[str, Sequence[Mapping]], drive_names: Sequence[str],
                     labels: set[str] | None = None, pos: Sequence[int] | None = None) -> dict:
    """``M`` of the ``labels`` (default: the runs') over the seeds at positions ``pos`` (default: all); a staged
    label's run needs its per-seed ``stages``."""
    out = {}
    for lab in sorted(runs if labels is None else labels):
        run, _, st = lab.partition("@")
        if run not in runs:
            continue
        per = [runs[run][i] for i in (range(len(runs[run])) if pos is None else pos)]
        if not st:
            out[lab] = aggregate(per, drive_names)
            continue
        marks = [x["n"] for x in per[0]["stages"]] if st == "curve" else None
        try:
            wins = [[_window(m["stages"], str(t), drive_names) for t in marks] if marks else
                    _window(m["stages"], st, drive_names) for m in per]
        except ValueError:  # a shorter run: a criterion that reads this part says it was not measured
            continue
        if marks:  # the mean curve: per tick, the mean over the seeds (HSR over those with an intention by then)
            mean = lambda xs: (lambda v: sum(v) / len(v) if v else math.nan)([x for x in xs if x == x])  # noqa: E731
            out[lab] = {"t": marks} | {p: [mean([value_at(w[i], p) for w in wins]) for i in range(len(marks))]
                                       for p in _paths(drive_names)}
        else:
            out[lab] = aggregate(wins, drive_names) | {k: describe([w[k] for w in wins]) for k in ("misses", "insecure")}
    return out


def _paths(names: Sequence[str]) -> list[str]:
    return ["HSR", "RSR"] + [f"{k}.{d}" for k in ("CDA", "CEDA") for d in (*names, "all")]


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
    pts = _sweep(M, c, sweeps, base_value) if "sweep" in c else ()
    if k == "first_below":
        below = [v for v, lab in pts if _mean(M, lab, c["metric"]) < c["level"]]
        return (f"{c['metric']} < {c['level']:g} from {c['sweep']} {below[0]:g} on" if below else
                f"{c['metric']} never below {c['level']:g}"), bool(below) and abs(below[0] - c["value"]) <= c["tol"] + 1e-9
    if k == "best_near":
        best_v, _ = max(((v, _product_mean(M[lab], c["product"])) for v, lab in pts), key=lambda p: p[1])
        return (f"{' x '.join(c['product'])} is highest at {c['sweep']} {best_v:g}",
                abs(best_v - c["value"]) <= c["tol"] + 1e-9)
    if k == "lowest_at":
        best_v = min(pts, key=lambda p: sum(_mean(M, p[1], m) for m in c["metrics"]))[0]
        return f"the sum of {', '.join(c['metrics'])} is lowest at {c['sweep']} {best_v:g}", abs(best_v - c["value"]) <= c["tol"] + 1e-9
    if k == "sweep_corr":
        r = _pearson([v for v, _ in pts], [_mean(M, lab, c["metric"]) for _, lab in pts])
        return f"Pearson r of {c['metric']} and {c['sweep']} over the sweep: {r:+.3f}", c["lo"] <= r <= c["hi"]
    return _check_more(c, M, sweeps, base_value)


def _pearson(x: Sequence[float], y: Sequence[float]) -> float:
    mx, my = sum(x) / len(x), sum(y) / len(y)
    sxy = sum((a - mx) * (b - my) for a, b in zip(x, y))
    sxx, syy = sum((a - mx) ** 2 for a in x), sum((b - my) ** 2 for b in y)
    return sxy / math.sqrt(sxx * syy) if sxx and syy else math.nan


def _check_more(c: Mapping, M: Mapping, sweeps: Mapping, base_value: Mapping | None) -> tuple[str, bool]:
    """The kinds of issue 31: parts of a run (staged labels), ratios, significance, curves, several at once."""
    k, m = c["kind"], c.get("metric")
    if k == "all_of":
        parts = [_check(p, M, sweeps, base_value) for p in c["parts"]]
        return "; ".join(t for t, _ in parts), all(ok for _, ok in parts)
    if k == "within":
        xs = [_mean(M, c["at"], p) for p in c["metrics"]]
        return (f"{', '.join(f'{p} {x:.3f}' for p, x in zip(c['metrics'], xs))} ({c['at']}); in [{c['lo']:g}, {c['hi']:g}]",
                all(c["lo"] <= x <= c["hi"] for x in xs))
    if k == "ratio":
        a, b = _mean(M, c["from"], m), _mean(M, c["to"], m)
        q = b / a if a else math.inf
        return f"{m}: {b:.3f} ({c['to']}) / {a:.3f} ({c['from']}) = {q:.3f}", c["lo"] <= q <= c["hi"]
    if k == "gain_larger":
        g, g2 = (_mean(M, c[t], m) - _mean(M, c[f], m) for f, t in (("from", "to"), ("than_from", "than_to")))
        return f"{m}: {g:+.3f} ({c['from']} -> {c['to']}) against {g2:+.3f} ({c['than_from']} -> {c['than_to']})", g > g2
    if k == "mostly_from":
        drops = {d: _mean(M, c["from"], f"{m}.{d}") - _mean(M, c["to"], f"{m}.{d}") for d in M[c["from"]][m] if d != "all"}
        total = sum(drops.values())
        share = drops[c["drive"]] / total if total > 0 else math.nan
        return (f"{m} all falls by {total / len(drops):.3f} ({c['from']} -> {c['to']}), {c['drive']}'s share {share:.2f}",
                share > c["value"])
    if k == "apart":
        pairs = [(p, lo, hi) for p in c["metrics"] for lo in c["lower"] for hi in c["higher"]]
        bad = [f"{p} {lo} vs {hi}" for p, lo, hi in pairs if not value_at(M[lo], p)["ci95"][1] < value_at(M[hi], p)["ci95"][0]]
        return f"95% intervals apart in {len(pairs) - len(bad)} of {len(pairs)}" + (f" (not: {', '.join(bad)})" if bad else ""), not bad
    cur = M[f"{c['at']}@curve"]
    idx = [i for i, t in enumerate(cur["t"]) if c["span"][0] <= t <= c["span"][1]]
    if k == "curve_corr":
        r = _pearson([cur[c["x"]][i] for i in idx], [cur[c["y"]][i] for i in idx])
        return f"Pearson r of {c['x']} and {c['y']} over iterations {c['span'][0]}-{c['span'][1]}: {r:+.3f}", c["lo"] <= r <= c["hi"]
    if k == "curve_min":
        i = min(idx, key=lambda j: cur[m][j])
        return (f"{m} lowest at iteration {cur['t'][i]}: {cur[m][i]:.3f}",
                cur[m][i] < c["value"] and c["when"][0] <= cur["t"][i] <= c["when"][1])
    raise ValueError(f"unknown criterion kind {k!r}")


def criteria_score(criteria: Sequence[Mapping], M: Mapping, sweeps: Mapping,
                   base_value: Mapping | None = None) -> list[dict]:
    """Each criterion with our numbers and whether it holds. ``sweeps``: the values run per sweep;
    ``base_value``: the default run's value of each swept parameter (it joins that sweep)."""
    out = []
    for c in criteria:
        try:
            ours, ok = _check(c, M, sweeps, base_value)
        except KeyError as exc:
            ours, ok = f"not measured: these runs have no {exc.args[0]}", False
        out.append({"id": c["id"], "figure": c["figure"], "thesis": c["says"], "criterion": c["criterion"],
                    "ours": ours, "agrees": bool(ok)})
    return out


def needed_labels(criteria: Sequence[Mapping], sweeps: Mapping) -> set[str]:
    """The labels the criteria read (staged ones included; ``<run>@...`` needs the run ``<run>``)."""
    out = {"base"}
    for c in criteria:
        out |= {c[k] for k in ("at", "from", "to", "a", "b", "than_from", "than_to") if k in c}
        out |= {lab for k in ("lower", "higher") for lab in c.get(k, ())}
        if c["kind"].startswith("curve_"):
            out.add(f"{c['at']}@curve")
        if "sweep" in c:
            out |= {f"{c['sweep']}={v}" for v in sweeps.get(c["sweep"], ())}
        out |= needed_labels(c.get("parts", ()), sweeps) - {"base"}
    return out


def statement_shares(criteria: Sequence[Mapping], M_sets: Sequence[Mapping], sweeps: Mapping,
                     base_value: Mapping | None = None) -> dict:
    """Each criterion on every seed set: per set the statements met, per statement the sets it holds on."""
    return _shares(criteria, [criteria_score(criteria, M, sweeps, base_value) for M in M_sets])


def _shares(criteria: Sequence[Mapping], per_set: Sequence[Sequence[Mapping]]) -> dict:
    """``statement_shares`` from the ``criteria_score`` rows of each set."""
    shares = []
    for i, c in enumerate(criteria):
        held = [rows[i]["agrees"] for rows in per_set]
        shares.append({"id": c["id"], "held": sum(held), "of": len(held), "per_set": held,
                       "share": sum(held) / len(held) if held else 0.0})
    return {"met_per_set": [sum(r["agrees"] for r in rows) for rows in per_set], "shares": shares}


def statements_goal_met(met_per_set: Sequence[int], n_statements: int, goals: Mapping = GOALS) -> bool:
    """Issue 25's goal for the statements: on every seed set at least that share of them hold (no set: not met)."""
    return bool(met_per_set) and min(met_per_set) >= goals["statements_per_set"] * n_statements


def format_goals(goals: Mapping[str, bool], not_met: str = "not met") -> str:
    """The goals as ``mean error met, each error not met, ...`` (``not_met``: how a missed goal reads)."""
    return ", ".join(f"{k.replace('_', ' ')} {'met' if ok else not_met}" for k, ok in goals.items())


# -- the whole score -----------------------------------------------------------------------

def fidelity(reference, M: Mapping, sweeps: Mapping, base_value: Mapping | None = None,
             M_sets: Sequence[Mapping] | None = None, n_seeds: int | None = None, set_size: int = SET_SIZE,
             goals: Mapping = GOALS) -> dict:
    """The score and a one-line summary (``reference``: a ``ReferenceSpec`` or None). ``M`` aggregates
    all ``n_seeds`` seeds (the published numbers); ``M_sets`` the same runs per seed set (``seed_sets``;
    default: ``M`` alone, one set) for the statements."""
    if reference is None:
        return {"table": [], "statements": [], "summary": "no reference block: no fidelity score"}
    table = table_score(M["base"], reference.metrics)
    for row, e in zip(table, relative_errors(M["base"], reference.metrics)):
        row["error"] = e["error"]
    errors = error_summary(table, goals)
    criteria = reference.criteria or ()
    crit = criteria_score(criteria, M, sweeps, base_value)
    # without seed sets, ``M`` is the one set: its rows are ``crit``, already scored
    sets = (_shares(criteria, [crit]) if M_sets is None
            else statement_shares(criteria, M_sets, sweeps, base_value))
    for row, share in zip(crit, sets["shares"]):
        row.update(held=share["held"], of=share["of"], per_set=share["per_set"])
    inside = sum(r["inside"] for r in table)
    met = sum(s["agrees"] for s in crit)
    per_set, n_st = sets["met_per_set"], len(crit)
    out = {"table": table, "table_inside": inside, "table_total": len(table),
           "table_mean_distance": sum(r["distance"] for r in table) / len(table) if table else 0.0,
           "statements": crit, "statements_met": met, "statements_total": len(crit),
           "half_width_floor": HALF_WIDTH_FLOOR, "errors": errors, "seeds": n_seeds, "set_size": set_size,
           "statements_per_set": per_set}
    parts = []
    if errors:
        head = ", ".join(f"{k} {100 * v:+.1f}%" for k, v in errors["headline_errors"].items())
        parts.append(f"Table 4.5{f' over {n_seeds} seeds' if n_seeds else ''}: mean |error| "
                     f"{100 * errors['mean_abs_error']:.1f}%, largest {errors['largest'].replace('.', ' ')} "
                     f"{100 * errors['largest_error']:+.0f}%, {errors['within_each']}/{errors['of']} within "
                     f"{100 * goals['each_error']:g}%" + (f", {head}" if head else ""))
    if n_st:
        size = len((M_sets or [M])[0]["base"]["HSR"]["per_seed"])
        parts.append(f"statements per {size}-seed set: {', '.join(map(str, per_set))} of {n_st}")
        out["goals"] = dict(errors.get("goals", {}), statements_per_set=statements_goal_met(per_set, n_st, goals))
    else:
        out["goals"] = dict(errors.get("goals", {}))
    out["summary"] = "; ".join(parts) if parts else "no published numbers or statements"
    return out

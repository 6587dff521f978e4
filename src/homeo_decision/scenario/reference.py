"""The scenario's optional ``reference`` block: published numbers to set beside ours.

    "reference": {
      "source": "where the numbers come from",
      "metrics": {"HSR": 0.82, "RSR": 0.9, "CDA": {"<drive>": 1.7, "all": 32.5}, "CEDA": {...}},
      "statements": {                       # what the source says about the sweeps
        "<sweep>": ["..."],                 # per sweep (SWEEP_NAMES: xi, pseudo, dod), quoted in the report
        "rsr_at_xi0_below": 0.4,            # RSR(xi 0) below this
        "hsr_at_dod0": 0.6,                 # HSR(DoD 0) about this (within 0.1)
        "rsr_below_half_from_dod": 0.5,     # RSR < 0.5 from about this DoD on (within 0.1)
        "best_dod": 0.2,                    # HSR x RSR is best near this DoD (within 0.1)
        "pseudo_unaffected_drive": "<drive>"  # CDA of this drive does not move with the pseudo update
      },
      "criteria": [                         # each statement of the text and how we test it
        {"id": "...", "figure": "4.3", "says": "the text", "criterion": "the test in words",
         "kind": "below", "at": "xi=0.0", "metric": "RSR", "value": 0.4}, ...
      ]
    }

Criterion kinds (labels: ``base`` or ``<sweep>=<value>``; metrics: ``HSR``, ``RSR``, ``CDA.<drive>``,
``CEDA.all``, ...): ``below`` (at, metric, value), ``near`` (at, metric, value, tol),
``change_between`` (from, to, metric, lo, hi: lo < to - from < hi), ``decreases`` (from, to,
metrics), ``same`` (a, b, metric: the 95% intervals overlap), ``first_below`` (sweep, metric, level,
value, tol), ``best_near`` (sweep, product: [metrics], value, tol), and issue 31's (``CRITERION_FIELDS``). ``homeo_sim.report.fidelity`` evaluates them.

Everything but ``source`` is optional; a scenario without the block gets no comparison.
"""

from __future__ import annotations

from typing import Any, Sequence

from homeo_msgs_py.learning import DOD, XI
from homeo_msgs_py.params import checked

from .model import ReferenceSpec, ScenarioError

# the thesis's sweeps (homeo_sim.sweep runs them), each over one learning parameter and named by it;
# the pseudo update's by a short name. Statements, criteria and result labels (``xi=0.0``) use these
XI_SWEEP, DOD_SWEEP, PSEUDO_SWEEP = XI.name, DOD.name, "pseudo"
SWEEP_NAMES = (XI_SWEEP, DOD_SWEEP, PSEUDO_SWEEP)
STATEMENT_TEXTS = (XI_SWEEP, PSEUDO_SWEEP, DOD_SWEEP)
STATEMENT_NUMBERS = ("rsr_at_xi0_below", "hsr_at_dod0", "rsr_below_half_from_dod", "best_dod")
STATEMENT_DRIVES = ("pseudo_unaffected_drive",)


def parse_reference(block: Any, drive_names: Sequence[str], where: str) -> ReferenceSpec:
    ctx = f"{where}: reference"
    if not isinstance(block, dict) or set(block) - {"source", "metrics", "statements", "criteria", "description"}:
        raise ScenarioError(f"{ctx} must be an object with 'source' and optional 'metrics', 'statements', 'criteria', "
                            "'description'")
    if not isinstance(block.get("source"), str) or not block["source"]:
        raise ScenarioError(f"{ctx}.source must name where the numbers come from")
    metrics = block.get("metrics", {})
    if not isinstance(metrics, dict) or set(metrics) - {"HSR", "RSR", "CDA", "CEDA"}:
        raise ScenarioError(f"{ctx}.metrics must be an object with (some of) HSR, RSR, CDA, CEDA")
    for k in ("HSR", "RSR"):
        if k in metrics:
            checked(metrics[k], f"{ctx}.metrics.{k}: a rate", 0, 1, error=ScenarioError)
    for k in ("CDA", "CEDA"):
        per = metrics.get(k, {})
        if not isinstance(per, dict):
            raise ScenarioError(f"{ctx}.metrics.{k} must be an object of drive (or 'all'): value")
        for dn, v in per.items():
            if dn != "all" and dn not in drive_names:
                raise ScenarioError(f"{ctx}.metrics.{k}: unknown drive {dn!r}; known: {', '.join(drive_names)}, all")
            checked(v, f"{ctx}.metrics.{k}.{dn}", 0, 100, error=ScenarioError)
    statements = block.get("statements")
    if statements is not None:
        known = set(STATEMENT_TEXTS + STATEMENT_NUMBERS + STATEMENT_DRIVES)
        if not isinstance(statements, dict) or set(statements) != known:
            raise ScenarioError(f"{ctx}.statements must be an object with exactly {sorted(known)}")
        for k in STATEMENT_TEXTS:
            if not isinstance(statements[k], list) or not all(isinstance(s, str) for s in statements[k]):
                raise ScenarioError(f"{ctx}.statements.{k} must be a list of texts")
        for k in STATEMENT_NUMBERS:
            checked(statements[k], f"{ctx}.statements.{k}", 0, 1, error=ScenarioError)
        for k in STATEMENT_DRIVES:
            if statements[k] not in drive_names:
                raise ScenarioError(f"{ctx}.statements.{k}: unknown drive {statements[k]!r}; known: {', '.join(drive_names)}")
        statements = dict(statements)
    criteria = block.get("criteria")
    if criteria is not None:
        if not isinstance(criteria, list):
            raise ScenarioError(f"{ctx}.criteria must be a list of criteria")
        ids = [c.get("id") if isinstance(c, dict) else None for c in criteria]
        if len(set(ids)) != len(ids):
            raise ScenarioError(f"{ctx}.criteria: ids must be distinct")
        criteria = tuple(_criterion(c, drive_names, f"{ctx}.criteria[{i}]") for i, c in enumerate(criteria))
    return ReferenceSpec(block["source"], dict(metrics), statements, criteria)


# the fields of each criterion kind besides id, figure, says, criterion, kind (see the module docstring)
CRITERION_FIELDS = {
    "below": ("at", "metric", "value"),
    "near": ("at", "metric", "value", "tol"),
    "change_between": ("from", "to", "metric", "lo", "hi"),
    "decreases": ("from", "to", "metrics"),
    "same": ("a", "b", "metric"),
    "first_below": ("sweep", "metric", "level", "value", "tol"),
    "best_near": ("sweep", "product", "value", "tol"),
    # issue 31 (homeo_sim.report.fidelity): labels may name part of a run, <label>@<a>-<b>
    "lowest_at": ("sweep", "metrics", "value", "tol"),  # the sum of the metrics is lowest near value
    "sweep_corr": ("sweep", "metric", "lo", "hi"),  # lo <= Pearson r(metric, swept value) <= hi
    "within": ("at", "metrics", "lo", "hi"),  # each metric in [lo, hi]
    "ratio": ("from", "to", "metric", "lo", "hi"),  # lo <= to / from <= hi
    "gain_larger": ("from", "to", "than_from", "than_to", "metric"),  # to - from > than_to - than_from
    "mostly_from": ("from", "to", "metric", "drive", "value"),  # the drive's share of CDA/CEDA's fall > value
    "apart": ("lower", "higher", "metrics"),  # each lower label's 95% interval below each higher one's
    "curve_corr": ("at", "x", "y", "span", "lo", "hi"),  # Pearson r of two mean curves over [from, to]
    "curve_min": ("at", "metric", "span", "value", "when"),  # a curve's lowest point in span: < value, inside when
    "all_of": ("parts",),  # each part holds (a part: a criterion without id, figure, says, criterion)
}
_SWEEPS = SWEEP_NAMES
_LABEL_FIELDS, _METRIC_FIELDS = ("at", "from", "to", "a", "b", "than_from", "than_to"), ("metric", "x", "y")
_TEXT_FIELDS = ("id", "figure", "says", "criterion")


def _metric_ok(m: Any, drive_names: Sequence[str]) -> bool:
    if m in ("HSR", "RSR", "misses", "insecure"):
        return True
    if not isinstance(m, str) or m.count(".") != 1:
        return False
    k, dn = m.split(".")
    return k in ("CDA", "CEDA") and (dn == "all" or dn in drive_names)


def _label_ok(lab: Any) -> bool:
    if not isinstance(lab, str):
        return False
    lab, at, st = lab.partition("@")
    a, dash, b = st.partition("-")
    if at and not (st == "curve" or (b if dash else a).isdigit() and (not dash or a.isdigit() and int(a) < int(b))):
        return False
    return lab == "base" or ("=" in lab and lab.split("=", 1)[0] in _SWEEPS)


def _criterion(c: Any, drive_names: Sequence[str], ctx: str, text: tuple = _TEXT_FIELDS) -> dict:
    if not isinstance(c, dict):
        raise ScenarioError(f"{ctx} must be an object")
    kind = c.get("kind")
    if kind not in CRITERION_FIELDS:
        raise ScenarioError(f"{ctx}.kind = {kind!r} must be one of {sorted(CRITERION_FIELDS)}")
    need = text + ("kind",) + CRITERION_FIELDS[kind]
    if set(c) != set(need):
        raise ScenarioError(f"{ctx}: a {kind!r} criterion has exactly the fields {list(need)}")
    for k in text:
        if not isinstance(c[k], str) or not c[k]:
            raise ScenarioError(f"{ctx}.{k} must be a non-empty text")
    if kind == "all_of":
        if not isinstance(c["parts"], list) or not c["parts"]:
            raise ScenarioError(f"{ctx}.parts must be a non-empty list of criteria")
        return dict(c, parts=[_criterion(p, drive_names, f"{ctx}.parts[{i}]", ()) for i, p in enumerate(c["parts"])])
    for k in ("metrics", "product", "lower", "higher"):
        if k in c and (not isinstance(c[k], list) or not c[k]):
            raise ScenarioError(f"{ctx}.{k} must be a non-empty list of {'labels' if k in ('lower', 'higher') else 'metrics'}")
    labels = [(k, c[k]) for k in _LABEL_FIELDS if k in c] + [(k, x) for k in ("lower", "higher") for x in c.get(k, [])]
    for k, lab in labels:
        if not _label_ok(lab):
            raise ScenarioError(f"{ctx}.{k}: label {lab!r} must be 'base' or '<sweep>=<value>' with sweep in {list(_SWEEPS)}, "
                                "optionally with '@<to>', '@<from>-<to>' or '@curve'")
    metrics = [c[k] for k in _METRIC_FIELDS if k in c and kind != "mostly_from"] + list(c.get("metrics", [])) \
        + list(c.get("product", [])) + ([f"{c['metric']}.{c['drive']}"] if kind == "mostly_from" else [])
    for m in metrics:
        if not _metric_ok(m, drive_names):
            raise ScenarioError(f"{ctx}: metric {m!r} must be HSR, RSR or CDA/CEDA.<drive or all> "
                                f"(drives: {', '.join(drive_names)})")
    if "sweep" in c and c["sweep"] not in _SWEEPS:
        raise ScenarioError(f"{ctx}.sweep = {c['sweep']!r} must be one of {list(_SWEEPS)}")
    for k in ("value", "tol", "level", "lo", "hi"):
        if k in c:
            checked(c[k], f"{ctx}.{k}", error=ScenarioError)
    for k in ("span", "when"):
        if k in c and (not isinstance(c[k], list) or len(c[k]) != 2
                       or not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in c[k])):
            raise ScenarioError(f"{ctx}.{k} must be two iterations [from, to]")
    return dict(c)

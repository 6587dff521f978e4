"""The scenario's optional ``reference`` block: published numbers to set beside ours.

    "reference": {
      "source": "where the numbers come from",
      "metrics": {"HSR": 0.82, "RSR": 0.9, "CDA": {"<drive>": 1.7, "all": 32.5}, "CEDA": {...}},
      "statements": {                       # what the source says about the sweeps
        "xi": ["..."], "pseudo": ["..."], "dod": ["..."],    # quoted in the report
        "rsr_at_xi0_below": 0.4,            # RSR(xi 0) below this
        "hsr_at_dod0": 0.6,                 # HSR(DoD 0) about this (within 0.1)
        "rsr_below_half_from_dod": 0.5,     # RSR < 0.5 from about this DoD on (within 0.1)
        "best_dod": 0.2,                    # HSR x RSR is best near this DoD (within 0.1)
        "pseudo_unaffected_drive": "<drive>"  # CDA of this drive does not move with the pseudo update
      }
    }

Everything but ``source`` is optional; a scenario without the block gets no comparison.
"""

from __future__ import annotations

from typing import Any, Sequence

from .model import ReferenceSpec, ScenarioError

STATEMENT_TEXTS = ("xi", "pseudo", "dod")
STATEMENT_NUMBERS = ("rsr_at_xi0_below", "hsr_at_dod0", "rsr_below_half_from_dod", "best_dod")
STATEMENT_DRIVES = ("pseudo_unaffected_drive",)


def _number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def parse_reference(block: Any, drive_names: Sequence[str], where: str) -> ReferenceSpec:
    ctx = f"{where}: reference"
    if not isinstance(block, dict) or set(block) - {"source", "metrics", "statements", "description"}:
        raise ScenarioError(f"{ctx} must be an object with 'source' and optional 'metrics', 'statements', 'description'")
    if not isinstance(block.get("source"), str) or not block["source"]:
        raise ScenarioError(f"{ctx}.source must name where the numbers come from")
    metrics = block.get("metrics", {})
    if not isinstance(metrics, dict) or set(metrics) - {"HSR", "RSR", "CDA", "CEDA"}:
        raise ScenarioError(f"{ctx}.metrics must be an object with (some of) HSR, RSR, CDA, CEDA")
    for k in ("HSR", "RSR"):
        if k in metrics and (not _number(metrics[k]) or not 0 <= metrics[k] <= 1):
            raise ScenarioError(f"{ctx}.metrics.{k} = {metrics[k]!r} must be a rate in [0, 1]")
    for k in ("CDA", "CEDA"):
        per = metrics.get(k, {})
        if not isinstance(per, dict):
            raise ScenarioError(f"{ctx}.metrics.{k} must be an object of drive (or 'all'): value")
        for dn, v in per.items():
            if dn != "all" and dn not in drive_names:
                raise ScenarioError(f"{ctx}.metrics.{k}: unknown drive {dn!r}; known: {', '.join(drive_names)}, all")
            if not _number(v) or not 0 <= v <= 100:
                raise ScenarioError(f"{ctx}.metrics.{k}.{dn} = {v!r} must be a number in [0, 100]")
    statements = block.get("statements")
    if statements is not None:
        known = set(STATEMENT_TEXTS + STATEMENT_NUMBERS + STATEMENT_DRIVES)
        if not isinstance(statements, dict) or set(statements) != known:
            raise ScenarioError(f"{ctx}.statements must be an object with exactly {sorted(known)}")
        for k in STATEMENT_TEXTS:
            if not isinstance(statements[k], list) or not all(isinstance(s, str) for s in statements[k]):
                raise ScenarioError(f"{ctx}.statements.{k} must be a list of texts")
        for k in STATEMENT_NUMBERS:
            if not _number(statements[k]) or not 0 <= statements[k] <= 1:
                raise ScenarioError(f"{ctx}.statements.{k} = {statements[k]!r} must be a number in [0, 1]")
        for k in STATEMENT_DRIVES:
            if statements[k] not in drive_names:
                raise ScenarioError(f"{ctx}.statements.{k}: unknown drive {statements[k]!r}; known: {', '.join(drive_names)}")
        statements = dict(statements)
    return ReferenceSpec(block["source"], dict(metrics), statements)

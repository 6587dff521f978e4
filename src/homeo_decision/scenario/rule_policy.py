"""The scenario's optional ``rule_policy`` block: the fixed-priority rules of the rule baseline.

    "rule_policy": {
      "description": "...",
      "rules": [                                   # tried in order; the first that picks wins
        {"name": "battery", "drive": "D",          # fires when drive D >= "at" (default: D's threshold)
         "at": 50,
         "keep_while": {"when": {...}, "above": 10},  # hysteresis: or while the world is so and D > above
         "when": {...},                            # world condition the rule needs besides its drive
         "actions": [{"action": "A", "when": {...}}, ...]},  # first valid one whose "when" holds
        {"name": "serve", "serve": true},          # the first valid desired action of the intention
        {"name": "idle", "actions": [...]}         # no drive: fires whenever its "when" holds
      ]
    }

A rule that picks nothing falls through to the next; when no rule picks, the policy takes the
first valid action. ``homeo_decision.baselines.RulePolicy`` runs the rules.
"""

from __future__ import annotations

from typing import Any, Callable, Mapping, Sequence

from homeo_msgs_py.params import checked

from .model import DriveSpec, RuleCandidate, RuleSpec, ScenarioError

RULE_KEYS = {"name", "drive", "at", "keep_while", "when", "serve", "actions", "description"}


def parse_rule_policy(block: Any, drives: Sequence[DriveSpec], action_ids: Mapping[str, int],
                      check_cond: Callable[[Any, str], None], where: str) -> tuple:
    """Validate the block; returns a tuple of RuleSpec (``check_cond`` validates world conditions)."""
    ctx = f"{where}: rule_policy"
    if not isinstance(block, dict) or set(block) - {"rules", "description"}:
        raise ScenarioError(f"{ctx} must be an object with 'rules' (and an optional 'description')")
    rules = block.get("rules")
    if not isinstance(rules, list) or not rules:
        raise ScenarioError(f"{ctx}.rules must be a non-empty list of rules")
    dnames = [d.name for d in drives]
    out = []
    for i, r in enumerate(rules):
        rctx = f"rule_policy.rules[{i}]"
        if not isinstance(r, dict):
            raise ScenarioError(f"{where}: {rctx} must be an object")
        unknown = set(r) - RULE_KEYS
        if unknown:
            raise ScenarioError(f"{where}: {rctx} has unknown key(s) {sorted(unknown)}; known: {sorted(RULE_KEYS)}")
        name = r.get("name", f"rule{i}")
        if not isinstance(name, str):
            raise ScenarioError(f"{where}: {rctx}.name must be a string")
        rctx = f"rule_policy rule {name!r}"
        drive, at, keep_when, keep_above = None, 0.0, None, 0.0
        if "drive" in r:
            if r["drive"] not in dnames:
                raise ScenarioError(f"{where}: {rctx}: unknown drive {r['drive']!r}; known: {', '.join(dnames)}")
            drive = dnames.index(r["drive"])
            at = r.get("at", drives[drive].threshold)  # default: where the drive's motivation activates (Eq 3.2)
            checked(at, f"{where}: {rctx}.at", 0, 100, error=ScenarioError)
            if "keep_while" in r:
                kw = r["keep_while"]
                if not isinstance(kw, dict) or set(kw) - {"when", "above"} or "above" not in kw:
                    raise ScenarioError(f"{where}: {rctx}.keep_while must be an object with 'above' and an optional 'when'")
                checked(kw["above"], f"{where}: {rctx}.keep_while.above", 0, 100, error=ScenarioError)
                keep_when = dict(kw.get("when", {}))
                check_cond(keep_when, f"{rctx}.keep_while.when")
                keep_above = float(kw["above"])
        elif "at" in r or "keep_while" in r:
            raise ScenarioError(f"{where}: {rctx}: 'at' and 'keep_while' need a 'drive'")
        when = r.get("when", {})
        check_cond(when, f"{rctx}.when")
        serve = r.get("serve", False)
        if not isinstance(serve, bool):
            raise ScenarioError(f"{where}: {rctx}.serve must be true or false")
        cands = r.get("actions")
        if serve and cands is not None:
            raise ScenarioError(f"{where}: {rctx}: a 'serve' rule takes the intention's desired actions, not 'actions'")
        if not serve and (not isinstance(cands, list) or not cands):
            raise ScenarioError(f"{where}: {rctx} needs 'serve': true or a non-empty list 'actions'")
        candidates = []
        for j, c in enumerate(cands or []):
            cctx = f"{rctx}.actions[{j}]"
            if not isinstance(c, dict) or "action" not in c or set(c) - {"action", "when"}:
                raise ScenarioError(f"{where}: {cctx} must be an object with 'action' and an optional 'when'")
            if c["action"] not in action_ids:
                raise ScenarioError(f"{where}: {cctx}: unknown action {c['action']!r}")
            check_cond(c.get("when", {}), f"{cctx}.when")
            candidates.append(RuleCandidate(action_ids[c["action"]], dict(c.get("when", {}))))
        out.append(RuleSpec(name, drive, float(at), dict(when), keep_when, keep_above, serve, tuple(candidates)))
    return tuple(out)

"""Loading and validation of a scenario file; every malformed part is a one-line ScenarioError.

``load_scenario`` reads a JSON file (the shipped thesis scenario by default),
``scenario_from_dict`` validates a parsed one and hands it to ``compile.py``. The ``open`` block
(the choices the thesis leaves open) is declared and validated in ``open_choices.py``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping, Sequence

from homeo_msgs_py.learning import DOD, LEARNING, check_learning
from homeo_msgs_py.params import checked

from ..numeric import left_sum
from .compile import _compile
from .open_choices import Names, parse_open
from .model import (HUMAN_VARS, NONE_INTENTION, NULL_OBJECT, OBS_CHANNELS, PRESENCE, RELATIONS, DISTANCES, SCHEMA,
                    SCHEMA_VERSION, ActionSpec, DriveSpec, IntentionSpec, ObservationSpec, Scenario, ScenarioError)
from .reference import parse_reference
from .rule_policy import parse_rule_policy

SCHEDULE = "schedule"  # the learning block's alpha/tau phases (objectq.schedule_from)
DEFAULT_SCHEDULE = ({"from": 0, "alpha": 0.3, "tau": 4.0}, {"from": 1000, "alpha": 0.1, "tau": 2.0})
ANY_ACTION = "<action>"  # kept for importers: human_proposal_choice may name any action of the scenario


def load_scenario(path: str | Path | None = None, overrides: Mapping[str, Any] | None = None) -> Scenario:
    """Load, validate and compile a scenario file (the thesis scenario by default; a bare name such as
    ``workshop`` is a file shipped in ``homeo_decision/scenarios``)."""
    from homeo_decision.scenarios import SCENARIO_DIR, default_scenario_path

    from homeo_decision.jsonfile import read, shipped

    p = shipped(path if path is not None else default_scenario_path(), SCENARIO_DIR)  # a bare name: a shipped one
    raw = read(p, ScenarioError, "scenario")
    return scenario_from_dict(raw, source=str(p), overrides=overrides)


def scenario_from_dict(raw: Any, source: str = "<memory>", overrides: Mapping[str, Any] | None = None) -> Scenario:
    """Validate and compile a parsed scenario; any malformed part is a ScenarioError."""
    try:
        return _scenario_from_dict(raw, source, overrides)
    except ScenarioError:
        raise
    except (TypeError, AttributeError, KeyError, ValueError, IndexError) as exc:
        # a value of the wrong JSON type somewhere the specific checks do not look
        raise ScenarioError(f"{source}: malformed scenario ({type(exc).__name__}: {exc})") from None


def _scenario_from_dict(raw: Any, source: str, overrides: Mapping[str, Any] | None) -> Scenario:
    where = source
    if not isinstance(raw, dict):
        raise ScenarioError(f"{where}: a scenario must be a JSON object")
    if raw.get("schema") != SCHEMA:
        raise ScenarioError(f"{where}: 'schema' must be {SCHEMA!r}")
    if raw.get("version") != SCHEMA_VERSION:
        raise ScenarioError(f"{where}: unsupported scenario version {raw.get('version')!r} (this program reads {SCHEMA_VERSION})")

    def need(obj, key, typ, ctx):
        if key not in obj:
            raise ScenarioError(f"{where}: {ctx} is missing {key!r}")
        val = obj[key]
        if not isinstance(val, typ) or isinstance(val, bool) and typ is not bool:
            raise ScenarioError(f"{where}: {ctx}.{key} has the wrong type ({type(val).__name__})")
        return val

    # drives
    drives = []
    for i, d in enumerate(need(raw, "drives", list, "scenario")):
        ctx = f"drives[{i}]"
        if not isinstance(d, dict):
            raise ScenarioError(f"{where}: {ctx} must be an object")
        name = need(d, "name", str, ctx)
        thr = float(need(d, "threshold", (int, float), ctx))
        rate = float(need(d, "rate", (int, float), ctx))
        if not 0 <= thr <= 100:
            raise ScenarioError(f"{where}: {ctx} ({name}) threshold {thr} is outside [0, 100]")
        src = d.get("source", "internal")
        if src not in ("internal", "body"):
            raise ScenarioError(f"{where}: {ctx} ({name}) source must be 'internal' or 'body'")
        drives.append(DriveSpec(name, need(d, "motivation", str, ctx), thr, rate, src))
    if not drives:
        raise ScenarioError(f"{where}: a scenario needs at least one drive")
    _unique([d.name for d in drives], "drive", where)
    _unique([d.motivation for d in drives], "motivation", where)
    dnames = [d.name for d in drives]
    motiv = [d.motivation for d in drives]
    serving_name = raw.get("serving_drive", dnames[0])
    if serving_name not in dnames:
        raise ScenarioError(f"{where}: serving_drive {serving_name!r} is not a declared drive")

    locations = tuple(need(raw, "locations", list, "scenario"))
    _unique(locations, "location", where)
    human = need(raw, "human", dict, "scenario")
    hloc = need(human, "location", str, "human")
    if hloc not in locations:
        raise ScenarioError(f"{where}: human.location {hloc!r} is not one of the locations {list(locations)}")
    rest = raw.get("resting_place")
    if rest is not None and rest not in locations:
        raise ScenarioError(f"{where}: resting_place {rest!r} is not one of the locations")

    objects: dict[str, dict] = {}
    for oname, o in need(raw, "objects", dict, "scenario").items():
        ctx = f"objects.{oname}"
        if oname in (NULL_OBJECT, "human", "robot", "intention"):
            raise ScenarioError(f"{where}: {ctx}: {oname!r} is a reserved name")
        if not isinstance(o, dict):
            raise ScenarioError(f"{where}: {ctx} must be an object")
        loc = o.get("location")
        if loc is not None and loc not in locations:
            raise ScenarioError(f"{where}: {ctx}.location {loc!r} is not one of the locations")
        variables = o.get("variables", {})
        if not isinstance(variables, dict):
            raise ScenarioError(f"{where}: {ctx}.variables must be an object")
        for var, vals in variables.items():
            if var == "distance":
                raise ScenarioError(f"{where}: {ctx}: 'distance' is derived from the location, do not declare it")
            if not isinstance(vals, list) or len(vals) < 1 or not all(isinstance(v, str) for v in vals):
                raise ScenarioError(f"{where}: {ctx}.variables.{var} must be a non-empty list of names")
            _unique(vals, f"value of {oname}.{var}", where)
        if loc is None and not variables:
            raise ScenarioError(f"{where}: {ctx} has neither a location nor variables: it has no state")
        on_leave = o.get("on_leave", {})
        for var, val in on_leave.items():
            if var not in variables or val not in variables[var]:
                raise ScenarioError(f"{where}: {ctx}.on_leave sets {var}={val!r}, not a value of that object")
        objects[oname] = {"location": loc, "variables": {k: list(v) for k, v in variables.items()}, "on_leave": dict(on_leave)}

    intentions = []
    for i, it in enumerate(need(raw, "intentions", list, "scenario")):
        ctx = f"intentions[{i}]"
        name = need(it, "name", str, ctx)
        if name == NONE_INTENTION:
            raise ScenarioError(f"{where}: {ctx}: 'none' is reserved for 'no intention'")
        desired = need(it, "desired", list, ctx)
        if not desired:
            raise ScenarioError(f"{where}: {ctx} ({name}) needs at least one desired action")
        intentions.append(IntentionSpec(name, tuple(desired), dict(it.get("reasonable", {}))))
    _unique([i.name for i in intentions], "intention", where)

    # variables (needed to validate conditions)
    # the relation is a base variable (a robot senses it); presence is derived from it (model.py)
    base_vars = ["robot.location", "human.relation", "intention"]
    base_values = [list(locations), list(RELATIONS), [NONE_INTENTION] + [i.name for i in intentions]]
    for oname, o in objects.items():
        for var, vals in o["variables"].items():
            base_vars.append(f"{oname}.{var}")
            base_values.append(list(vals))
    derived = {"human.presence": list(PRESENCE)}
    for oname, o in objects.items():
        if o["location"] is not None:
            derived[f"{oname}.distance"] = list(DISTANCES)
    all_vars = dict(zip(base_vars, base_values)) | derived

    def check_cond(cond, ctx):
        if not isinstance(cond, dict):
            raise ScenarioError(f"{where}: {ctx} must be an object of variable: [values]")
        for var, vals in cond.items():
            if var not in all_vars:
                raise ScenarioError(f"{where}: {ctx} refers to unknown variable {var!r}; known: {', '.join(sorted(all_vars))}")
            if not isinstance(vals, list) or not vals:
                raise ScenarioError(f"{where}: {ctx}.{var} must be a non-empty list of values")
            for v in vals:
                bare = v[1:] if isinstance(v, str) and v.startswith("!") else v
                if bare not in all_vars[var]:
                    raise ScenarioError(f"{where}: {ctx}: {var} has no value {bare!r}; values: {all_vars[var]}")

    def check_set(st, ctx):
        for var, val in st.items():
            if var not in base_vars or var in HUMAN_VARS:
                raise ScenarioError(f"{where}: {ctx} sets {var!r}, which an action cannot set")
            if val not in all_vars[var]:
                raise ScenarioError(f"{where}: {ctx} sets {var} to {val!r}; values: {all_vars[var]}")

    stimuli = []
    for i, st in enumerate(need(raw, "stimuli", list, "scenario")):
        ctx = f"stimuli[{i}]"
        check_cond(need(st, "when", dict, ctx), ctx + ".when")
        eff = need(st, "effects", dict, ctx)
        for m, v in eff.items():
            if m not in motiv:
                raise ScenarioError(f"{where}: {ctx} affects unknown motivation {m!r}; known: {motiv}")
            checked(v, f"{where}: {ctx}.effects.{m}", error=ScenarioError)
        stimuli.append({"name": st.get("name", f"stimulus{i}"), "when": st["when"], "effects": dict(eff)})

    actions = []
    obj_names = list(objects) + [NULL_OBJECT]
    for i, a in enumerate(need(raw, "actions", list, "scenario")):
        ctx = f"actions[{i}]"
        name = need(a, "name", str, ctx)
        ctx = f"action {name!r}"
        obj = need(a, "object", str, ctx)
        if obj not in obj_names:
            raise ScenarioError(f"{where}: {ctx} targets unknown object {obj!r}; objects: {', '.join(obj_names)}")
        req = a.get("requires", {})
        check_cond(req, ctx + ".requires")
        effects = a.get("effects", [])
        if not isinstance(effects, list):
            raise ScenarioError(f"{where}: {ctx}.effects must be a list")
        for j, e in enumerate(effects):
            ectx = f"{ctx}.effects[{j}]"
            if not isinstance(e, dict) or set(e) - {"when", "set", "drives"}:
                raise ScenarioError(f"{where}: {ectx} may only have 'when', 'set' and 'drives'")
            check_cond(e.get("when", {}), ectx + ".when")
            check_set(e.get("set", {}), ectx + ".set")
            _check_drives(e.get("drives", {}), dnames, ectx, where)
        actions.append(ActionSpec(name, obj, dict(req), tuple(effects)))
    _unique([a.name for a in actions], "action", where)
    anames = {a.name for a in actions}
    for it in intentions:
        for d in it.desired:
            if d not in anames:
                raise ScenarioError(f"{where}: intention {it.name!r} desires unknown action {d!r}")
        check_cond(it.reasonable, f"intention {it.name!r}.reasonable")
    for o in obj_names:
        if not any(a.obj == o for a in actions):
            raise ScenarioError(f"{where}: object {o!r} has no actions")
    ongoing = _parse_ongoing(raw.get("ongoing", []), dnames, check_cond, where)

    fb = raw.get("feedback", {})
    learning = _check_learning(raw.get("learning", {}), len(drives), where)

    block = raw.get("open", {})
    if not isinstance(block, dict):
        raise ScenarioError(f"{where}: open must be an object")
    opens = parse_open({**block, **dict(overrides or {})}, Names(frozenset(anames), tuple(dnames), serving_name),
                       locations, base_vars, all_vars, motiv, where)
    observations = None
    if "observations" in raw:
        observations = _parse_observations(raw["observations"], [NONE_INTENTION] + [i.name for i in intentions], where)
    action_ids = {a.name: k for k, a in enumerate(actions)}
    rule_policy = None
    if "rule_policy" in raw:
        rule_policy = parse_rule_policy(raw["rule_policy"], drives, action_ids, check_cond, where)
    reference = parse_reference(raw["reference"], dnames, where) if "reference" in raw else None

    sc = Scenario(
        name=str(raw.get("name", Path(source).stem)),
        raw=raw,
        drives=tuple(drives),
        serving=dnames.index(serving_name),
        locations=locations,
        human_location=hloc,
        resting_place=rest,
        objects=objects,
        stimuli=tuple(stimuli),
        actions=tuple(actions),
        intentions=tuple(intentions),
        feedback_value=float(fb.get("value", 10)),
        praise_change=float(fb.get("praise_drive_change", -10)),
        learning=learning,
        open=opens,
        source=source,
        base_vars=tuple(base_vars),
        base_values=tuple(tuple(v) for v in base_values),
        observations=observations,
        rule_policy=rule_policy,
        reference=reference,
        ongoing=ongoing,
    )
    _compile(sc)
    return sc


def _parse_ongoing(block: Any, dnames: list, check_cond, where: str) -> tuple:
    """The scenario's ``ongoing`` effects: a state's effect on drives per tick (open choice ``ongoing_effects``)."""
    if not isinstance(block, list):
        raise ScenarioError(f"{where}: ongoing must be a list of {{'when': condition, 'drives': {{drive: change}}}}")
    out = []
    for i, og in enumerate(block):
        ctx = f"ongoing[{i}]"
        if not isinstance(og, dict) or set(og) - {"name", "when", "drives", "description"} or "when" not in og \
                or "drives" not in og:
            raise ScenarioError(f"{where}: {ctx} must be an object with 'when' and 'drives' (and optional 'name', "
                                "'description')")
        check_cond(og["when"], ctx + ".when")
        if not isinstance(og["drives"], dict) or not og["drives"]:
            raise ScenarioError(f"{where}: {ctx}.drives must be a non-empty object of drive: change")
        _check_drives(og["drives"], dnames, ctx, where)
        out.append({"name": str(og.get("name", f"ongoing{i}")), "when": dict(og["when"]), "drives": dict(og["drives"])})
    return tuple(out)


def _check_drives(changes: Mapping, dnames: list, ctx: str, where: str) -> None:
    """``{drive: change}`` of an action's effect or an ongoing effect: known drives, numeric changes."""
    for dn, dv in changes.items():
        if dn not in dnames:
            raise ScenarioError(f"{where}: {ctx} changes unknown drive {dn!r}")
        checked(dv, f"{where}: {ctx}.drives.{dn}", error=ScenarioError)


def _unique(names: Sequence, what: str, where: str) -> None:
    seen = set()
    for n in names:
        if n in seen:
            raise ScenarioError(f"{where}: {what} {n!r} is declared twice")
        seen.add(n)


def _parse_observations(obs: Any, intention_names: list, where: str) -> ObservationSpec:
    """Validate the ``observations`` block (alphabets, ``prior`` and optional ``habits``)."""
    ctx = f"{where}: observations"
    if not isinstance(obs, dict):
        raise ScenarioError(f"{ctx} must be an object")
    unknown = set(obs) - set(OBS_CHANNELS) - {"prior", "habits", "description"}
    if unknown:
        raise ScenarioError(f"{ctx} has unknown key(s) {sorted(unknown)}; known: {list(OBS_CHANNELS)}, prior, habits, description")
    alphabets = {}
    for ch in OBS_CHANNELS:
        vals = obs.get(ch)
        if not isinstance(vals, list) or not vals or not all(isinstance(v, str) and v for v in vals):
            raise ScenarioError(f"{ctx}.{ch} must be a non-empty list of symbol names")
        _unique(vals, f"{ch} symbol", where)
        alphabets[ch] = tuple(vals)

    def dist(spec: Any, symbols: Sequence[str], dctx: str) -> tuple:
        # listed symbols get their probability, unlisted ones share the rest equally
        if not isinstance(spec, dict):
            raise ScenarioError(f"{dctx} must be an object of symbol: probability")
        for sym, p in spec.items():
            if sym not in symbols:
                raise ScenarioError(f"{dctx}: unknown symbol {sym!r}; known: {', '.join(symbols)}")
            checked(p, f"{dctx}.{sym}: a probability", 0.0, 1.0, error=ScenarioError)
        total = left_sum(float(v) for v in spec.values())
        rest = [s for s in symbols if s not in spec]
        if total > 1.0 + 1e-9:
            raise ScenarioError(f"{dctx}: probabilities sum to {total:g}, more than 1")
        if not rest and abs(total - 1.0) > 1e-9:
            raise ScenarioError(f"{dctx}: probabilities sum to {total:g}; with every symbol listed they must sum to 1")
        share = max(0.0, 1.0 - total) / len(rest) if rest else 0.0
        return tuple(float(spec[s]) if s in spec else share for s in symbols)

    def per_intention(block: Any, bctx: str) -> dict:
        if not isinstance(block, dict):
            raise ScenarioError(f"{bctx} must be an object with one entry per intention")
        for name in block:
            if name != "intention" and name not in intention_names:
                raise ScenarioError(f"{bctx}: unknown intention {name!r}; known: {', '.join(intention_names)}")
        missing = [n for n in intention_names if n not in block]
        if missing:
            raise ScenarioError(f"{bctx} lacks intention(s) {missing}: every intention (with 'none') needs an entry")
        out = {}
        for ch in OBS_CHANNELS:
            rows = []
            for name in intention_names:
                entry = block[name]
                if not isinstance(entry, dict) or set(entry) - set(OBS_CHANNELS):
                    raise ScenarioError(f"{bctx}.{name} must be an object with (some of) {list(OBS_CHANNELS)}")
                rows.append(dist(entry.get(ch, {}), alphabets[ch], f"{bctx}.{name}.{ch}"))
            out[ch] = tuple(rows)
        return out

    prior_raw = obs.get("prior")
    if prior_raw is None:
        raise ScenarioError(f"{ctx} is missing 'prior' (the network's P(symbol | intention) per intention)")
    prior = per_intention(prior_raw, f"{ctx}.prior")
    prior_intention = dist(prior_raw.get("intention", {}), intention_names, f"{ctx}.prior.intention")
    habits = per_intention(obs["habits"], f"{ctx}.habits") if "habits" in obs else prior
    if "habits" in obs and "intention" in obs["habits"]:
        raise ScenarioError(f"{ctx}.habits: 'intention' does not apply (the simulated human draws its intentions itself)")
    return ObservationSpec(alphabets, prior_intention, prior, habits)


def _check_learning(block: Any, n_drives: int, where: str) -> dict:
    """The ``learning`` block: the learning parameters as declared (``homeo_msgs_py.learning``; one
    left out takes the declared default, DoD 1 / number of drives) and the alpha/tau ``schedule``."""
    if not isinstance(block, dict):
        raise ScenarioError(f"{where}: learning must be an object")
    given = {k: v for k, v in block.items() if k != SCHEDULE}
    try:
        params = check_learning(given)
    except ValueError as exc:
        raise ScenarioError(f"{where}: learning.{exc}") from None
    defaults = {s.name: s.default for s in LEARNING} | {DOD.name: 1.0 / n_drives}  # equal weights (Eq 3.28)
    learning = params | {k: v for k, v in defaults.items() if k not in params}
    learning[SCHEDULE] = block.get(SCHEDULE, [dict(phase) for phase in DEFAULT_SCHEDULE])
    sched = learning[SCHEDULE]
    if not isinstance(sched, list) or not sched or sched[0].get("from") != 0:
        raise ScenarioError(f"{where}: learning.schedule must be a list starting with from = 0")
    last = -1
    for s in sched:
        if not all(k in s for k in ("from", "alpha", "tau")) or s["from"] <= last:
            raise ScenarioError(f"{where}: learning.schedule entries need increasing 'from', 'alpha' and 'tau'")
        if not 0 < s["alpha"] <= 1 or not s["tau"] > 0:
            raise ScenarioError(f"{where}: learning.schedule: alpha must be in (0, 1] and tau > 0")
        last = s["from"]
    return learning

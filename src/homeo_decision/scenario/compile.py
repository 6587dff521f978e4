"""Compilation of a validated scenario into flat lookup tables indexed by world code.

``_compile`` enumerates every world code once and records, per code, the stimuli
(Table 3.2, summed per motivation for Eq 3.2), the valid actions (Table 3.3 constraints),
each action's next world and drive change (Table 4.1), the human state S_hum (Eq 3.9) and
each object's reduced state (Eq 3.10-3.13, 3.24-3.26).

The human's relation is part of the world code (as sensed on a robot); the next-world table is
the simulation's: an action that moves the robot re-derives the relation from the locations
(Section 4.2.1), any other leaves it as it was.
"""

from __future__ import annotations

import itertools
from typing import TYPE_CHECKING, Mapping

from .model import DISTANCES, NULL_OBJECT, PRESENCE, RELATIONS, Compiled

if TYPE_CHECKING:
    from .model import Scenario


def holds(cond: Mapping[str, list], view: Mapping[str, str]) -> bool:
    """Whether a condition ``{variable: [values]}`` holds in a view (``"!x"``: anything but x)."""
    for var, vals in cond.items():
        v = view[var]
        pos = [x for x in vals if not x.startswith("!")]
        neg = [x[1:] for x in vals if x.startswith("!")]
        if pos and v not in pos:
            return False
        if v in neg:
            return False
    return True


_holds = holds  # the older, private name


def _compile(sc: Scenario) -> None:
    base_vars, base_values = sc.base_vars, sc.base_values
    radices = [len(v) for v in base_values]
    n_codes = 1
    for r in radices:
        n_codes *= r
    sc.n_codes = n_codes
    dnames = sc.drive_names
    motivs = sc.motivation_names
    obj_names = sc.object_names
    act_ids = {a.name: i for i, a in enumerate(sc.actions)}
    intent_names = sc.intention_names

    # object reduced states (Eq 3.24-3.26); null has one empty state (Eq 3.12)
    obj_state_vars: list[list[tuple[str, tuple]]] = []
    obj_state_labels = []
    for o in obj_names:
        if o == NULL_OBJECT:
            obj_state_vars.append([])
            obj_state_labels.append(("-",))
            continue
        spec = sc.objects[o]
        axes = []
        if spec["location"] is not None:
            axes.append((f"{o}.distance", DISTANCES))
        for var, vals in spec["variables"].items():
            axes.append((f"{o}.{var}", tuple(vals)))
        obj_state_vars.append(axes)
        obj_state_labels.append(tuple("/".join(p) for p in itertools.product(*[vals for _, vals in axes])))

    obj_actions = [tuple(i for i, a in enumerate(sc.actions) if a.obj == o) for o in obj_names]
    act_obj = tuple(obj_names.index(a.obj) for a in sc.actions)
    act_local = tuple(obj_actions[act_obj[i]].index(i) for i in range(len(sc.actions)))

    def encode(vals: list[int]) -> int:
        code = 0
        for v, r in zip(vals, radices):
            code = code * r + v
        return code

    views, codes_vals = [], []
    for idx in itertools.product(*[range(r) for r in radices]):
        view = {var: base_values[k][i] for k, (var, i) in enumerate(zip(base_vars, idx))}
        loc = view["robot.location"]
        view["human.presence"] = "absent" if view["human.relation"] == "absent" else "present"
        for o, spec in sc.objects.items():
            if spec["location"] is not None:
                view[f"{o}.distance"] = "near" if loc == spec["location"] else "far"
        views.append(view)
        codes_vals.append(list(idx))

    stim, stim_names, valid, valid_local, next_code, drive_delta = [], [], [], [], [], []
    hum, obj_state, intention_of, relation_of, location_of, presence_of = [], [], [], [], [], []
    with_intention, with_relation, with_presence, reasonable = [], [], [], []
    loc_k, rel_k, int_k = 0, 1, 2
    absent = RELATIONS.index("absent")
    # the relation where the simulation places its human, per robot location (Section 4.2.1)
    located = [RELATIONS.index(sc.located_relation(loc, "present")) for loc in base_values[loc_k]]
    on_leave = sc.open.on_leave_effects  # objects left behind take their on_leave values
    # Eq 3.17 sums over all of A; Table 3.3's constraints exclude actions (default) or, read as
    # "has no effect", leave them selectable but idle (open choices invalid_actions, always_valid_actions)
    all_of_a = sc.open.invalid_actions == "no_effect"
    unconstrained = frozenset(sc.open.always_valid_actions)
    # open choice ongoing_effects: a state's effect on the drives on every tick that starts and ends in it
    ongoing = sc.ongoing if sc.open.ongoing_effects == "every_tick" else ()
    for code, (view, idx) in enumerate(zip(views, codes_vals)):
        s = [0.0] * len(motivs)
        present = []
        for st in sc.stimuli:
            if _holds(st["when"], view):
                present.append(st["name"])
                for m, v in st["effects"].items():
                    s[motivs.index(m)] += float(v)
        stim.append(tuple(s))
        stim_names.append(tuple(present))
        allowed = tuple(a.name in unconstrained or _holds(a.requires, view) for a in sc.actions)
        ok = tuple(range(len(sc.actions))) if all_of_a else tuple(i for i, a in enumerate(sc.actions) if allowed[i])
        valid.append(ok)
        valid_local.append(tuple(tuple(act_local[a] for a in ok if act_obj[a] == k) for k in range(len(obj_names))))
        ongoing_here = [og for og in ongoing if _holds(og["when"], view)]  # it must hold before and after
        nxt, dd = [], []
        for ai, a in enumerate(sc.actions):
            new = list(idx)
            delta = [0.0] * len(dnames)
            for e in (a.effects if allowed[ai] or not all_of_a else ()):  # an idle invalid action: no effect
                if not _holds(e.get("when", {}), view):
                    continue
                for var, val in e.get("set", {}).items():
                    k = base_vars.index(var)
                    new[k] = base_values[k].index(val)
                for dn, dv in e.get("drives", {}).items():
                    delta[dnames.index(dn)] += float(dv)
            if on_leave and new[loc_k] != idx[loc_k]:
                for o, spec in sc.objects.items():
                    if spec["location"] == sc.locations[idx[loc_k]]:
                        for var, val in spec["on_leave"].items():
                            k = base_vars.index(f"{o}.{var}")
                            new[k] = base_values[k].index(val)
            if new[loc_k] != idx[loc_k] and idx[rel_k] != absent:  # the robot moved: relation from the locations
                new[rel_k] = located[new[loc_k]]
            nc = encode(new)
            own = tuple(delta)  # the action's own effects: an ongoing effect does not add to a drive they change
            for og in ongoing_here:
                if _holds(og["when"], views[nc]):
                    for dn, dv in og["drives"].items():
                        k = dnames.index(dn)
                        if own[k] == 0.0:
                            delta[k] += float(dv)
            nxt.append(nc)
            dd.append(tuple(delta))
        next_code.append(tuple(nxt))
        drive_delta.append(tuple(dd))
        rel = idx[rel_k]
        hum.append(idx[int_k] * len(RELATIONS) + rel)  # S_hum = intention x relation (Eq 3.9)
        os_ = []
        for k, axes in enumerate(obj_state_vars):
            si = 0
            for var, vals in axes:
                si = si * len(vals) + vals.index(view[var])
            os_.append(si)
        obj_state.append(tuple(os_))
        intention_of.append(idx[int_k])
        relation_of.append(rel)
        location_of.append(idx[loc_k])
        presence_of.append(PRESENCE.index(view["human.presence"]))
        with_intention.append(tuple(_with(idx, int_k, i, encode) for i in range(len(intent_names))))
        with_relation.append(tuple(_with(idx, rel_k, r, encode) for r in range(len(RELATIONS))))
        with_presence.append((_with(idx, rel_k, located[idx[loc_k]], encode), _with(idx, rel_k, absent, encode)))
        reasonable.append(tuple(i + 1 for i, it in enumerate(sc.intentions) if _holds(it.reasonable, view)))

    desired = (frozenset(),) + tuple(frozenset(act_ids[d] for d in it.desired) for it in sc.intentions)
    sc.c = Compiled(
        action_ids=act_ids,
        views=views,
        stim=stim,
        stim_names=stim_names,
        valid=valid,
        valid_local=valid_local,
        next_code=next_code,
        drive_delta=drive_delta,
        hum=hum,
        obj_state=obj_state,
        obj_state_labels=obj_state_labels,
        obj_actions=obj_actions,
        act_obj=act_obj,
        act_local=act_local,
        intention_of=intention_of,
        relation_of=relation_of,
        location_of=location_of,
        presence_of=presence_of,
        with_intention=with_intention,
        with_relation=with_relation,
        with_presence=with_presence,
        reasonable=reasonable,
        desired=desired,
        n_hum=len(intent_names) * len(RELATIONS),
    )


def _with(idx: list, k: int, value: int, encode) -> int:
    """The code of the base values ``idx`` with base variable ``k`` set to ``value``."""
    new = list(idx)
    new[k] = value
    return encode(new)

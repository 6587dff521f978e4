"""The scenario model: what a validated scenario holds, and its compiled lookup tables.

A scenario is data (JSON), validated on load (``load.py``) and *compiled* (``compile.py``)
into flat lookup tables so that the per-tick work is a handful of list indexings. Every
world the scenario can be in is a small integer, the *world code*: a mixed-radix number over
the base variables (robot location, human relation, intention, each object variable).
Derived variables (the human's presence, an object's distance to the robot) are computed from
the base ones.

The human's relation to the robot (near / far / absent, Eq 3.9) is a base variable because a
robot senses it (a Pepper's engagement zones): a person may walk up to the robot wherever it
stands. The simulation places its human at the scenario's human location and derives the relation
from the two locations (Section 4.2.1: near iff the robot is there), so it only ever reaches the
*located* worlds; the others are reachable on a robot.

Conditions (`requires`, `when`, `reasonable`) are ``{variable: [values]}``; a value
written ``"!x"`` means "anything but x". All listed variables must hold (AND).
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass, field
from typing import Mapping

SCHEMA = "homeo-scenario"
SCHEMA_VERSION = 1
NONE_INTENTION = "none"
NO_MOTIVATION = "none"  # the internal state without a dominant motivation (open choice no_activated_motivation)
NULL_OBJECT = "null"
PRESENCE = ("present", "absent")
RELATIONS = ("near", "far", "absent")
# the human's variables: the human (or the robot's senses) sets them, never an action or the initial state
HUMAN_VARS = ("human.relation", "human.presence", "intention")
DISTANCES = ("near", "far")

# Observed children of the hidden intention in the Bayesian network (Section 2.3, Fig 2.3).
OBS_CHANNELS = ("gesture", "movement", "keyword")


class ScenarioError(ValueError):
    """A scenario file that cannot be used; the message says where and why."""


@dataclass(frozen=True)
class DriveSpec:
    name: str
    motivation: str
    threshold: float
    rate: float
    source: str  # "internal" (computed by the robot) or "body" (read from the body)


@dataclass(frozen=True)
class ActionSpec:
    name: str
    obj: str
    requires: dict
    effects: tuple  # of dicts: {"when": cond, "set": {...}, "drives": {...}}


@dataclass(frozen=True)
class IntentionSpec:
    name: str
    desired: tuple
    reasonable: dict


@dataclass(frozen=True)
class ObservationSpec:
    """The scenario's ``observations`` block: alphabets, the network's prior and the user's habits.

    ``prior`` and ``habits`` map a channel to one distribution over its alphabet per intention
    (``Scenario.intention_names`` order, ``none`` first): P0(symbol | intention) for the
    network, and how the simulated user actually expresses each intention.
    """

    alphabets: dict  # channel -> tuple of symbols
    prior_intention: tuple  # P0(intention)
    prior: dict  # channel -> tuple (per intention) of tuple (per symbol)
    habits: dict  # channel -> same shape as prior

    def layout(self) -> dict:
        """What a saved intention model must agree with (besides the intentions)."""
        return {ch: list(self.alphabets[ch]) for ch in OBS_CHANNELS}


@dataclass(frozen=True)
class RuleCandidate:
    """One action a rule may pick: taken when it is valid and its ``when`` world condition holds."""

    action: int  # action id
    when: dict  # condition on the world's variables ({} = always)


@dataclass(frozen=True)
class RuleSpec:
    """One prioritized rule of the scenario's ``rule_policy`` block (see ``rule_policy.py``).

    It fires when its drive is at or above ``at`` (or, with hysteresis, while the world
    satisfies ``keep_when`` and the drive is above ``keep_above``) and the world satisfies
    ``when``; a rule without a drive fires whenever ``when`` holds. ``serve`` rules pick the
    first valid desired action of the expressed intention; others the first valid candidate
    whose condition holds. A rule that picks nothing falls through to the next.
    """

    name: str
    drive: int | None  # drive index, None: no drive condition
    at: float  # fire when drive >= at
    when: dict  # world condition the rule needs besides its drive
    keep_when: dict | None  # hysteresis: keep going while this holds ...
    keep_above: float  # ... and the drive is above this
    serve: bool
    candidates: tuple  # of RuleCandidate


@dataclass(frozen=True)
class ReferenceSpec:
    """Published numbers to print beside ours (the scenario's optional ``reference`` block).

    ``metrics``: {"HSR": x, "RSR": x, "CDA": {drive or "all": x}, "CEDA": {...}} (any part may be
    missing). ``statements``: what the source says about the sweeps, as texts per sweep plus
    the few numbers and the drive the report's comparisons need (see ``reference.py``).
    """

    source: str
    metrics: dict
    statements: dict | None
    criteria: tuple | None = None  # of dicts: a statement of the text and its testable criterion (reference.py)


@dataclass
class Scenario:
    """A validated scenario plus its compiled tables (see module docstring)."""

    name: str
    raw: dict
    drives: tuple
    serving: int
    locations: tuple
    human_location: str
    resting_place: str
    objects: dict  # name -> {"location": str|None, "variables": {var: [values]}, "on_leave": {...}}
    stimuli: tuple
    actions: tuple
    intentions: tuple
    feedback_value: float
    praise_change: float
    learning: dict  # the learning parameters by name (homeo_msgs_py.learning) and the alpha/tau schedule
    open: "OpenChoices"  # the open choices and the initial state (open_choices.py)
    source: str = "<memory>"
    # compiled
    base_vars: tuple = ()
    base_values: tuple = ()
    n_codes: int = 0
    c: "Compiled" = field(default=None, repr=False)  # type: ignore[assignment]
    observations: ObservationSpec | None = None  # None: the scenario cannot run intention recognition
    rule_policy: tuple | None = None  # of RuleSpec; None: the scenario has no rule baseline
    reference: ReferenceSpec | None = None  # None: no published numbers to compare with
    ongoing: tuple = ()  # of {"name", "when", "drives"}: a state's drive effect per tick (open choice ongoing_effects)

    # -- names ---------------------------------------------------------------
    @property
    def drive_names(self) -> list[str]:
        return [d.name for d in self.drives]

    @property
    def motivation_names(self) -> list[str]:
        return [d.motivation for d in self.drives]

    @property
    def internal_states(self) -> list[str]:
        """The values of m_dom (Eq 3.6): the motivations, and ``none`` when the open choice
        ``no_activated_motivation`` is ``none``."""
        names = self.motivation_names
        return names + [NO_MOTIVATION] if self.open.no_activated_motivation == "none" else names

    @property
    def none_state(self) -> int:
        """The index of m_dom ``none`` (-1: Eq 3.3's argmax always picks a motivation)."""
        return len(self.drives) if self.open.no_activated_motivation == "none" else -1

    @property
    def activation_thresholds(self) -> list[float]:
        """The thresholds Eq 3.2 compares with (``d < at``: not activated). Under the open choice
        ``activation_boundary = above`` a drive exactly at its threshold is not activated either
        (Definition 3): the next float above each threshold, so that ``d < at'`` is ``d <= at``."""
        thr = [d.threshold for d in self.drives]
        if self.open.activation_boundary == "above":
            return [math.nextafter(t, math.inf) for t in thr]
        return thr

    @property
    def action_names(self) -> list[str]:
        return [a.name for a in self.actions]

    @property
    def intention_names(self) -> list[str]:
        """Intentions as the robot perceives them: ``none`` first."""
        return [NONE_INTENTION] + [i.name for i in self.intentions]

    @property
    def object_names(self) -> list[str]:
        """Objects with a Q-table, the ``null`` object last (Eq 3.12)."""
        return list(self.objects) + [NULL_OBJECT]

    def action_index(self, name: str) -> int:
        try:
            return self.c.action_ids[name]
        except KeyError:
            raise ScenarioError(f"unknown action {name!r}; known: {', '.join(self.action_names)}") from None

    def fingerprint(self) -> str:
        """Hash of what a Q-table depends on (drives, intentions, objects' states/actions)."""
        blob = json.dumps(self.q_layout(), sort_keys=True).encode()
        return hashlib.sha256(blob).hexdigest()[:16]

    def q_layout(self) -> dict:
        """Labels of every Q-table axis: what a saved table must agree with."""
        c = self.c
        return {
            "motivations": self.internal_states,
            "intentions": self.intention_names,
            "relations": list(RELATIONS),
            "objects": {
                o: {"states": list(c.obj_state_labels[k]), "actions": [self.actions[a].name for a in c.obj_actions[k]]}
                for k, o in enumerate(self.object_names)
            },
        }

    def located_relation(self, location: str, presence: str) -> str:
        """The human's relation as the simulation derives it (Section 4.2.1): the human stays at the
        scenario's human location, so it is near iff the robot is there (absent when absent)."""
        return "absent" if presence == "absent" else "near" if location == self.human_location else "far"

    def code_layout(self) -> list:
        """How world codes are numbered (the base variables and their values, in order): what a
        saved world code must agree with."""
        return [[var, list(vals)] for var, vals in zip(self.base_vars, self.base_values)]

    # -- observations --------------------------------------------------------
    def encode(self, values: Mapping[str, str]) -> int:
        """World code of a full assignment of the base variables. ``human.presence`` may stand for
        ``human.relation``: the relation is then the located one (``located_relation``); given
        both, they must agree (absent iff absent)."""
        values = _relation_of(self, values)
        code = 0
        for var, vals in zip(self.base_vars, self.base_values):
            v = values.get(var)
            if v not in vals:
                raise ScenarioError(f"{var} = {v!r} is not one of {list(vals)}")
            code = code * len(vals) + vals.index(v)
        return code

    def decode(self, code: int) -> dict[str, str]:
        out = {}
        for var, vals in reversed(list(zip(self.base_vars, self.base_values))):
            code, r = divmod(code, len(vals))
            out[var] = vals[r]
        return dict(reversed(list(out.items())))

    def view(self, code: int) -> dict[str, str]:
        """Base and derived variables of a world code."""
        return dict(self.c.views[code])


def _relation_of(sc: "Scenario", values: Mapping[str, str]) -> Mapping[str, str]:
    rel, pres = values.get("human.relation"), values.get("human.presence")
    if pres is None:
        return values
    if pres not in PRESENCE:
        raise ScenarioError(f"human.presence = {pres!r} is not one of {list(PRESENCE)}")
    if rel is None:
        return dict(values, **{"human.relation": sc.located_relation(values.get("robot.location"), pres)})
    if rel in RELATIONS and (rel == "absent") != (pres == "absent"):
        raise ScenarioError(f"human.presence {pres!r} contradicts human.relation {rel!r}")
    return values


@dataclass
class Compiled:
    """Lookup tables indexed by world code (and action / object index)."""

    action_ids: dict
    views: list  # code -> dict of all variables
    stim: list  # code -> tuple of per-motivation stimulus sums (Eq 3.2)
    stim_names: list  # code -> tuple of present stimulus names
    valid: list  # code -> tuple of valid action ids (Table 3.3 constraints)
    valid_local: list  # code -> tuple per object of valid local action indices
    next_code: list  # code -> tuple per action of the world code after its effects
    drive_delta: list  # code -> tuple per action of tuple per drive of the change (Table 4.1)
    hum: list  # code -> index of S_hum = intention x relation (Eq 3.9)
    obj_state: list  # code -> tuple per object of its state index (Eq 3.24-3.26)
    obj_state_labels: list  # object -> tuple of state labels
    obj_actions: list  # object -> tuple of action ids (A_o)
    act_obj: tuple  # action -> object index
    act_local: tuple  # action -> index within A_o
    intention_of: list  # code -> intention index (0 = none)
    relation_of: list  # code -> relation index (a base variable: as sensed, or as the simulation located it)
    location_of: list  # code -> location index
    presence_of: list  # code -> 0 present / 1 absent (derived from the relation)
    with_intention: list  # code -> tuple per intention index of the code with that intention
    with_relation: list  # code -> tuple per relation index of the code with that relation
    # code -> (the code with the human present where the simulation places them: the located
    # relation, Section 4.2.1; the code with the human absent): the simulated human's moves
    with_presence: list
    reasonable: list  # code -> tuple of intention indices reasonable there (human side)
    desired: tuple  # intention index -> frozenset of action ids
    n_hum: int


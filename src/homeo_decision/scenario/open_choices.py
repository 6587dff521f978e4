"""The choices the thesis leaves open (docs/FIDELITY.md), declared once and typed.

``OpenChoices`` is what ``Scenario.open`` holds: one attribute per choice (``sc.open.reward_span``),
each declared here with its default, the values it may take and what it decides; and the initial
state the same ``open`` block gives (``initial_drives``, ``initial_location``, ``initial_objects``).
``parse_open`` validates the file's block with the overrides over it (``homeo-sim --set``, a node's
``overrides`` parameter) in one place: a bad value is a one-line ScenarioError. The file format is
unchanged; ``table()`` is docs/FIDELITY.md's table of the choices (a test compares).
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import Any, Callable, Mapping, Sequence

from homeo_msgs_py.params import ParamSpec, checked, number

from .model import HUMAN_VARS, NO_MOTIVATION, ScenarioError

# when a drive other than the serving one grows (drive_growth): every tick (Table 4.2), only on ticks
# the human is not near the robot (Sec 3.3.1, NSoc: "increases when the robot is not interacting with
# human"), only on ticks whose action changed the robot's location (Sec 3.3.1, NRes: "assumed to
# increase as robot moves"), or on every tick whose action does not lower it (NSoc "is lowered when
# the robot chats", NRes: joints heat up "in motion or maintaining certain postures" and cool while resting)
GROWTH_READINGS = ("always", "human_not_near", "robot_moved", "not_lowered")
INITIAL_STATE = ("initial_drives", "initial_location", "initial_objects")  # checked against the scenario


@dataclass(frozen=True)
class Names:
    """The scenario's names an open choice may refer to."""

    actions: frozenset
    drives: tuple
    serving: str


# -- what a choice may take: a declaration (``homeo_msgs_py.params.ParamSpec``, the one validator of a typed
# value), and for a choice that names the scenario's things, the names it may take ------------------------
@dataclass(frozen=True)
class Allowed:
    spec: ParamSpec  # its type and range or choices
    names: Callable | None = None  # (value, Names) -> the names it may also or only take, or None: any
    shown: str = ""  # what the docs table says it takes, when the declaration alone cannot

    def check(self, key: str, val, names: Names):
        extra = self.names(names) if self.names is not None else ()
        try:
            if self.spec.kind is str and isinstance(val, str) and val in extra:
                return val
            if isinstance(val, (list, tuple)) and self.spec.kind is tuple:
                val = tuple(val)
                if not set(val) <= set(extra) or len(set(val)) != len(val):
                    raise ValueError(f"must be a list of distinct action names: {', '.join(sorted(extra))}")
            return self.spec.check(val)
        except ValueError as exc:
            raise ValueError(f"open.{key} {exc}" + (f" (or one of {', '.join(sorted(extra))})" if extra and
                                                    self.spec.kind is str else "")) from None

    def text(self) -> str:
        s = self.spec
        return self.shown or s.range_text().replace("|", "\\|") or ("true \\| false" if s.kind is bool else "")


def Between(lo: float, hi: float) -> Allowed:  # noqa: N802 - reads as a type in the declarations below
    """Any number in [lo, hi] (kept as a float)."""
    return Allowed(number(lo, hi, float))


def OneOf(*values, any_action: bool = False) -> Allowed:  # noqa: N802
    """One of ``values`` (strings, or True and False); ``any_action``: or an action name of the scenario."""
    if values == (True, False):
        return Allowed(ParamSpec("", True, ""))
    return Allowed(ParamSpec("", values[0], "", choices=values),
                   (lambda n: n.actions) if any_action else None,
                   " \\| ".join(values + (("an action name",) if any_action else ())))


def ActionList() -> Allowed:  # noqa: N802
    """Distinct action names of the scenario (kept as a tuple)."""
    return Allowed(ParamSpec("", (), ""), lambda n: n.actions, "distinct action names")


class DriveReadings:
    """``{drive: one of GROWTH_READINGS}`` for drives other than the serving one (in drive order)."""

    def check(self, key: str, val, names: Names):
        if not isinstance(val, dict) or not all(isinstance(k, str) and k in names.drives and k != names.serving
                                                and v in GROWTH_READINGS for k, v in val.items()):
            others = [d for d in names.drives if d != names.serving]
            raise ValueError(f"open.{key} = {val!r} must map drive names ({', '.join(others)}; the "
                             f"serving drive's is serving_growth) to one of {list(GROWTH_READINGS)}")
        return {k: val[k] for k in names.drives if k in val}

    def text(self) -> str:
        return "{drive: " + " \\| ".join(GROWTH_READINGS) + "}"


def choice(default, allowed, doc: str, late: bool = False):
    """A field of ``OpenChoices``: an open choice with its default, the values it may take and its doc.
    ``late``: declared after world checkpoints began to print the block (``OpenChoices.printed``)."""
    meta = {"allowed": allowed, "doc": doc, "late": late}
    if isinstance(default, dict):  # a mutable default: each instance its own
        return field(default_factory=lambda: dict(default), metadata=meta)
    return field(default=default, metadata=meta)


def initial(default, doc: str):
    """A field of ``OpenChoices`` that gives the initial state (checked against the scenario's names)."""
    if isinstance(default, dict):
        return field(default_factory=dict, metadata={"doc": doc})
    return field(default=default, metadata={"doc": doc})


def _default(f):
    return f.default_factory() if callable(f.default_factory) else f.default


@dataclass(frozen=True)
class OpenChoices:
    """The ``open`` block, validated: the thesis's open choices and the initial state."""

    initial_q: float = choice(0.0, Between(-1e6, 1e6), "the value every Q entry starts at (Eq 3.14 says none)")
    scold_drive_change: float = choice(0.0, Between(-100.0, 100.0), "change of the serving drive when the "
                                       "user scolds (Sec 3.3.1: it increases, by no amount)")
    serving_growth: str = choice("always", OneOf("always", "expressed", "unsatisfied"), "the serving drive grows "
                                 "every tick, only while an intention is expressed, or only while one is "
                                 "expressed and not yet satisfied (Table 4.2)")
    reward_span: str = choice("iteration", OneOf("iteration", "action"), "the drives 'after' of Eq 3.19: after "
                              "the whole iteration or right after the action (before the time increase)")
    on_leave_effects: bool = choice(True, OneOf(True, False), "objects' on_leave settings apply when the robot "
                                    "leaves their location")
    tie_break: str = choice("first", OneOf("first", "last"), "Eq 3.3's argmax on a tie")
    value_max_over: str = choice("all", OneOf("all", "valid"), "V of Eq 3.15-3.16: max over all of A_o or the "
                                 "valid actions")
    human_no_intention_prob: float = choice(0.0, Between(0.0, 1.0), "P(the simulated human wants nothing)")
    human_leave_prob: float = choice(0.0, Between(0.0, 1.0), "P(the present human leaves) a tick")
    human_return_prob: float = choice(1.0, Between(0.0, 1.0), "P(the absent human returns) a tick")
    human_proposal_choice: str = choice("first", OneOf("first", "random", any_action=True), "which desired "
                                        "action the human proposes when its intention has several: the first, "
                                        "a random one, or a named one (when desired, else the first)")
    human_proposal_prob: float = choice(1.0, Between(0.0, 1.0), "P(the human proposes an action after a scold)")
    metrics_sample: str = choice("end", OneOf("end", "after_action"), "when d(t) of Eq 4.2-4.5 is sampled: "
                                 "after the time increase or right after the action")
    invalid_actions: str = choice("excluded", OneOf("excluded", "no_effect"), "Eq 3.17's softmax over the "
                                  "actions whose Table 3.3 constraint holds, or over all of A (a failing one "
                                  "changes nothing)")
    always_valid_actions: tuple = choice((), ActionList(), "actions whose Table 3.3 constraint is dropped")
    time_increase: str = choice("after_action", OneOf("after_action", "before_action"), "the Table 4.2 time "
                                "increase comes after the action's and the feedback's effects, or before them")
    drive_growth: dict = choice({}, DriveReadings(), "drives (not the serving one) that grow only on some "
                                      "ticks")
    no_activated_motivation: str = choice("argmax", OneOf("argmax", "none"), "when no motivation is activated "
                                          "(Definition 6): Eq 3.3's argmax picks one, or m_dom is 'none'")
    activation_boundary: str = choice("eq_3_2", OneOf("eq_3_2", "above"), "a drive exactly at its threshold: "
                                      "Eq 3.2 activates its motivation ('0 if d_i < at_i'); 'above': not "
                                      "activated, as Definition 3 reads ('When d_i > at_i, d_i is considered "
                                      "unsatisfied')", late=True)
    ongoing_effects: str = choice("actions", OneOf("actions", "every_tick"), "the scenario's ongoing block "
                                  "(Table 4.1's charging): only through the actions whose own effects say so, "
                                  "or on every tick that starts and ends in that state whatever the action "
                                  "(a drive the action changes is not changed twice)", late=True)
    motivation_bonus: str = choice("dominant", OneOf("dominant", "activated"), "Eq 3.20's bonus (1 + xi) goes to "
                                   "the drive of m_dom whatever its intensity, or only when m_dom is activated "
                                   "(Definition 6: intensity > 0)", late=True)
    pseudo_reward: str = choice("eq_3_20", OneOf("eq_3_20", "eq_3_19"), "r+_drives of Eq 3.23: by Eq 3.20 (with "
                                "the motivation factor) or by Eq 3.19 (without it)", late=True)
    pseudo_serving: str = choice("praise", OneOf("praise", "satisfied"), "the serving drive in the pseudo new "
                                 "state (Sec 3.2.6, approximation 1): moved as a praise moves it, or to 0 (the "
                                 "need met)", late=True)
    intention_threshold: float = choice(0.0, Between(0.0, 1.0), "below this posterior the recognised "
                                        "intention is none (docs/INTENTION.md)")
    intention_prior_strength: float = choice(10.0, Between(0.0, 1e6), "textbook observations each prior CPD "
                                             "column is worth")
    intention_reveal: str = choice("proposal", OneOf("proposal", "feedback", "never"), "which responses of the "
                                   "user reveal the intention")
    gesture_noise: float = choice(0.0, Between(0.0, 1.0), "P(a gesture is uniform noise, not the user's habit)")
    movement_noise: float = choice(0.0, Between(0.0, 1.0), "P(a movement is uniform noise)")
    keyword_noise: float = choice(0.0, Between(0.0, 1.0), "P(a keyword is uniform noise)")
    # the initial state: not choices of the thesis, but given by the same block
    initial_drives: tuple = initial((), "drive values at the start, in drive order (the file: {drive: value}, "
                                    "0 for one left out)")
    initial_location: str = initial("", "the robot's location at the start (default: the first location)")
    initial_objects: dict = initial({}, "object variables at the start ({object.variable: value}; default: "
                                    "each variable's first value)")

    def as_dict(self) -> dict:
        """The block as plain data, in declaration order (results files, a checkpoint's scenario print)."""
        return {f.name: getattr(self, f.name) for f in fields(self)}

    def printed(self) -> dict:
        """``as_dict`` without the choices declared after checkpoints began to print the block, where they
        hold their defaults: a checkpoint written before a choice existed stays valid while it is unused."""
        return {f.name: getattr(self, f.name) for f in fields(self)
                if not (f.metadata.get("late") and getattr(self, f.name) == _default(f))}


CHOICES = tuple(f for f in fields(OpenChoices) if "allowed" in f.metadata)  # the open choices, in order
NAMES = tuple(f.name for f in CHOICES)


def parse_open(block: Mapping, names: Names, locations: Sequence, base_vars: Sequence, all_vars: Mapping,
               motivations: Sequence, where: str) -> OpenChoices:
    """The ``open`` block (overrides already over it) as ``OpenChoices``, or a one-line ScenarioError."""
    if not isinstance(block, Mapping):
        raise ScenarioError(f"{where}: open must be an object")
    for key in block:
        if key not in NAMES and key not in INITIAL_STATE:
            raise ScenarioError(f"{where}: unknown open choice {key!r}; known: {', '.join(sorted(NAMES))}")
    out: dict[str, Any] = {}
    for f in CHOICES:
        try:
            out[f.name] = f.metadata["allowed"].check(f.name, block.get(f.name, _default(f)), names)
        except ValueError as exc:
            raise ScenarioError(f"{where}: {exc}") from None
    if out["no_activated_motivation"] == "none" and NO_MOTIVATION in motivations:
        raise ScenarioError(f"{where}: open.no_activated_motivation = 'none' needs the name {NO_MOTIVATION!r}, "
                            f"which a motivation already has")
    return OpenChoices(**out, **_initial_state(block, names, locations, base_vars, all_vars, where))


def _initial_state(block: Mapping, names: Names, locations: Sequence, base_vars: Sequence, all_vars: Mapping,
                   where: str) -> dict:
    init = block.get("initial_drives", {})
    if not isinstance(init, dict):
        raise ScenarioError(f"{where}: open.initial_drives must be an object of drive: value")
    for dn, v in init.items():
        if dn not in names.drives:
            raise ScenarioError(f"{where}: open.initial_drives has unknown drive {dn!r}")
        checked(v, f"{where}: open.initial_drives.{dn}", 0, 100, error=ScenarioError)
    loc = block.get("initial_location", locations[0])
    if not isinstance(loc, str) or loc not in locations:
        raise ScenarioError(f"{where}: open.initial_location {loc!r} is not a location")
    objs = block.get("initial_objects", {})
    if not isinstance(objs, dict):
        raise ScenarioError(f"{where}: open.initial_objects must be an object of object.variable: value")
    objs = dict(objs)
    for var, val in objs.items():
        if var not in all_vars or var in ("robot.location", *HUMAN_VARS) or var not in base_vars:
            raise ScenarioError(f"{where}: open.initial_objects has unknown object variable {var!r}")
        if val not in all_vars[var]:
            raise ScenarioError(f"{where}: open.initial_objects.{var} = {val!r}; values: {all_vars[var]}")
    for var in base_vars[3:]:
        objs.setdefault(var, all_vars[var][0])
    return {"initial_drives": tuple(float(init.get(dn, 0.0)) for dn in names.drives), "initial_location": loc,
            "initial_objects": objs}


def table() -> str:
    """The open choices as docs/FIDELITY.md shows them (defaults: the declared ones, not a scenario's)."""
    rows = ["| open choice | takes | default | decides |", "|---|---|---|---|"]
    for f in CHOICES:
        default = _default(f)
        shown = "true" if default is True else "false" if default is False else \
            f"{default:g}" if isinstance(default, float) else "[]" if default == () else \
            "{}" if default == {} else str(default)
        rows.append(f"| `{f.name}` | {f.metadata['allowed'].text()} | {shown} | {f.metadata['doc']} |")
    return "\n".join(rows)


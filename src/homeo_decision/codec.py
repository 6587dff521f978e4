"""Between the core's records (world codes, indices) and the graph's message fields (names).

The one place where an :class:`~homeo_decision.environment.Observation`, an
:class:`~homeo_decision.environment.Outcome`, a perception and an action become the fields of
``homeo/world``, ``homeo/observation``, ``homeo/outcome``, ``homeo/drives`` and ``homeo/action``
(``homeo_msgs_py.schemas``) and back. Fields coming in have been validated by ``decode`` against
the scenario's vocabulary; the functions here raise ScenarioError only for combinations the
vocabulary cannot rule out.
"""

from __future__ import annotations

from homeo_msgs_py.schemas import Vocabulary

from .environment import Observation, Outcome
from .scenario import NONE_INTENTION, OBS_CHANNELS, PRESENCE, RELATIONS, Scenario


def vocabulary(sc: Scenario) -> Vocabulary:
    """The names a scenario's messages may carry."""
    return Vocabulary(object_vars={o: {var: list(vals) for var, vals in spec["variables"].items()}
                                   for o, spec in sc.objects.items()},
                      actions=sc.action_names, intentions=sc.intention_names, drives=sc.drive_names,
                      motivations=sc.motivation_names, internal_states=sc.internal_states, locations=sc.locations, presences=PRESENCE,
                      relations=RELATIONS)


# -- the world -----------------------------------------------------------------------------
def world_code(sc: Scenario, world: dict, intention: str = NONE_INTENTION) -> int:
    """World code of ``homeo/world``'s robot/objects/human seen with ``intention`` (raises ScenarioError).

    The human's relation is taken as the world carries it (a robot senses it; the simulation
    derived it from the locations), never rebuilt from the robot's location; a presence that
    contradicts it (absent iff absent) is refused."""
    human = world["human"]
    values = {"robot.location": world["robot"]["location"], "human.relation": human["relation"],
              "intention": intention}
    if "presence" in human:
        values["human.presence"] = human["presence"]
    for o, vars_ in world["objects"].items():
        for var, v in vars_.items():
            values[f"{o}.{var}"] = v
    return sc.encode(values)


def world_state(sc: Scenario, code: int) -> dict:
    """The ``robot``/``objects``/``human`` fields of ``homeo/world`` for a world code."""
    v = sc.view(code)
    return {
        "robot": {"location": v["robot.location"]},
        "objects": {o: {var: v[f"{o}.{var}"] for var in spec["variables"]} for o, spec in sc.objects.items()},
        "human": {"presence": v["human.presence"], "relation": v["human.relation"]},
    }


def body_fields(sc: Scenario, body) -> dict:
    """Body readings indexed like all drives -> ``{drive name: value}`` of the body drives."""
    return {d.name: float(body[i]) for i, d in enumerate(sc.drives) if d.source == "body"}


def body_vector(sc: Scenario, body: dict, default=None) -> list[float]:
    """``{drive name: value}`` -> a vector indexed like all drives; a body drive missing from ``body``
    takes ``default[i]`` (else 0); internal drives are 0 (never read)."""
    out = []
    for i, d in enumerate(sc.drives):
        v = body.get(d.name) if d.source == "body" else None
        out.append(float(v) if v is not None else float(default[i]) if default is not None else 0.0)
    return out


def world_fields(sc: Scenario, obs: Observation, final: bool = False) -> dict:
    out = world_state(sc, obs.code)
    out["body"] = body_fields(sc, obs.body)
    if obs.readings:
        out["body"].update(obs.readings)
    if final:
        out["final"] = True
    return out


def observation_fields(sc: Scenario, obs: Observation) -> dict:
    out = {}
    if obs.intention is not None:
        out["intention"] = sc.intention_names[obs.intention]
    if obs.cues:
        out.update({ch: obs.cues.get(ch) for ch in OBS_CHANNELS})
    return out


def observation_messages(sc: Scenario, obs: Observation, final: bool = False) -> tuple[dict, dict]:
    """``homeo/world`` and ``homeo/observation`` fields of one observation (a world node's tick)."""
    return world_fields(sc, obs, final), observation_fields(sc, obs)


def observation_from_fields(sc: Scenario, world: dict | None, seen: dict | None) -> Observation:
    """The Observation of a ``homeo/world`` and/or a ``homeo/observation`` payload (either may be
    None: the intention node reads only the second, the drives node only the first)."""
    code = world_code(sc, world) if world is not None else -1
    body = body_vector(sc, world["body"]) if world is not None else ()
    intention = cues = None
    if seen is not None:
        name = seen.get("intention")
        intention = sc.intention_names.index(name) if name is not None else None
        cues = {ch: seen.get(ch) for ch in OBS_CHANNELS}
    return Observation(code, body, intention, cues)


# -- outcomes ------------------------------------------------------------------------------
def _name(names, i):
    return names[i] if i is not None else None


def _index(names, name):
    return names.index(name) if name is not None else None


def outcome_fields(sc: Scenario, out: Outcome) -> dict:
    acts, its = sc.action_names, sc.intention_names
    f = {"action": _name(acts, out.action), "feedback": out.feedback, "proposal": _name(acts, out.proposal),
         "clarified_intention": _name(its, out.clarified)}
    if out.body is not None:
        f["body"] = body_fields(sc, out.body)
    if out.true_intention is not None:
        f["truth"] = {"intention": its[out.true_intention], "expressed": out.true_intention != 0,
                      "satisfied": out.satisfied}
    return f


def outcome_from_fields(sc: Scenario, f: dict) -> Outcome:
    acts, its = sc.action_names, sc.intention_names
    body = body_vector(sc, f["body"]) if f.get("body") is not None else None
    truth = f.get("truth")
    return Outcome(_index(acts, f.get("action")), f.get("feedback", 0), _index(acts, f.get("proposal")),
                   _index(its, f.get("clarified_intention")), body,
                   its.index(truth["intention"]) if truth else None, bool(truth and truth["satisfied"]))


def learned_fields(sc: Scenario, out: Outcome) -> dict:
    """What the decision learns from, as the drives node passes it on in ``homeo/drives``."""
    acts = sc.action_names
    return {"action": _name(acts, out.action), "feedback": out.feedback, "proposal": _name(acts, out.proposal)}


# -- perception and action ---------------------------------------------------------------------
def drives_fields(sc: Scenario, perceived: tuple, world: dict, out: Outcome | None, after_action: tuple | None,
                  final: bool = False) -> dict:
    """``homeo/drives``: the perception of a tick (``robot.Perception.tick``), the world it was made
    in, and the outcome of the tick before (the decision learns from it)."""
    code, drives, inten, m_dom = perceived
    mot = sc.motivation_names
    f = {"drives": dict(zip(sc.drive_names, drives)), "stimuli": dict(zip(mot, map(float, sc.c.stim[code]))),
         "intensities": dict(zip(mot, inten)), "m_dom": sc.internal_states[m_dom],
         "intention": sc.intention_names[sc.c.intention_of[code]],
         "world": {k: world[k] for k in ("robot", "objects", "human")}}
    if after_action is not None:
        f["after_action"] = dict(zip(sc.drive_names, after_action))
    if out is not None:
        f["outcome"] = learned_fields(sc, out)
    if final:
        f["final"] = True
    return f


def perception_from_fields(sc: Scenario, d: dict) -> tuple:
    """``homeo/drives`` -> (perceived tuple, the outcome to learn from or None, after_action or None, final)."""
    mot = sc.motivation_names
    code = world_code(sc, d["world"], d["intention"])
    perceived = (code, tuple(d["drives"][n] for n in sc.drive_names), [d["intensities"][m] for m in mot],
                 sc.internal_states.index(d["m_dom"]))
    o = d.get("outcome")
    out = None
    if o is not None:
        acts = sc.action_names
        out = Outcome(_index(acts, o["action"]), o["feedback"], _index(acts, o["proposal"]), None)
    after = tuple(d["after_action"][n] for n in sc.drive_names) if "after_action" in d else None
    return perceived, out, after, bool(d.get("final"))


def action_fields(sc: Scenario, action: int | None, drives_msg: dict, tau: float, params: dict,
                  final: bool = False) -> dict:
    """``homeo/action``: the choice, and the drives it was made with (the world's metrics of the tick
    before need them: d(t) after the iteration)."""
    f = {"action": _name(sc.action_names, action), "m_dom": drives_msg["m_dom"], "tau": tau,
         "drives": drives_msg["drives"], "intention": drives_msg["intention"], "params": params}
    if "after_action" in drives_msg:
        f["after_action"] = drives_msg["after_action"]
    if final:
        f["final"] = True
    return f

"""The contract's payloads as JSON Schema (draft 2020-12), for tools that plot by field (Foxglove).

``schemas.py`` validates with code; this describes the same fields for a viewer: names from the
scenario's vocabulary become enums and map keys, so a Foxglove plot offers
``/homeo/drives.drives.<drive>`` by name. ``tests/test_live.py`` checks that every schema here
has exactly the fields of ``schemas.SCHEMAS`` plus the envelope.
"""

from __future__ import annotations

from .schemas import Vocabulary

NUM, INT, BOOL, STR, OBJ = {"type": "number"}, {"type": "integer"}, {"type": "boolean"}, {"type": "string"}, {"type": "object"}


def _enum(voc: Vocabulary, kind: str, nullable: bool = False) -> dict:
    names = list(voc.names(kind))
    return {"enum": names + [None]} if nullable else {"type": "string", "enum": names}


def _map(voc: Vocabulary, kind: str, value: dict, extra: bool = False) -> dict:
    return {"type": "object", "properties": {n: value for n in voc.names(kind)}, "additionalProperties": extra}


def _obj(props: dict, required=()) -> dict:
    return {"type": "object", "properties": props, "required": list(required), "additionalProperties": False}


def _world(voc: Vocabulary) -> dict:
    objects = _obj({o: _obj({var: {"enum": vals} for var, vals in vars_.items()}) for o, vars_ in voc.object_vars.items()})
    return {"robot": _obj({"location": _enum(voc, "locations")}), "objects": objects,
            "human": _obj({"presence": _enum(voc, "presences"), "relation": _enum(voc, "relations")})}


def fields(name: str, voc: Vocabulary) -> dict:
    """The properties of payload ``name`` (without the envelope)."""
    drive = {"type": "number", "minimum": 0, "maximum": 100}
    drives = _map(voc, "drives", drive)
    symbol = {"type": ["string", "null"]}
    table = {
        "homeo/world": dict(_world(voc), body=_map(voc, "drives", drive, extra=True), final=BOOL),
        "homeo/observation": {"intention": _enum(voc, "intentions", True), "gesture": symbol, "movement": symbol,
                              "keyword": symbol},
        "homeo/intention": {"intention": _enum(voc, "intentions"), "posterior": _map(voc, "intentions", NUM),
                            "mode": _enum(voc, "modes")},
        "homeo/drives": {"drives": drives, "stimuli": _map(voc, "motivations", NUM),
                         "intensities": _map(voc, "motivations", NUM), "m_dom": _enum(voc, "internal_states"),
                         "intention": _enum(voc, "intentions"), "world": _obj(_world(voc)), "after_action": drives,
                         "outcome": _obj({"action": _enum(voc, "actions", True), "feedback": {"enum": [-1, 0, 1]},
                                          "proposal": _enum(voc, "actions", True)}),
                         "final": BOOL},
        "homeo/action": {"action": _enum(voc, "actions", True), "m_dom": _enum(voc, "internal_states"), "tau": NUM,
                         "params": _obj({k: NUM for k in ("dod", "xi", "gamma")} | {"feedback": BOOL, "pseudo_update": BOOL}),
                         "drives": drives, "intention": _enum(voc, "intentions"), "after_action": drives, "final": BOOL},
        "homeo/outcome": {"action": _enum(voc, "actions", True), "feedback": {"enum": [-1, 0, 1]},
                          "proposal": _enum(voc, "actions", True), "clarified_intention": _enum(voc, "intentions", True),
                          "body": _map(voc, "drives", drive, extra=True),
                          "truth": _obj({"intention": _enum(voc, "intentions"), "expressed": BOOL, "satisfied": BOOL})},
        "homeo/device": {"device": STR, "command": STR, "action": _enum(voc, "actions", True)},
        "homeo/run_status": {"iterations": INT, "done": BOOL, "missed": INT, "state": STR,
                             "metrics": OBJ, "extra": OBJ},
        "homeo/human_input": {"intention": _enum(voc, "intentions", True), "feedback": {"enum": ["praise", "scold", None]},
                              "proposal": _enum(voc, "actions", True)},
    }
    return table[name]


def json_schema(name: str, voc: Vocabulary) -> dict:
    """The JSON Schema of a whole message of payload ``name`` (envelope included)."""
    props = {"schema": {"const": name}, "version": INT, "run": INT, "tick": INT, "stamp": NUM}
    props.update(fields(name, voc))
    return {"$schema": "https://json-schema.org/draft/2020-12/schema", "title": name, "type": "object",
            "properties": props, "required": ["schema", "version", "run", "tick", "stamp"]}

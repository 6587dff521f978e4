"""The contract's payloads as JSON Schema (draft 2020-12), for tools that plot by field (Foxglove).

Generated from ``schemas.SCHEMAS``, not restated: every check there carries the JSON Schema of what
it accepts (``check.json(voc)``). Names from the scenario's vocabulary become enums and map keys,
so a Foxglove plot offers ``/homeo/drives.drives.<drive>`` by name.
"""

from __future__ import annotations

from . import human_input
from .schemas import COUNT, ENVELOPE, SCHEMAS, STAMP, VERSION, Vocabulary, object_schema


def fields(name: str, voc: Vocabulary) -> dict:
    """The properties of payload ``name`` (without the envelope)."""
    return object_schema(SCHEMAS[name], voc)["properties"]


def json_schema(name: str, voc: Vocabulary) -> dict:
    """The JSON Schema of a whole message of payload ``name`` (envelope included; a person's input
    may leave it out). The signature (``auth.py``), appended after the fields, is not described."""
    payload = object_schema(SCHEMAS[name], voc)
    envelope = dict(zip(ENVELOPE, ({"const": name}, {"const": VERSION}, COUNT.json(voc), COUNT.json(voc),
                                   STAMP.json(voc))))
    required = ([] if name == human_input.SCHEMA else list(ENVELOPE)) + payload["required"]
    return {"$schema": "https://json-schema.org/draft/2020-12/schema", "title": name, "type": "object",
            "properties": envelope | payload["properties"], "required": required}

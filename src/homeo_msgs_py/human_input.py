"""A person's message on ``homeo/human_input``: hostile until decoded (no rclpy).

A person types it (``ros2 topic pub``, ``homeo-topic pub``, Foxglove's Publish panel), so the
envelope is optional: ``{"feedback": "scold", "proposal": "X"}`` is a whole message. If an
envelope is there it must be this schema's; its tick and run are not checked (a person does not
count ticks: an input answers the tick that is waiting). Unknown fields, unknown names and values
out of range are refused with a one-line reason (``Rejected``).
"""

from __future__ import annotations

from dataclasses import dataclass

from .schemas import ENVELOPE, SCHEMAS, VERSION, Rejected, Vocabulary, _fields, parse_json

SCHEMA = "homeo/human_input"
MAX_TEXT = 4096  # a person's message is a line
NONE_NAMES = (None, "none")


@dataclass(frozen=True)
class HumanInput:
    intention: str | None  # None: no wish (absent, null or "none")
    stated: bool  # the message said something about the wish (else it keeps what it was)
    feedback: int  # +1 praise, -1 scold, 0 none
    proposal: str | None


def decode_human_input(text, voc: Vocabulary) -> HumanInput:
    obj = parse_json(text, MAX_TEXT, " for a person's input")
    if not isinstance(obj, dict):
        raise Rejected(f"not a JSON object but {type(obj).__name__}")
    if "schema" in obj and obj["schema"] != SCHEMA:
        raise Rejected(f"schema {obj['schema']!r} on a topic that carries {SCHEMA!r}")
    if "version" in obj and obj["version"] != VERSION:
        raise Rejected(f"{SCHEMA} version {obj['version']!r} is not {VERSION}")
    body = {k: v for k, v in obj.items() if k not in ENVELOPE}
    f = _fields(body, SCHEMAS[SCHEMA], voc, "")
    if not f:
        raise Rejected("says nothing: give an intention, a feedback or a proposal")
    it = f.get("intention")
    if f.get("proposal") is not None and f.get("feedback", 0) == 1:
        raise Rejected("a proposal comes with a scold (or no feedback), not with praise")
    return HumanInput(None if it in NONE_NAMES else it, "intention" in f, f.get("feedback", 0), f.get("proposal"))

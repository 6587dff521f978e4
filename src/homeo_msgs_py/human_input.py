"""A person's message on ``homeo/human_input``: hostile until decoded (no rclpy).

A person types it (``ros2 topic pub``, ``homeo-topic pub``, Foxglove's Publish panel), so the
envelope is optional: ``{"feedback": "scold", "proposal": "X"}`` is a whole message. If an
envelope is there it must be this schema's; its tick and run are not checked (a person does not
count ticks: an input answers the tick that is waiting). Unknown fields, unknown names and values
out of range are refused with a one-line reason (``Rejected``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import msgspec

from .schemas import ANY, NOT_UNICODE, VERSION, Rejected, Vocabulary, const, short

SCHEMA = "homeo/human_input"
MAX_TEXT = 4096  # a person's message is a line
NONE_NAMES = (None, "none")
PRAISE_SCOLD = {"praise": 1, "scold": -1}
# the envelope a person may leave out: if there, it is this schema's; its run, tick and stamp are not
# checked (a person does not count ticks: an input answers the tick that is waiting)
ENVELOPE = {"schema": (const(Literal[SCHEMA]), False), "version": (const(Literal[VERSION]), False),
            **{k: (ANY, False) for k in ("run", "tick", "stamp")}}


@dataclass(frozen=True)
class HumanInput:
    intention: str | None  # None: no wish (absent, null or "none")
    stated: bool  # the message said something about the wish (else it keeps what it was)
    feedback: int  # +1 praise, -1 scold, 0 none
    proposal: str | None


def decode_human_input(text, voc: Vocabulary) -> HumanInput:
    if not isinstance(text, str):
        raise Rejected("not a string")
    if len(text) > MAX_TEXT:
        raise Rejected(f"message of {len(text)} characters is too long for a person's input")
    from .schemas import PAYLOADS

    t = voc.struct("person input", PAYLOADS[SCHEMA], ENVELOPE)
    try:
        f = msgspec.to_builtins(msgspec.json.decode(text, type=t))
    except msgspec.ValidationError as exc:
        raise Rejected(short(str(exc))) from None
    except msgspec.DecodeError as exc:
        raise Rejected(short(f"not JSON ({exc})")) from None
    except UnicodeEncodeError:
        raise Rejected(NOT_UNICODE) from None
    for k in ENVELOPE:
        f.pop(k, None)
    if not f:
        raise Rejected("says nothing: give an intention, a feedback or a proposal")
    it = f.get("intention")
    fb = PRAISE_SCOLD.get(f.get("feedback"), f.get("feedback") or 0)  # "praise", "scold", +1, -1; null or 0: none
    if f.get("proposal") is not None and fb == 1:
        raise Rejected("a proposal comes with a scold (or no feedback), not with praise")
    return HumanInput(None if it in NONE_NAMES else it, "intention" in f, fb, f.get("proposal"))

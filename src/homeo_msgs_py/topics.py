"""Topic names and which schema each carries (no rclpy: the launcher and tests read these too)."""

from __future__ import annotations

WORLD = "/homeo/world"
OBSERVATION = "/homeo/observation"
INTENTION = "/homeo/intention"
DRIVES = "/homeo/drives"
ACTION = "/homeo/action"
OUTCOME = "/homeo/outcome"
RUN_STATUS = "/homeo/run_status"
DIAGNOSTICS = "/diagnostics"

# topic -> (schema, kind); "state" topics are latched, "event" topics are not (see qos.py)
TOPICS: dict[str, tuple[str, str]] = {
    WORLD: ("homeo/world", "state"),
    OBSERVATION: ("homeo/observation", "event"),
    INTENTION: ("homeo/intention", "state"),
    DRIVES: ("homeo/drives", "state"),
    ACTION: ("homeo/action", "event"),
    OUTCOME: ("homeo/outcome", "event"),
    RUN_STATUS: ("homeo/run_status", "state"),
}

# node names of the simulated graph (the launcher waits for all of them)
SIM_NODES = ("homeo_sim", "homeo_intention", "homeo_drives", "homeo_decision")


def schema_of(topic: str) -> str:
    try:
        return TOPICS[topic][0]
    except KeyError:
        raise KeyError(f"{topic} is not a homeo topic; known: {', '.join(TOPICS)}") from None

"""The bridge node's checkpoint (no rclpy), in ``homeo_decision.checkpoint``'s envelope (node
``pepper_bridge``). The world lives on the robot, which goes on by itself while the bridge is down;
what the bridge needs to go on with the run is its lockstep position (run, tick, missed, the last
outcome sent), the interaction log the launcher prints, and the run's configuration (the number of
interactions, the scenario's fingerprint). A restarted bridge reconnects to the robot, restores
these and goes on after the newest tick the robot nodes answered (``homeo_msgs_py.world_rejoin``).
"""

from __future__ import annotations

from homeo_decision.checkpoint import CheckpointError, check_int, check_world_position, envelope, scenario_print
from homeo_decision.codec import vocabulary

from .environment import MAX_LOG_ROWS

NODE = "pepper_bridge"
ROW_STR = ("m_dom", "intention", "proposal", "reason", "cue_intention")  # what the launcher prints: text or null


def run_config(sc, interactions: int) -> dict:
    return {"interactions": int(interactions), "scenario": scenario_print(sc)}


def bridge_checkpoint(side, position: dict, config: dict, session: str = "") -> dict:
    state = {"log": list(side.log), "interactions_done": side.env.tick, "position": position}
    return envelope(NODE, position["tick"], 0, position["run"], config, None, state, session)


def _check_rows(rows, sc) -> list:
    if not isinstance(rows, list) or len(rows) > MAX_LOG_ROWS:
        raise CheckpointError(f"log must be a list of at most {MAX_LOG_ROWS} rows")
    actions = set(sc.action_names)
    for r in rows:
        if not isinstance(r, dict):
            raise CheckpointError("a log row that is not an object")
        check_int(r.get("interaction"), "a log row's interaction", 1, 10**9)
        if r.get("action") is not None and r.get("action") not in actions:
            raise CheckpointError(f"a log row's action {str(r.get('action'))[:40]!r} is not the scenario's")
        if type(r.get("ok")) is not bool or type(r.get("missed")) is not bool or r.get("feedback") not in (-1, 0, 1) \
                or type(r.get("feedback")) is not int:
            raise CheckpointError("a log row's ok, missed or feedback is malformed")
        if any(r.get(k) is not None and not isinstance(r.get(k), str) for k in ROW_STR):
            raise CheckpointError(f"a log row's {', '.join(ROW_STR)} must be text or null")
    return rows


def restore_bridge(side, ck: dict, ours: dict, where: str = "<memory>") -> tuple[dict, dict]:
    """Put the checkpoint's log into ``side`` (``world_side.PepperWorldSide``); returns (the run's
    configuration, the driver's position). Everything is checked first."""
    sc, st, p = side.sc, ck["state"], ck["params"]
    try:
        if p.get("scenario") != ours["scenario"]:
            raise CheckpointError("a checkpoint of another scenario")
        cfg = {"interactions": check_int(p.get("interactions"), "interactions", 0, 10**9)}
        rows = _check_rows(st.get("log"), sc)
        done = check_int(st.get("interactions_done"), "interactions_done", 0, 10**9)
    except CheckpointError as exc:
        raise CheckpointError(f"{where}: corrupt checkpoint ({exc})") from None
    pos = check_world_position(st.get("position"), sc, vocabulary(sc), where, done)
    if pos["run"] != ck["run"] or pos["tick"] != ck["ticks"]:
        raise CheckpointError(f"{where}: corrupt checkpoint (the envelope's run and ticks are not the position's)")
    side.log = list(rows)
    side.env.tick = done
    return cfg, pos

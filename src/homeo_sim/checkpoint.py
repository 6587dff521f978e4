"""The simulation node's checkpoint (no rclpy): what the world needs to go on with a run after its
process died, in ``homeo_decision.checkpoint``'s envelope (node ``homeo_sim``, written atomically
by the same ``Checkpointer``).

    params  the run's configuration: seed, iterations, rate, action_timeout, intention_accuracy,
            human, the scenario's fingerprint, how its world codes are numbered (``world_codes``: a
            checkpoint of another numbering is refused), and how many bytes of the trace file belong to it
    rng     the human's two streams ("human", "observation"): a restart continues them exactly
    state   env (world code, body, human, the cues of the current observation), metrics (the
            recorder's running sums), accuracy (the recognition hits kept), pending (the truth of
            the tick whose drives have not come back yet), position (the lockstep driver's run,
            tick, missed ticks, elapsed time, the last outcome sent)

``ticks`` is the driver's tick: the ticks stepped in this run. Restoring checks everything before
it changes anything, and a checkpoint of another scenario, human or recognition setting is refused.
"""

from __future__ import annotations

from homeo_decision.checkpoint import CheckpointError, check_codes, check_int as _int, check_number as _num
from homeo_decision.checkpoint import check_world_position as check_position
from homeo_decision.checkpoint import codes_print, envelope, scenario_print
from homeo_decision.codec import vocabulary

NODE = "homeo_sim"
CONFIG_CHECKED = ("scenario", "human", "intention_accuracy")  # a restart must be the same kind of run


def run_config(sc, *, seed: int, iterations: int, rate: float, action_timeout: float, intention_accuracy: bool,
               human: str, trace_bytes: int | None = None) -> dict:
    return {"seed": int(seed), "iterations": int(iterations), "rate": float(rate),
            "action_timeout": float(action_timeout), "intention_accuracy": bool(intention_accuracy),
            "human": human, "scenario": scenario_print(sc), "world_codes": codes_print(sc), "trace_bytes": trace_bytes}


def world_checkpoint(side, position: dict, config: dict, session: str = "") -> dict:
    env = side.env.state()
    h = env["human"]
    rng = {"human": h.pop("rng"), "observation": h.pop("obs_rng")}
    state = {"env": env, "metrics": side.rec.state(), "accuracy": side.hits.state(), "pending": side.pending_truth,
             "position": position}
    return envelope(NODE, position["tick"], 0, position["run"], config, rng, state, session)


def check_config(p: dict, ours: dict, where: str) -> dict:
    """The checkpoint's run configuration, checked; refused when it is of another kind of run."""
    check_codes(p.get("world_codes"), ours["world_codes"], where)
    try:
        for key in CONFIG_CHECKED:
            if p.get(key) != ours[key]:
                raise CheckpointError(f"a checkpoint of another run ({key} {str(p.get(key))[:40]!r}, this node's "
                                      f"{ours[key]!r})")
        tb = p.get("trace_bytes")
        return {"seed": _int(p.get("seed"), "seed", 0, 2**31 - 1),
                "iterations": _int(p.get("iterations"), "iterations", 0, 10**9),
                "rate": _num(p.get("rate"), "rate", 0.0, 1000.0),
                "action_timeout": _num(p.get("action_timeout"), "action_timeout", 0.01, 3600.0),
                "trace_bytes": None if tb is None else _int(tb, "trace_bytes")}
    except CheckpointError as exc:
        raise CheckpointError(f"{where}: corrupt checkpoint (params: {exc})") from None


def restore_world(side, ck: dict, ours: dict, where: str = "<memory>") -> tuple[dict, dict]:
    """Put the checkpoint's environment, streams, metrics and accuracy into ``side``
    (``world_side.SimWorldSide``); returns (its run configuration, the driver's position). Everything
    is checked first: a bad file leaves ``side`` as it was."""
    sc, st = side.sc, ck["state"]
    cfg = check_config(ck["params"], ours, where)
    env = st.get("env")
    rng = ck.get("rng")
    pending = st.get("pending")
    try:
        if not isinstance(env, dict) or not isinstance(env.get("human"), dict) or not isinstance(rng, dict):
            raise ValueError("env, env.human and rng must be objects")
        if pending is not None and not (isinstance(pending, list) and len(pending) == 2
                                        and all(type(x) is bool for x in pending)):
            raise ValueError("pending must be null or [expressed, satisfied]")
        pos = check_position(st.get("position"), sc, vocabulary(sc), where, env.get("tick"))
        if pos["run"] != ck["run"] or pos["tick"] != ck["ticks"]:
            raise ValueError("the envelope's run and ticks are not the position's")
        env = dict(env, human=dict(env["human"], rng=rng.get("human"), obs_rng=rng.get("observation")))
        # each part is checked on a scratch copy first, so a failure in a later one changes nothing
        from .metrics import AccuracyEnds, MetricRecorder

        rec = MetricRecorder(side.rec.drive_names, side.rec.thresholds)
        rec.set_state(st.get("metrics"))
        hits = AccuracyEnds(side.hits.window)
        hits.set_state(st.get("accuracy"))
        side.env.set_state(env)  # last: it checks everything before it changes anything
    except CheckpointError:
        raise
    except ValueError as exc:
        raise CheckpointError(f"{where}: corrupt checkpoint ({str(exc)[:200]})") from None
    side.rec, side.hits = rec, hits
    side.set_pending_truth(pending)
    return cfg, pos

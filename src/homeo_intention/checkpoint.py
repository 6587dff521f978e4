"""The intention node's checkpoint (``homeo_decision.checkpoint``'s envelope): the Bayesian model
(CPDs and every count seen, ``model_io``), its settings and the ticks learned. The recogniser
draws no random numbers, so ``rng`` is null."""

from __future__ import annotations

from homeo_decision.checkpoint import CheckpointError, envelope

from . import model_io

NODE = "homeo_intention"


def intention_checkpoint(model, ticks: int, tick_offset: int, run: int, mode: str, session: str = "") -> dict:
    params = {"mode": mode, "threshold": model.threshold, "prior_strength": model.strength}
    return envelope(NODE, ticks, tick_offset, run, params, None, model_io.to_dict(model), session)


def intention_learned(model) -> dict:
    return {"cpds": model.cpds(), "counts": model_io.to_dict(model)["counts"]}


def restore_intention(model, ck: dict, mode: str, where: str = "<memory>") -> None:
    if ck["params"].get("mode") != mode:
        raise CheckpointError(f"{where}: a checkpoint of the {ck['params'].get('mode')!r} recogniser, not {mode!r}")
    try:
        model_io.from_dict(model, ck["state"], where)  # checks everything before it changes the model
    except model_io.IntentionModelError as exc:
        raise CheckpointError(str(exc)) from None

"""The command-line options of checkpoints, resume and supervision (sim and pepper), and their checks."""

from __future__ import annotations

import os

from homeo_msgs_py.cli_args import UserError, int_at_least

CHECKPOINT_ROOT = "checkpoints"  # under --data-dir


def add_durable_options(p, graph: str) -> None:
    g = p.add_argument_group("checkpoints and restarts")
    g.add_argument("--checkpoint-dir", metavar="DIR", default=None,
                   help=f"write the robot nodes' learned state here every --checkpoint-every ticks and at the end "
                        f"(inside --data-dir; default: DATA_DIR/{CHECKPOINT_ROOT}/NAMESPACE or {graph}, or the --resume "
                        f"folder)")
    g.add_argument("--checkpoint-every", metavar="N", type=int_at_least(1), default=100,
                   help="ticks between checkpoints (default 100)")
    g.add_argument("--no-checkpoints", action="store_true", help="write no checkpoints (a restarted node starts fresh)")
    g.add_argument("--resume", metavar="DIR", default=None,
                   help="continue from the checkpoints in DIR: the Q-table, the intention model, the random "
                        "streams, and the learning schedule from the ticks learned")
    g.add_argument("--max-restarts", metavar="N", type=int_at_least(0), default=3,
                   help="restart a robot node that dies up to N times (default 3; 0: a death stops the graph)")


def durable_options(a, graph: str, sc, bayes: bool) -> dict:
    """SimOptions fields from the arguments; a resume folder that cannot be used is a UserError."""
    if a.no_checkpoints and a.checkpoint_dir:
        raise UserError("--checkpoint-dir and --no-checkpoints contradict each other")
    from homeo_msgs_py.data_dir import options_inside

    options_inside(a.data_dir, [("--checkpoint-dir", a.checkpoint_dir), ("--resume", a.resume)])
    if a.resume and getattr(a, "load_q", None):
        raise UserError("--resume and --load-q: the checkpoint holds the Q-table; give one of them")
    if a.resume:
        check_resume(a.resume, sc, bayes)
    if a.no_checkpoints:
        ck_dir = ""
    else:
        ns = (getattr(a, "namespace", "") or "").strip("/").replace("/", "_")
        ck_dir = a.checkpoint_dir or a.resume or os.path.join(a.data_dir, CHECKPOINT_ROOT, ns or graph)
        if os.path.exists(ck_dir) and not os.path.isdir(ck_dir):
            raise UserError(f"--checkpoint-dir {ck_dir}: not a directory")
    return {"checkpoint_dir": ck_dir, "checkpoint_every": a.checkpoint_every, "resume": a.resume,
            "max_restarts": a.max_restarts}


def check_resume(d: str, sc, bayes: bool) -> None:
    """Every checkpoint a resumed run needs is there and loads into this scenario (one-line errors
    here, not in the nodes)."""
    from homeo_decision import checkpoint
    from homeo_decision.agent import DecisionCore

    if not os.path.isdir(d):
        raise UserError(f"--resume {d}: no such directory")
    try:
        ck = checkpoint.load(checkpoint.path_for(d, "homeo_decision"), "homeo_decision")
        checkpoint.restore_decision(DecisionCore(sc, 0), ck, str(checkpoint.path_for(d, "homeo_decision")))
        if bayes:
            from homeo_intention.checkpoint import restore_intention
            from homeo_intention.model import IntentionModel

            p = checkpoint.path_for(d, "homeo_intention")
            restore_intention(IntentionModel(sc), checkpoint.load(p, "homeo_intention"), "bayes", str(p))
    except checkpoint.CheckpointError as exc:
        raise UserError(f"--resume: {exc}") from None

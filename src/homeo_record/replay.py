"""``homeo-replay``: a recorded run (``homeo-launch sim --record DIR``) from its bag alone.

    homeo-replay DIR [--json] [--log] [--plots DIR]
    homeo-replay DIR --policy Q_TABLE [--dod X] [--xi X] [--json]

``--json`` prints exactly what the run's ``--json`` printed (the final run status carries the
metrics); without it, the metrics table and a summary of the interaction. ``--log`` adds the
interaction, one line per tick (what the human wanted, what the robot recognised and did, the
human's answer). ``--plots DIR`` draws the drives, CDA/CEDA and HSR/RSR over time (as Figs
4.1-4.2). ``--policy`` judges a Q-table on the recorded session, offline: it sees each recorded
perception (``homeo/drives``) and is scored on the robot's recorded choice (``policy_eval.py``).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from homeo_msgs_py.cli_args import Parser, UserError, run_command
from homeo_msgs_py.learning import BY_NAME, add_learning_flags, learning_values

from .bag import BagError, RecordedRun, load_run
from .policy_eval import POLICY_LEARNING

PROG = "homeo-replay"


def interaction_log(run: RecordedRun) -> list[dict]:
    """One row per tick: the human's truth, the recognised intention, m_dom, the action, the answer."""
    drives, actions, outcomes = run.by_tick("drives"), run.by_tick("action"), run.by_tick("outcome")
    rows = []
    for k in sorted(outcomes):
        o, d, a = outcomes[k], drives.get(k, {}), actions.get(k, {})
        truth = o.get("truth") or {}
        rows.append({"tick": k, "intention": truth.get("intention"), "recognised": a.get("intention", d.get("intention")),
                     "m_dom": d.get("m_dom"), "action": o["action"], "feedback": o["feedback"],
                     "proposal": o["proposal"], "satisfied": truth.get("satisfied")})
    return rows


def world_result(run: RecordedRun) -> tuple:
    """The world's result as the run printed it (``WorldBackend.result`` of the recorded final run status),
    the world found by its name in the registry; ``(class, setting, result)``."""
    from homeo_decision.world_api import world_class

    info = run.info
    cls = world_class(info["graph"])
    setting = {"seed": info["seed"], "iterations": info["iterations"], "learning": {}, "values": {},
               "intention": info.get("intention") or next(iter(cls.INTENTIONS.values())), "interrupted": False}
    out = cls.result(run.sc, run.final_status(), setting)
    if out is None:
        raise BagError(f"{run.path}: the recorded run has no result yet")
    return cls, setting, out


def _log_line(r: dict) -> str:
    fb = {1: "praise", -1: "scold", 0: "-"}[r["feedback"]]
    prop = f" proposes {r['proposal']}" if r["proposal"] else ""
    return (f"{r['tick']:6d}  wants {r['intention'] or '-':<10} seen {r['recognised'] or '-':<10} "
            f"{r['m_dom'] or '-':<11} -> {r['action'] or '(none)':<9} {fb}{prop}")


def series(run: RecordedRun):
    """The metrics' per-tick inputs as recorded: d(t) after tick t came back with action t+1 (final
    included), the human's truth with outcome t; ``metrics.cumulative_series`` of them."""
    import numpy as np

    from homeo_sim.metrics import cumulative_series

    sc = run.sc
    key = "after_action" if sc.open.metrics_sample == "after_action" else "drives"
    acts = run.by_tick("action")
    acts.update(run.by_tick("action", final=True))
    outs = run.by_tick("outcome")
    ticks = [k for k in sorted(outs) if (acts.get(k + 1) or {}).get(key) is not None]
    if not ticks:
        raise BagError(f"{run.path}: no complete tick to plot")
    d = np.array([[acts[k + 1][key][n] for n in sc.drive_names] for k in ticks], dtype=float)
    e = np.array([outs[k].get("truth", {}).get("expressed", False) for k in ticks], dtype=bool)
    s = np.array([outs[k].get("truth", {}).get("satisfied", False) for k in ticks], dtype=bool)
    return np.array(ticks), cumulative_series(d, e, s, sc.drive_names, [x.threshold for x in sc.drives])


def plots(run: RecordedRun, out: Path) -> list[Path]:
    """Fig 4.1-like (drives, CDA, CEDA over time) and Fig 4.2-like (HSR, RSR over time)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t, s = series(run)
    names, thr = run.sc.drive_names, {x.name: x.threshold for x in run.sc.drives}
    files = []
    fig, axes = plt.subplots(3, 1, figsize=(9, 9), sharex=True)
    for n in names:
        line, = axes[0].plot(t, s["drives"][n], lw=0.8, label=n)
        axes[0].axhline(thr[n], color=line.get_color(), ls=":", lw=0.8)
        axes[1].plot(t, s["CDA"][n], label=n)
        axes[2].plot(t, s["CEDA"][n], label=n)
    for ax, title in zip(axes, ("drives (dotted: thresholds)", "CDA (Eq 4.2)", "CEDA (Eq 4.4)")):
        ax.set_title(title)
        ax.legend(loc="upper right", fontsize=8)
    axes[2].set_xlabel("tick")
    fig.tight_layout()
    files.append(out / "drives.png")
    fig.savefig(files[-1], dpi=110)
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(9, 4))
    ax.plot(t, s["HSR"], label="HSR (Eq 4.1)")
    ax.plot(t, s["RSR"], label="RSR (Eq 4.6)")
    ax.set_ylim(0, 1.02)
    ax.set_xlabel("tick")
    ax.legend()
    fig.tight_layout()
    files.append(out / "hsr_rsr.png")
    fig.savefig(files[-1], dpi=110)
    plt.close(fig)
    return files


def build_parser() -> argparse.ArgumentParser:
    ap = Parser(prog=PROG, description="A recorded run (homeo-launch sim --record DIR) from its bag alone.")
    ap.add_argument("bag", metavar="DIR", help="the bag folder (metadata.yaml and MCAP storage)")
    ap.add_argument("--json", action="store_true", help="print exactly the JSON the run printed with --json")
    ap.add_argument("--log", action="store_true", help="print the interaction, one line per tick")
    ap.add_argument("--plots", metavar="DIR", help="draw drives, CDA/CEDA and HSR/RSR over time here")
    ap.add_argument("--policy", metavar="Q_TABLE", help="judge this Q-table on the recorded perceptions")
    add_learning_flags(ap, POLICY_LEARNING, help_extra=" for --policy (default: the recorded scenario's)")
    return ap


def run_cli(a) -> int:
    given = learning_values(a, POLICY_LEARNING)
    if given and not a.policy:
        raise UserError(f"{BY_NAME[next(iter(given))].flag} needs --policy")
    if a.json and a.log:
        raise UserError("--log prints text: use it without --json")
    if a.plots and Path(a.plots).exists() and not Path(a.plots).is_dir():
        raise UserError(f"--plots {a.plots}: exists and is not a directory")
    if a.policy and not os.path.isfile(a.policy):
        raise UserError(f"Q-table file not found: {a.policy}")
    run = load_run(a.bag)
    if a.policy:
        from .policy_eval import evaluate, format_eval

        res = evaluate(run, a.policy, given)
        print(json.dumps(res) if a.json else format_eval(res))
        return 0
    from homeo_decision.world_api import WorldConfigError
    from homeo_msgs_py.schemas import finite

    try:
        cls, setting, out = world_result(run)
    except WorldConfigError as exc:
        raise BagError(f"{a.bag}: {exc}") from None
    if a.json:
        print(json.dumps(finite(out)))
    else:
        print(cls.result_text(run.sc, out, setting))
        rows = interaction_log(run)
        fb = [r["feedback"] for r in rows]
        print(f"interaction: {len(rows)} ticks, {sum(r['intention'] not in (None, 'none') for r in rows)} with a wish, "
              f"{fb.count(1)} praised, {fb.count(-1)} scolded, {sum(r['proposal'] is not None for r in rows)} proposals"
              + (f"; {sum(run.rejected.values())} undecodable messages skipped" if run.rejected else ""))
        if a.log:
            for r in rows:
                print(_log_line(r))
    if a.plots:
        out_dir = Path(a.plots)
        out_dir.mkdir(parents=True, exist_ok=True)
        for f in plots(run, out_dir):
            print(f"{PROG}: wrote {f}", file=sys.stderr)
    return 0


def main(argv=None) -> int:
    from homeo_decision.qtable_io import QTableError
    from homeo_decision.scenario import ScenarioError

    return run_command(PROG, lambda: run_cli(build_parser().parse_args(argv)), (BagError, QTableError, ScenarioError))


if __name__ == "__main__":
    sys.exit(main())

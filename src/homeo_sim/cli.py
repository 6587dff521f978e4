"""``homeo-sim``: the in-process thesis simulation, its metrics, and its benchmark.

    homeo-sim run [--iterations N] [--seed S | --seeds K [--first-seed N]] [--dod X] [--xi X]
                  [--pseudo-update BOOL | --no-pseudo]
                  [--policy {objectq,random,rule,flatq,nofeedback}] [--adaptive-dod]
                  [--scenario FILE] [--set KEY=VALUE ...] [--save-q FILE] [--load-q FILE]
                  [--trace FILE] [--json] [--workers W | --cluster ADDRESS] [--out DIR] [--quiet]
                  [--intention {oracle,bayes}] [--save-intention FILE] [--load-intention FILE]
    homeo-sim sweep {xi,dod,pseudo} [--seeds K] [--first-seed N] [--iterations N] [--out DIR] [--json]
                    [--workers W | --cluster ADDRESS] [--quiet]
    homeo-sim report --out DIR [--seeds K] [--first-seed N] [--iterations N] [--workers W | --cluster ADDRESS] [--quiet]
    homeo-sim bench [--intention {oracle,bayes}] [--json]

With --out DIR, each finished run is kept in DIR/runs as it finishes; the same command again (after
Ctrl-C, or a driver that died) runs only the missing runs. --cluster runs them as Ray tasks (homeo_sim.cluster).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from dataclasses import replace
from pathlib import Path

from homeo_decision.qtable_io import QTableError
from homeo_intention.model_io import IntentionModelError
from homeo_decision.scenario import ScenarioError

from homeo_decision.baselines import POLICIES

from homeo_decision.scenario.reference import DOD_SWEEP, PSEUDO_SWEEP, SWEEP_NAMES, XI_SWEEP
from homeo_msgs_py.cli_args import Parser, UserError, int_at_least, run_command, setting
from homeo_msgs_py.graph import BAYES, INTENTION_MODES, ORACLE
from homeo_msgs_py.learning import add_learning_flags, add_no_pseudo_flag, learning_values

from .parallel import Pool, add_cluster_argument
from .runner import RUN_LEARNING, RunConfig, build_scenario, run_episode, run_seeds
from .stats import aggregate, describe, json_safe
from .sweep import progress_bar

PROG = "homeo-sim"


def add_run_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--iterations", type=int_at_least(1), default=5000, help="iterations per run (default 5000)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--seed", type=int_at_least(0), default=None, help="one run with this seed (default 0)")
    g.add_argument("--seeds", type=int_at_least(1), default=None, help="runs with seeds 0..K-1 on all cores")
    add_first_seed(p)
    add_learning_flags(p, RUN_LEARNING, help_extra=" (default: the scenario's)")
    add_no_pseudo_flag(p)
    add_common_arguments(p)
    p.add_argument("--json", action="store_true", help="print one JSON object instead of a table")


def add_first_seed(p: argparse.ArgumentParser) -> None:
    # seeds used to choose (a calibration) can then be kept apart from seeds used to confirm
    p.add_argument("--first-seed", type=int_at_least(0), default=0, metavar="N",
                   help="with --seeds K: seeds N..N+K-1 instead of 0..K-1 (default 0)")


def seed_range(first: int, k: int) -> list[int]:
    return list(range(first, first + k))


def add_common_arguments(p: argparse.ArgumentParser) -> None:
    """Scenario, open-choice overrides, worker count and progress: shared by run, sweep and report."""
    p.add_argument("--scenario", metavar="FILE", default=None, help="scenario JSON (default: the thesis scenario)")
    p.add_argument("--set", metavar="KEY=VALUE", type=setting, action="append", default=[],
                   help="override an open choice of the scenario, e.g. --set human_no_intention_prob=0.5")
    p.add_argument("--workers", type=int_at_least(1), default=None, help="processes (default: all cores)")
    add_cluster_argument(p)
    p.add_argument("--quiet", action="store_true", help="no progress bar")


def pool(args, out_dir: Path | None) -> Pool:
    """Where the runs go: the local processes or the cluster; kept in ``out_dir``/runs."""
    return Pool(args.workers, args.cluster, out_dir / "runs" if out_dir is not None else None)


def build_parser() -> argparse.ArgumentParser:
    ap = Parser(prog=PROG, description="Homeostatic Object-Q robot: the thesis simulation (Section 4.2).")
    sub = ap.add_subparsers(dest="cmd", required=True, parser_class=Parser)
    run = sub.add_parser("run", help="run the simulation and print Table 4.5's metrics")
    add_run_arguments(run)
    run.add_argument("--out", metavar="DIR", help="keep each finished run in DIR/runs (the same command again "
                                                  "runs only the missing ones)")
    run.add_argument("--save-q", metavar="FILE", help="save the learned Q-table (with --seeds: FILE per seed)")
    run.add_argument("--load-q", metavar="FILE", help="start from a saved Q-table")
    run.add_argument("--trace", metavar="FILE", help="write one JSON line per iteration (with --seeds: FILE per seed)")
    run.add_argument("--policy", choices=POLICIES, default="objectq",
                     help="decision maker: the thesis's Object-Q (default) or a baseline (docs/EXPERIMENTS.md)")
    run.add_argument("--adaptive-dod", action="store_true",
                     help="adjust DoD online from the user's and the robot's satisfaction (docs/EXPERIMENTS.md)")
    run.add_argument("--intention", choices=INTENTION_MODES, default=ORACLE,
                     help="oracle: the robot observes the intention (the thesis's simulation, default); "
                          "bayes: it recognises it with the Bayesian network of Sec 2.3 (docs/INTENTION.md)")
    run.add_argument("--save-intention", metavar="FILE",
                     help="bayes: save the learned intention model (with --seeds: FILE per seed)")
    run.add_argument("--load-intention", metavar="FILE", help="bayes: start from a saved intention model")
    sw = sub.add_parser("sweep", help="sweep xi (Fig 4.3), DoD (Fig 4.5) or the pseudo update (Fig 4.4)")
    sw.add_argument("param", choices=SWEEP_NAMES, help="the parameter to sweep")
    sw.add_argument("--seeds", type=int_at_least(1), default=10, help="seeds 0..K-1 per point (default 10)")
    add_first_seed(sw)
    sw.add_argument("--iterations", type=int_at_least(1), default=5000, help="iterations per run (default 5000)")
    sw.add_argument("--out", metavar="DIR", help="also write sweep-PARAM.json and the figure into DIR")
    add_common_arguments(sw)
    sw.add_argument("--json", action="store_true", help='print {"param", "points": [{"value", "metrics"}]}')
    rp = sub.add_parser("report", help="every table and figure of Section 4.2, baselines and adaptive DoD")
    rp.add_argument("--out", metavar="DIR", required=True, help="directory for the PNGs, report.md and results.json")
    rp.add_argument("--seeds", type=int_at_least(2), default=10, help="seeds 0..K-1 per configuration (default 10)")
    add_first_seed(rp)
    rp.add_argument("--iterations", type=int_at_least(10), default=5000, help="iterations per run (default 5000)")
    add_common_arguments(rp)
    b = sub.add_parser("bench", help="iterations per second (one core) and the 20-seed wall time")
    b.add_argument("--iterations", type=int_at_least(100), default=20000, help="iterations of the single-core run")
    b.add_argument("--intention", choices=INTENTION_MODES, default=ORACLE,
                   help="bayes: also time the recogniser (one recognition, its share of learning) and the "
                        "bayes-mode iteration against the oracle one")
    b.add_argument("--json", action="store_true")
    return ap


def config_from_args(args) -> tuple[RunConfig, list[int]]:
    first = getattr(args, "first_seed", 0)
    if first and args.seed is not None:
        raise UserError("--first-seed goes with --seeds K (seeds N..N+K-1); for one run use --seed alone")
    seeds = seed_range(first, args.seeds) if args.seeds else [args.seed if args.seed is not None else first]
    cfg = RunConfig(
        iterations=args.iterations, seed=seeds[0], **learning_values(args, RUN_LEARNING),
        scenario=args.scenario, overrides=tuple(args.set),
        load_q=getattr(args, "load_q", None), save_q=getattr(args, "save_q", None), trace=getattr(args, "trace", None),
        policy=getattr(args, "policy", "objectq"), adaptive_dod=getattr(args, "adaptive_dod", False),
        intention=getattr(args, "intention", ORACLE), load_intention=getattr(args, "load_intention", None),
        save_intention=getattr(args, "save_intention", None))
    if cfg.intention != BAYES and (cfg.load_intention or cfg.save_intention):
        raise UserError(f"{'--save-intention' if cfg.save_intention else '--load-intention'} needs --intention bayes")
    if cfg.adaptive_dod and cfg.policy not in ("objectq", "nofeedback"):
        raise UserError(f"--adaptive-dod needs --policy objectq or nofeedback (a DoD-weighted Object-Q robot), not {cfg.policy}")
    if (cfg.save_q or cfg.load_q) and cfg.policy not in ("objectq", "nofeedback"):
        raise UserError(f"{'--save-q' if cfg.save_q else '--load-q'}: policy {cfg.policy} has no Object-Q table to save or load")
    return cfg, seeds


def _per_seed_path(path: str | None, seed: int, many: bool) -> str | None:
    if path is None or not many:
        return path
    p = Path(path)
    return str(p.with_name(f"{p.stem}.seed{seed}{p.suffix}"))


def cmd_run(args) -> int:
    cfg, seeds = config_from_args(args)
    sc = build_scenario(cfg)  # validates the scenario before any worker starts
    for f, what in ((cfg.load_q, "Q-table"), (cfg.load_intention, "intention model")):
        if f and not Path(f).is_file():
            raise UserError(f"{what} file not found: {f}")
    if cfg.policy == "rule" and sc.rule_policy is None:
        raise UserError(f"--policy rule: scenario {sc.source} has no 'rule_policy' block (docs/EXPERIMENTS.md)")
    if cfg.intention == BAYES and sc.observations is None:
        raise UserError(f"--intention bayes: scenario {sc.source} has no 'observations' block (docs/INTENTION.md)")
    if cfg.load_intention:
        from homeo_intention.model import IntentionModel

        IntentionModel(sc).load(cfg.load_intention)  # a bad file fails here, in one line, not in a worker
    many = len(seeds) > 1
    results = []
    files = cfg.trace or cfg.save_q or cfg.load_q or cfg.save_intention or cfg.load_intention
    if files and (args.cluster or args.out):
        raise UserError(f"{'--cluster' if args.cluster else '--out'}: runs that read or write files (--trace, --save-q, "
                        "--load-q, --save-intention, --load-intention) run here, one after the other")
    if (many or args.cluster or args.out) and not (cfg.trace or cfg.save_q or cfg.load_q or cfg.save_intention):
        with progress_bar(len(seeds), args.quiet, unit="seed") as bar:
            results = run_seeds(cfg, seeds, pool(args, _out_dir(args.out) if args.out else None), bar)
    else:
        with progress_bar(len(seeds) * cfg.iterations, args.quiet, unit="it") as bar:
            step = max(1, cfg.iterations // 100)
            tick = lambda t: bar.update(step) if t % step == step - 1 else None  # noqa: E731
            for s in seeds:
                c = replace(cfg, seed=s, trace=_per_seed_path(cfg.trace, s, many), save_q=_per_seed_path(cfg.save_q, s, many),
                            save_intention=_per_seed_path(cfg.save_intention, s, many))
                r = run_episode(c, sc, on_tick=None if args.quiet else tick)
                if r.load_report is not None and not args.json:
                    lr = r.load_report
                    msg = f"loaded Q-table: {', '.join(lr.loaded)}"
                    if lr.new:
                        msg += f"; new objects start fresh: {', '.join(lr.new)}"
                    if lr.dropped:
                        msg += f"; dropped objects not in this scenario: {', '.join(lr.dropped)}"
                    print(msg, file=sys.stderr)
                results.append(r)
    out = run_output(cfg.iterations, seeds, [r.metrics for r in results], sc.drive_names)
    if args.json:
        print(json.dumps(json_safe(out)))
    else:
        print(format_table(out, sc.drive_names, sc.name, sc.reference.metrics if sc.reference else None))
    return 0


def run_output(iterations: int, seeds: list, per_seed: list[dict], drive_names) -> dict:
    """The JSON of ``run`` (and of ``homeo-launch sim``): the metrics over seeds and, when the
    intention was recognised, the recognition accuracy at both ends of the run."""
    out = {"iterations": iterations, "seeds": seeds, "metrics": aggregate(per_seed, drive_names)}
    if per_seed and "intention_accuracy" in per_seed[0]:
        # fraction of ticks whose recognised intention is the human's true one (docs/INTENTION.md)
        out["intention_accuracy"] = {k: describe([m["intention_accuracy"][k] for m in per_seed])
                                     for k in per_seed[0]["intention_accuracy"]}
    return out


def format_table(out: dict, drive_names, scenario_name: str, reference: dict | None = None) -> str:
    """The metrics as text, with a column of published values when the scenario has a reference block."""
    m = out["metrics"]
    ref_of = lambda key, dn=None: (reference.get(key) if dn is None else reference.get(key, {}).get(dn)) if reference else None  # noqa: E731
    col = lambda v: f"  {'' if v is None else f'{v:7.2f}':>7}" if reference else ""  # noqa: E731
    n = len(out["seeds"])
    lines = [f"scenario {scenario_name}: {out['iterations']} iterations x {n} seed{'s' if n > 1 else ''}"
             + ("  (mean [95% interval])" if n > 1 else "")]

    def cell(d):
        if n > 1:
            return f"{d['mean']:7.3f} [{d['ci95'][0]:7.3f}, {d['ci95'][1]:7.3f}]"
        return f"{d['mean']:7.3f}"

    w = 28 if n > 1 else 8
    lines.append(f"{'metric':<10}{'drive':<6} {'ours':>{w}}" + (f"  {'thesis':>7}" if reference else ""))
    for key in ("HSR", "RSR"):
        lines.append(f"{key:<10}{'':<6} {cell(m[key]):>{w}}" + col(ref_of(key)))
    for key in ("CDA", "CEDA"):
        for dn in list(drive_names) + ["all"]:
            lines.append(f"{key:<10}{dn:<6} {cell(m[key][dn]):>{w}}" + col(ref_of(key, dn)))
    for key, d in out.get("intention_accuracy", {}).items():
        lines.append(f"{'accuracy':<10}{key.replace('_', ' '):<6} {cell(d):>{w}}")
    return "\n".join(lines)


def _out_dir(path: str) -> Path:
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise UserError(f"--out {path}: exists and is not a directory")
    try:
        p.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UserError(f"--out {path}: cannot create the directory ({exc.strerror or exc})") from None
    return p


def cmd_sweep(args) -> int:
    from .sweep import format_sweep, sweep

    base = RunConfig(iterations=args.iterations, scenario=args.scenario, overrides=tuple(args.set))
    sc = build_scenario(base)  # validates the scenario before any worker starts
    out_dir = _out_dir(args.out) if args.out else None
    seeds = seed_range(args.first_seed, args.seeds)
    out, raw = sweep(args.param, base, seeds, pool(args, out_dir), quiet=args.quiet,
                     curves=out_dir is not None and args.param == PSEUDO_SWEEP)
    if out_dir is not None:
        from . import report

        (out_dir / f"sweep-{args.param}.json").write_text(json.dumps(json_safe(out)))
        st = sc.reference.statements if sc.reference is not None else None  # published values to draw, if any
        if args.param == XI_SWEEP:
            report.fig_xi(out_dir / "fig4_3_xi.png", out["points"], st)
        elif args.param == DOD_SWEEP:
            report.fig_dod(out_dir / "fig4_5_dod.png", out["points"], sc.drive_names, st)
        else:
            other = st["pseudo_unaffected_drive"] if st else None
            report.fig_pseudo(out_dir / "fig4_4_pseudo.png", raw[0], raw[1], sc.drive_names[sc.serving], other=other)
            report.fig_pseudo(out_dir / "fig4_4_pseudo_early.png", raw[0], raw[1], sc.drive_names[sc.serving], until=1000,
                              other=other)
    if args.json:
        print(json.dumps(json_safe(out)))
    else:
        print(f"sweep {args.param}: {args.iterations} iterations x {args.seeds} seeds per point"
              + (f" (seeds {seeds[0]}..{seeds[-1]})" if args.first_seed else "")
              + ("  (mean [95% interval])" if args.seeds > 1 else ""))
        print(format_sweep(out, args.seeds, sc.drive_names[sc.serving]))
    return 0


def cmd_report(args) -> int:
    from .report import build_report
    from .report.fidelity import format_goals

    base = RunConfig(iterations=args.iterations, scenario=args.scenario, overrides=tuple(args.set))
    build_scenario(base)
    out_dir = _out_dir(args.out)
    data = build_report(out_dir, seeds=args.seeds, iterations=args.iterations, workers=pool(args, out_dir),
                        quiet=args.quiet, scenario=args.scenario, overrides=tuple(args.set), first_seed=args.first_seed)
    fails = [c["check"] for c in data["checks"] if not c["ok"]]
    print(f"report written to {out_dir / 'report.md'} in {data['timing']['total_s']:.1f} s "
          f"({data['timing']['jobs']} runs on {data['timing']['workers']} workers)")
    print(f"trend checks: {len(data['checks']) - len(fails)}/{len(data['checks'])} reproduced"
          + (f"; not reproduced: {'; '.join(fails)}" if fails else ""))
    print(f"fidelity: {data['fidelity']['summary']}")
    goals = data["fidelity"].get("goals")
    if goals:  # issue 25's targets (homeo_sim.report.fidelity.GOALS)
        print("goals: " + format_goals(goals))
    return 0


def cmd_bench(args) -> int:
    from homeo_decision.scenario import load_scenario

    if args.intention == BAYES:
        from .intention_bench import bench_intention, format_bench

        res = bench_intention(args.iterations)
        print(json.dumps(res) if args.json else format_bench(res))
        return 0
    sc = load_scenario()
    cfg = RunConfig(iterations=args.iterations, seed=0)
    best = math.inf
    for _ in range(3):
        t0 = time.perf_counter()
        run_episode(cfg, sc)
        best = min(best, time.perf_counter() - t0)
    ips = args.iterations / best
    t0 = time.perf_counter()
    run_seeds(RunConfig(iterations=5000), range(20))
    wall = time.perf_counter() - t0
    if args.json:
        print(json.dumps({"iterations_per_s": ips, "seeds20_wall_s": wall}))
    else:
        print(f"core loop, one process : {ips:,.0f} iterations/s (best of 3 runs of {args.iterations})")
        print(f"20 seeds x 5000 its    : {wall:.2f} s wall on {os.cpu_count()} cores")
    return 0


def main(argv=None) -> int:
    def command() -> int:
        args = build_parser().parse_args(argv)
        if getattr(args, "cluster", None) and args.scenario and os.path.isfile(args.scenario):
            args.scenario = os.path.abspath(args.scenario)  # a node's working directory is not ours
        return {"run": cmd_run, "sweep": cmd_sweep, "report": cmd_report, "bench": cmd_bench}[args.cmd](args)

    return run_command(PROG, command, (ScenarioError, QTableError, IntentionModelError), os_errors=True)

if __name__ == "__main__":
    sys.exit(main())

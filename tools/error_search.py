"""Search of the open choices on issue 25's fidelity score: relative errors of Table 4.5 over many seeds,
the statements on disjoint 20-seed sets (homeo_sim.report.fidelity), chosen on seeds the search picks
from and confirmed on seeds it never saw (docs/FIDELITY.md, "Issue 25").

    .venv/bin/python tools/error_search.py search --trials 150 --search-seeds 2000-2099 --statement-seeds 2000-2039 \
        --out calibrate-errors                       # Optuna's TPE (make calibrate-setup)
    .venv/bin/python tools/error_search.py validate --from calibrate-errors/trials.jsonl --best 8 \
        --seeds 3000-3099 --out calibrate-errors     # the best distinct points on seeds of their own
    .venv/bin/python tools/error_search.py confirm --seeds 5000-5099 [--change KEY=JSON ...]   # one point

Each command takes --workers W (local processes) or --cluster ADDRESS (the runs as Ray tasks on a cluster);
with --out, each finished run is kept in OUT/runs and the same command again runs only the missing runs.
The search's trials live in an Optuna study storage (--storage: an RDB URL, default the SQLite file
OUT/study.db; a database server for drivers on several machines): started again, the search goes on
where it stopped (a trial whose driver died is retried), and --parallel-trials K evaluates K trials at once.

What one evaluation runs (5000 iterations each): the default run on the table seeds (the 12 numbers:
the relative error of our mean), and on the statement seeds, in sets of 20, the runs the criteria read
(``NEEDED``: issue 31's complete list reads the xi sweep's points, no pseudo update and the whole DoD grid,
and parts of runs through their running sums). A point whose mean absolute error exceeds ``--gate`` is not
run on the statements (it scores as if none held): it cannot reach the goals, and the statements cost
eighteen times the table. ``search --issue31`` starts from the block and one change at a time (``HINTS_31``)
and leaves issue 25's costly readings as they are (``FIXED_31``).

The objective (maximised; the goals are those of issue 25, ``fidelity.GOALS``), in percentage points:

    score = - 100 x mean |error| - 2 x (sum of each number's |error| beyond 15%)
            - 4 x (sum of HSR's and RSR's |error| beyond 5%)
            + 3 x (statements met, mean over the sets) - 3 x (sum over the sets of the shortfall below 90%)
            - W_TEXT x (departures from the text's literal reading)
"""

from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path

TOOLS = Path(__file__).resolve().parent
sys.path.insert(0, str(TOOLS))
sys.path.insert(0, str(TOOLS.parent / "src"))

import joint_search as j  # noqa: E402
from homeo_msgs_py.cli_args import Parser, UserError, float_in, int_at_least, run_command  # noqa: E402
from homeo_sim.report.fidelity import (GOALS, error_summary, needed_labels, relative_errors, seed_sets,  # noqa: E402
                                       set_aggregates, statement_shares, statements_goal_met)
from homeo_sim.parallel import Pool, add_cluster_argument  # noqa: E402
from homeo_sim.runner import run_seeds  # noqa: E402
from homeo_sim.stats import aggregate  # noqa: E402
from homeo_sim.sweep import SWEEPS, point_config  # noqa: E402

PROG = "error_search.py"
SC, DRIVES = j.SC, j.DRIVES
# issue 15's searched choices, issue 25's readings of the energy drive and of the activation boundary, and issue
# 31's readings of the motivation factor and the pseudo update
ISSUE_31 = {"motivation_bonus": ("dominant", "activated"), "pseudo_reward": ("eq_3_20", "eq_3_19"),
            "pseudo_serving": ("praise", "satisfied")}
SEARCHED = j.SEARCHED + ("ongoing_effects", "activation_boundary") + tuple(ISSUE_31)
# issue 15's space, widened where its best points sat at an end (a busier human, a higher initial Q value,
# more absences), NEng's growth and issue 25's readings added; neighbours move the initial Q value and how
# busy the human is by more than one grid step
SPACE = j.Space(searched=SEARCHED, initial_q=(-5.0, 25.0), no_intention=(0.05, 0.8),
                leave_probs=(0.0, 0.02, 0.05, 0.1, 0.2),
                growth={**j.GROWTH_SEARCH, "NEng": ["always", "not_lowered"]},
                extra={"ongoing_effects": ("actions", "every_tick"), "activation_boundary": ("eq_3_2", "above"), **ISSUE_31},
                steps={"initial_q": (1, 2, 4), "human_no_intention_prob": (1, 2)})
DOD_SEARCH = j.DOD_SEARCH
W_EACH, W_HEAD, W_MET, W_SHORT, W_TEXT = 2.0, 4.0, 3.0, 3.0, 1.0
GATE = 0.20  # a mean absolute error above this: the statements are not run


def text_distance(o: dict) -> int:
    """Issue 15's count (joint_search.text_distance) plus the readings of issue 25: charging on every tick
    at the charger departs from Table 4.1's rows, a drive at its threshold left inactive from Eq 3.2."""
    return j.text_distance(o) + (o.get("ongoing_effects", "actions") != "actions") \
        + (o.get("activation_boundary", "eq_3_2") != "eq_3_2") + (o.get("pseudo_reward", "eq_3_20") != "eq_3_20") \
        + (o.get("pseudo_serving", "praise") != "praise")  # motivation_bonus: "when the robot has a dominant motivation"


def current_open() -> dict:
    return j.current_open(SEARCHED)


def suggest(trial, start: dict) -> dict:
    """One point of the joint space: every searched open choice at once (``SPACE``)."""
    return j.suggest(trial, start, SPACE)


def params(o: dict) -> dict:
    """An open block as the parameters of ``suggest`` (to enqueue a known point)."""
    return j._params(o, SPACE)


# -- one evaluation ---------------------------------------------------------------------------------

def _kept(r) -> dict:
    """A run's metrics and its running sums (the criteria read parts of runs)."""
    return r.metrics | {"stages": r.stages}


def evaluate(o: dict, table_seeds: list[int], statement_seeds: list[int], dods=SWEEPS["dod"], workers: int = 1,
             gate: float | None = GATE) -> dict:
    """The 12 relative errors over ``table_seeds``, the criteria on each set of 20 of ``statement_seeds``
    (not run when the mean absolute error is above ``gate``)."""
    e = evaluate_table(o, table_seeds, statement_seeds, workers)
    if gate is None or e["mae"] <= gate:
        add_statements(e, statement_seeds, dods, workers)
    return e


def evaluate_table(o: dict, table_seeds: list[int], statement_seeds: list[int], workers: int = 1) -> dict:
    """The default run on ``table_seeds``: the 12 relative errors; the statements still to run (scored as
    none held until ``add_statements``)."""
    cfg = j._configs(o, ())["base"]
    per_seed = dict(zip(table_seeds, [_kept(r) for r in run_seeds(cfg, table_seeds, workers)]))
    rows = relative_errors(aggregate(list(per_seed.values()), DRIVES), SC.reference.metrics)
    errors = error_summary(rows)
    e = {"open": o, "errors": {r["metric"]: r["error"] for r in rows}, "mae": errors["mean_abs_error"],
         "means": {r["metric"]: r["mean"] for r in rows}, "text_distance": text_distance(o),
         "table_seeds": [table_seeds[0], table_seeds[-1]], "statement_seeds": [statement_seeds[0], statement_seeds[-1]],
         "met_per_set": None, "shares": None, "n_sets": len(seed_sets(statement_seeds)),
         "goals": dict(errors["goals"], statements_per_set=False), "_base": per_seed}
    e["score"] = score(e)
    return e


NEEDED = needed_labels(SC.reference.criteria, SWEEPS)  # the labels the criteria read, parts of runs included


def configs(o: dict, dods=SWEEPS["dod"]) -> dict:
    """The runs the criteria read (``NEEDED``; the DoD sweep over ``dods``), by label."""
    base = j._configs(o, ())["base"]
    labs = {lab.partition("@")[0] for lab in NEEDED if not lab.startswith("dod=")} | {f"dod={v}" for v in dods}
    return {lab: base if lab == "base" else point_config(lab.split("=")[0], lab.endswith("True") if lab.startswith(
        "pseudo=") else float(lab.split("=")[1]), base) for lab in sorted(labs)}


def add_statements(e: dict, statement_seeds: list[int], dods=SWEEPS["dod"], workers: int = 1) -> dict:
    """The criteria on each set of 20 of ``statement_seeds`` for the point ``e`` of ``evaluate_table``."""
    o, per_seed = e["open"], e.pop("_base", {})
    cfgs = configs(o, dods)
    runs = {}
    for lab, cfg in cfgs.items():
        if cfg == cfgs["base"]:  # the default run: xi 1 and the pseudo update on are it
            missing = [s for s in statement_seeds if s not in per_seed]
            if missing:
                per_seed.update(zip(missing, [_kept(r) for r in run_seeds(cfg, missing, workers)]))
            runs[lab] = [per_seed[s] for s in statement_seeds]
        else:
            runs[lab] = [_kept(r) for r in run_seeds(cfg, statement_seeds, workers)]
    M_sets = set_aggregates(runs, DRIVES, NEEDED)
    sh = statement_shares(SC.reference.criteria, M_sets, {**SWEEPS, "dod": tuple(dods)}, {"dod": cfgs["base"].dod})
    e.update(met_per_set=sh["met_per_set"], shares={x["id"]: x["held"] for x in sh["shares"]}, n_sets=len(M_sets))
    e["goals"]["statements_per_set"] = statements_goal_met(e["met_per_set"], len(SC.reference.criteria))
    e["score"] = score(e)
    return e


def table_part(e: dict) -> float:
    """The score without its statement terms (what the table alone decides)."""
    return score({**e, "met_per_set": [0] * e["n_sets"]}) + W_SHORT * e["n_sets"] * GOALS["statements_per_set"] * len(
        SC.reference.criteria)


def score(e: dict) -> float:
    """The objective of the module docstring (higher is better)."""
    errs = e["errors"]
    each = sum(max(0.0, 100 * abs(x) - 100 * GOALS["each_error"]) for x in errs.values())
    head = sum(max(0.0, 100 * abs(errs[k]) - 100 * GOALS["headline_error"]) for k in GOALS["headline"])
    n_crit = len(SC.reference.criteria)
    need = GOALS["statements_per_set"] * n_crit
    met = e["met_per_set"] if e["met_per_set"] is not None else [0] * e["n_sets"]
    statements = W_MET * sum(met) / len(met) - W_SHORT * sum(max(0.0, need - m) for m in met)
    return -100 * e["mae"] - W_EACH * each - W_HEAD * head + statements - W_TEXT * e["text_distance"]


def line(e: dict) -> str:
    errs = e["errors"]
    worst = max(errs, key=lambda k: abs(errs[k]))
    met = "-" if e["met_per_set"] is None else ",".join(map(str, e["met_per_set"]))
    return (f"score {e['score']:7.2f}  MAE {100 * e['mae']:5.1f}%  worst {worst} {100 * errs[worst]:+.0f}%  "
            f"HSR {100 * errs['HSR']:+.1f}% RSR {100 * errs['RSR']:+.1f}%  statements {met}  text {e['text_distance']}")


def diff(o: dict, ref: dict) -> str:
    """``joint_search.diff`` over this search's choices."""
    return j.diff(o, ref, SEARCHED)


# -- the search --------------------------------------------------------------------------------------

# where the search starts: the current default, and issue 25's first measurements around it (docs/FIDELITY.md):
# charging at the charger on every tick moved CDA NEng to the thesis's; a busier human raised NSoc and NRes
HINTS = ({}, {"ongoing_effects": "every_tick"}, {"ongoing_effects": "every_tick", "human_no_intention_prob": 0.2},
         {"ongoing_effects": "every_tick", "human_no_intention_prob": 0.2, "tie_break": "last"})
# issue 31: the block of issue 25, then one change at a time: the readings of the motivation factor and the
# pseudo update, and the choices that moved the two features' claims most in a first look (docs/FIDELITY.md)
HINTS_31 = ({}, {"motivation_bonus": "activated"}, {"pseudo_reward": "eq_3_19"}, {"pseudo_serving": "satisfied"},
            {"scold_drive_change": 4.0}, {"scold_drive_change": 6.0}, {"human_proposal_prob": 1.0}, {"initial_q": 12.0},
            {"reward_span": "iteration"}, {"human_no_intention_prob": 0.3}, {"serving_growth": "expressed"},
            {"tie_break": "first"}, {"value_max_over": "all"}, {"metrics_sample": "end"})
# issue 31's search leaves these at the block's values: issue 25's one-at-a-time tables show each costs the table
# far more than it could give (docs/FIDELITY.md)
FIXED_31 = ("ongoing_effects", "activation_boundary", "drive_growth", "time_increase", "invalid_actions",
            "always_valid_actions", "human_leave_prob", "human_return_prob", "on_leave_effects",
            "no_activated_motivation", "human_proposal_choice")


def study_of(storage: str, sampler_seed: int):
    """The search's Optuna study in ``storage`` (created, or loaded to go on); a trial whose driver stopped
    sending heartbeats is failed and retried once a new trial starts."""
    import warnings

    import optuna
    from optuna.storages import RDBStorage, RetryHeartbeatStaleTrialCallback

    warnings.filterwarnings("ignore", category=optuna.exceptions.ExperimentalWarning)  # the heartbeat, since 2.8
    try:
        rdb = RDBStorage(storage, heartbeat_interval=60, grace_period=180,
                         heartbeat_stale_trial_callback=RetryHeartbeatStaleTrialCallback(max_retry=3))
    except Exception as exc:  # noqa: BLE001 (whatever SQLAlchemy says of a URL or a database it cannot open)
        raise UserError(f"--storage {storage[:80]}: {str(exc).splitlines()[0][:120]}") from None
    return optuna.create_study(study_name="error-search", storage=rdb, load_if_exists=True, direction="maximize",
                               sampler=optuna.samplers.TPESampler(seed=sampler_seed, multivariate=True))


def search(trials: int, table_seeds: list[int], statement_seeds: list[int], out: Path, sampler_seed: int,
           workers, gate: float, storage: str | None = None, parallel: int = 1, hints=HINTS,
           fixed: tuple = ()) -> list[dict]:
    """``trials`` trials in all, counting those the study in ``storage`` already completed."""
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    out.mkdir(parents=True, exist_ok=True)
    start, t0, evals = current_open(), time.time(), []
    study = study_of(storage or f"sqlite:///{(out / 'study.db').resolve()}", sampler_seed)
    resumed = bool(study.trials)
    if not resumed:
        for hint in hints:
            study.enqueue_trial(params({**start, **hint}))
    done = sum(t.state == optuna.trial.TrialState.COMPLETE for t in study.trials)
    if resumed:
        print(f"study in {storage or out / 'study.db'}: {done} trials done, {max(0, trials - done)} to go",
              file=sys.stderr, flush=True)
    with (out / "trials.jsonl").open("a" if resumed else "w") as log:
        def objective(trial):
            o = suggest(trial, start) | {k: start[k] for k in fixed}
            e = evaluate(o, table_seeds, statement_seeds, workers=workers, gate=gate)
            e.pop("_base", None)
            e["trial"] = trial.number
            evals.append(e)
            log.write(json.dumps(e) + "\n")
            log.flush()
            print(f"trial {trial.number:4d}: {line(e)}  ({time.time() - t0:.0f} s)", file=sys.stderr, flush=True)
            return e["score"]

        study.optimize(objective, n_trials=max(0, trials - done), n_jobs=parallel)
    return evals


# -- refinement: a greedy walk from the best point ------------------------------------------------------

def neighbours(o: dict) -> list[dict]:
    """Each searched choice moved alone (``joint_search.neighbours`` in ``SPACE``)."""
    return j.neighbours(o, SPACE)


def refine(start: dict, table_seeds: list[int], statement_seeds: list[int], out: Path, rounds: int, top: int,
           workers: int) -> dict:
    """From ``start``, each round scores every neighbour on the table alone, runs the statements for the ``top``
    best by that, and moves to the best full score if it beats the current point; stops when none does."""
    out.mkdir(parents=True, exist_ok=True)
    t0, n = time.time(), 0
    seen: dict[str, dict] = {}

    def logged(e, what):
        nonlocal n
        e.pop("_base", None)
        e["trial"] = n
        n += 1
        log.write(json.dumps(e) + "\n")
        log.flush()
        print(f"{what} {e['trial']:4d}: {line(e)}  {diff(e['open'], start)}  ({time.time() - t0:.0f} s)",
              file=sys.stderr, flush=True)
        return e

    with (out / "refine.jsonl").open("w") as log:
        cur = logged(evaluate(start, table_seeds, statement_seeds, workers=workers, gate=None), "start")
        seen[json.dumps(start, sort_keys=True)] = cur
        for r in range(rounds):
            tables = []
            for o in neighbours(cur["open"]):
                key = json.dumps(o, sort_keys=True)
                if key not in seen:
                    seen[key] = e = evaluate_table(o, table_seeds, statement_seeds, workers)
                    tables.append(e)
            tables.sort(key=lambda e: -table_part(e))
            full = [logged(add_statements(e, statement_seeds, workers=workers), f"round {r} full ") for e in tables[:top]]
            for e in tables[top:]:
                logged(e, f"round {r} table")
            best = max(full, key=lambda e: e["score"], default=None)
            if best is None or best["score"] <= cur["score"]:
                break
            cur = best
            print(f"round {r}: moved to {diff(cur['open'], start)}", file=sys.stderr, flush=True)
    return cur


def read_trials(path: str) -> list[dict]:
    """The trials of a ``search`` (its trials.jsonl); UserError (one line) for a file that is not one."""
    out = []
    try:
        text = Path(path).read_text()
    except (OSError, UnicodeDecodeError) as exc:
        raise UserError(f"{path}: {getattr(exc, 'strerror', None) or exc}") from None
    for n, ln in enumerate(text.splitlines(), 1):
        if not ln.strip():
            continue
        try:
            e = json.loads(ln)
            params(e["open"])
            if not isinstance(e["score"], (int, float)) or isinstance(e["score"], bool) or not math.isfinite(e["score"]):
                raise ValueError("no finite score")
            for k in ("table_seeds", "statement_seeds"):  # [first, last] of the seeds it ran on
                lo, hi = e[k]
                if not (type(lo) is int and type(hi) is int and 0 <= lo <= hi <= 2**31 - 1):
                    raise ValueError(f"{k} is not [first, last]")
        except (ValueError, KeyError, TypeError, AttributeError) as exc:
            raise UserError(f"{path}:{n}: not a trial of this search ({type(exc).__name__}: "
                            f"{str(exc)[:80]})".replace("\n", " ")) from None
        out.append(e)
    if not out:
        raise UserError(f"{path}: no trials")
    return out


def select(points: list[dict], slack: float = 2.0) -> dict:
    """Among the points whose score is within ``slack`` of the best, the closest to the text; then the
    higher score."""
    best = max(p["score"] for p in points)
    near = [p for p in points if p["score"] >= best - slack]
    return min(near, key=lambda p: (p["text_distance"], -p["score"]))


# -- the command line --------------------------------------------------------------------------------

def seeds_arg(spec: str) -> list[int]:
    try:
        return j._seeds(spec)
    except j.SeedSetError as exc:
        raise UserError(str(exc)) from None


def change_arg(spec: str, start: dict) -> dict:
    """``KEY=JSON[,KEY=JSON...]`` of searched open choices, checked against the scenario."""
    from homeo_decision.scenario import ScenarioError, load_scenario

    out = {}
    for kv in spec.split(","):
        k, eq, v = kv.partition("=")
        if not eq:
            raise UserError(f"--change {kv[:40]!r}: not KEY=JSON")
        if k.strip() not in start:
            raise UserError(f"--change: {k.strip()[:40]!r} is not a searched open choice")
        try:
            out[k.strip()] = json.loads(v)
        except ValueError:
            raise UserError(f"--change {k.strip()}: {v[:40]!r} is not JSON") from None
    try:
        load_scenario(overrides={**start, **out})
    except ScenarioError as exc:
        raise UserError(str(exc)) from None
    return out


def points_parser(prog: str, doc: str, seeds: str) -> Parser:
    """The command line of a tool that measures the current default and changes of it (dod_shape, feature_claims)."""
    ap = Parser(prog=prog, description=doc.splitlines()[0])
    ap.add_argument("--seeds", default=seeds, help=f"seeds A-B (default {seeds})")
    ap.add_argument("--change", action="append", default=[], metavar="KEY=JSON[,KEY=JSON]",
                    help="also the current default with these changes (repeat for several points)")
    ap.add_argument("--workers", type=int_at_least(1), default=1)
    return ap


def points_of(a) -> tuple[list[int], list[tuple[str, dict]]]:
    """The seeds and the points (label, open block) of a ``points_parser`` command line."""
    start = current_open()
    return seeds_arg(a.seeds), [("current default", start)] + [(ch, {**start, **change_arg(ch, start)}) for ch in a.change]


def build_parser() -> Parser:
    ap = Parser(prog=PROG, description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True, parser_class=Parser)
    s = sub.add_parser("search", help="Optuna's TPE on the search seeds")
    s.add_argument("--trials", type=int_at_least(1), default=150)
    s.add_argument("--search-seeds", default="2000-2099", help="seeds of the 12 numbers (default 2000-2099)")
    s.add_argument("--statement-seeds", default="2000-2039", help="seeds of the statements, sets of 20 (default 2000-2039)")
    s.add_argument("--sampler-seed", type=int_at_least(0), default=25)
    s.add_argument("--gate", type=float_in(0.0, 10.0), default=GATE,
                   help=f"skip the statements above this mean absolute error (default {GATE})")
    s.add_argument("--out", default="calibrate-errors")
    s.add_argument("--storage", metavar="URL", default=None,
                   help="the Optuna study's RDB URL (default: sqlite:///OUT/study.db); a database server for several drivers")
    s.add_argument("--parallel-trials", type=int_at_least(1), default=1, metavar="K", help="trials evaluated at once")
    s.add_argument("--issue31", action="store_true", help="issue 31's hints (one change at a time) and fixed choices")
    v = sub.add_parser("validate", help="the best distinct trials of a search on seeds of their own")
    v.add_argument("--from", dest="trials_file", required=True, metavar="TRIALS.jsonl")
    v.add_argument("--best", type=int_at_least(1), default=8)
    v.add_argument("--seeds", default="3000-3099", help="table and statement seeds (default 3000-3099)")
    v.add_argument("--out", default="calibrate-errors")
    r = sub.add_parser("refine", help="a greedy walk over one-step neighbours from the best trial of a search")
    r.add_argument("--from", dest="trials_file", required=True, metavar="TRIALS.jsonl")
    r.add_argument("--search-seeds", default="2000-2099")
    r.add_argument("--statement-seeds", default="2000-2039")
    r.add_argument("--rounds", type=int_at_least(1), default=8)
    r.add_argument("--top", type=int_at_least(1), default=5, help="neighbours per round whose statements are run")
    r.add_argument("--out", default="calibrate-errors")
    c = sub.add_parser("confirm", help="the current default (or a change of it) on seeds no search used")
    c.add_argument("--seeds", default="5000-5099", help="table and statement seeds (default 5000-5099)")
    c.add_argument("--change", action="append", default=[], metavar="KEY=JSON[,KEY=JSON]",
                   help="a point to score: the default with these changes (repeat for several points)")
    for p in (s, v, r, c):
        p.add_argument("--workers", type=int_at_least(1), default=1)
        add_cluster_argument(p)
    return ap


def main(argv=None) -> int:
    def command() -> int:
        a = build_parser().parse_args(argv)
        start = current_open()
        a.workers = Pool(a.workers, a.cluster, Path(a.out) / "runs" if "out" in a else None)
        if a.cmd == "search":
            t_seeds, s_seeds = seeds_arg(a.search_seeds), seeds_arg(a.statement_seeds)
            search(a.trials, t_seeds, s_seeds, Path(a.out), a.sampler_seed, a.workers, a.gate, a.storage,
                   a.parallel_trials, *((HINTS_31, FIXED_31) if a.issue31 else (HINTS, ())))
            return 0
        if a.cmd == "refine":
            t_seeds, s_seeds = seeds_arg(a.search_seeds), seeds_arg(a.statement_seeds)
            best = j.best_distinct(read_trials(a.trials_file), 1)[0]
            cur = refine(best["open"], t_seeds, s_seeds, Path(a.out), a.rounds, a.top, a.workers)
            print(f"refined: {line(cur)}\n```json\n" + json.dumps({k: cur["open"][k] for k in SEARCHED}, indent=1)
                  + "\n```")
            return 0
        seeds = seeds_arg(a.seeds)
        if a.cmd == "validate":
            evals = read_trials(a.trials_file)
            used = set()
            for e in evals:
                used |= set(range(e["table_seeds"][0], e["table_seeds"][1] + 1))
                used |= set(range(e["statement_seeds"][0], e["statement_seeds"][1] + 1))
            if used & set(seeds):
                raise UserError("--seeds overlap the seeds the search used")
            points = []
            out = Path(a.out)
            out.mkdir(parents=True, exist_ok=True)
            with (out / "validate.jsonl").open("w") as log:
                for p in j.best_distinct(evals, a.best):
                    e = evaluate(p["open"], seeds, seeds, dods=SWEEPS["dod"], workers=a.workers, gate=None)
                    e["trial"], e["search_score"] = p.get("trial"), p["score"]
                    points.append(e)
                    log.write(json.dumps(e) + "\n")
                    log.flush()
                    print(f"trial {e['trial']}: search {p['score']:.2f} -> {line(e)}", file=sys.stderr, flush=True)
            chosen = select(points)
            print(table(points, start, chosen))
            print("\nChosen (within 2 points of the best validation score, closest to the text):\n```json\n"
                  + json.dumps({k: chosen["open"][k] for k in SEARCHED}, indent=1) + "\n```")
            return 0
        points = [start] + [{**start, **change_arg(ch, start)} for ch in a.change]
        evals = []
        for o in points:
            e = evaluate(o, seeds, seeds, dods=SWEEPS["dod"], workers=a.workers, gate=None)
            e["trial"] = len(evals)
            evals.append(e)
            print(f"point {e['trial']}: {line(e)}", file=sys.stderr, flush=True)
        print(table(evals, start))
        return 0

    return run_command(PROG, command, (), os_errors=True)


def table(points: list[dict], start: dict, chosen: dict | None = None) -> str:
    """A Markdown row per point: its changes, the errors, the statements per set."""
    names = list(points[0]["errors"])
    head = ("| point | changes from the current default | text | score | MAE | " + " | ".join(names)
            + " | statements per set |\n|" + "---|" * (6 + len(names)))
    rows = []
    for p in points:
        mark = "**" if chosen is not None and p is chosen else ""
        met = "-" if p["met_per_set"] is None else ", ".join(map(str, p["met_per_set"]))
        rows.append(f"| {mark}{p.get('trial', '')}{mark} | {diff(p['open'], start)} | {p['text_distance']} | "
                    f"{p['score']:.2f} | {100 * p['mae']:.1f}% | "
                    + " | ".join(f"{100 * p['errors'][k]:+.0f}%" for k in names) + f" | {met} |")
    return "\n".join([head] + rows)


if __name__ == "__main__":
    raise SystemExit(main())

"""Joint search over the thesis's open choices (issue 15): Optuna's TPE on search seeds, the best
few confirmed on other seeds with the fidelity score of ``homeo-sim report``.

Called by ``tools/calibrate.py --joint``. Optuna is a tool dependency only:

    .venv/bin/pip install -r tools/requirements-calibrate.lock     # or: pip install -e '.[calibrate]'

What one trial measures, on the search seeds (5000 iterations each): the default run, xi 0 and 2,
no pseudo update and DoD 0, 0.1, ..., 0.6 and 1 (the runs the criteria read; DoD 0.7-0.9 only
matter when RSR stays above 0.5 up to 0.6, and then the "RSR < 0.5 above DoD 0.5" statement fails
anyway). The 95% intervals are rescaled to the confirmation seed count (Student t and sqrt(n)),
so "inside" means "would be inside with that many seeds" if the spread stays as measured.

Distance from the text (``text_distance``) counts the open choices set against the thesis's
literal reading; choices the text leaves wholly free (an amount, a rate, an initial value, an
order it does not state) cost nothing whatever their value. See docs/FIDELITY.md.
"""

from __future__ import annotations

import json
import math
import re
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from homeo_decision.scenario import load_scenario  # noqa: E402
from homeo_sim.report.analysis import DOD0_HSR_MIN, DOD_HSR_GAIN, DOD_RSR_DROP, PSEUDO_HSR_GAIN, XI_RSR_GAIN  # noqa: E402
from homeo_sim.report.fidelity import fidelity  # noqa: E402
from homeo_sim.runner import RunConfig, run_seeds  # noqa: E402
from homeo_sim.stats import aggregate, t975  # noqa: E402
from homeo_sim.sweep import SWEEPS, explicit, point_config  # noqa: E402

SC = load_scenario()  # the thesis scenario: its reference block holds Table 4.5 and the criteria
DRIVES = SC.drive_names
SEARCHED = ("initial_q", "scold_drive_change", "serving_growth", "reward_span", "on_leave_effects", "tie_break",
            "value_max_over", "metrics_sample", "human_no_intention_prob", "human_leave_prob", "human_return_prob",
            "human_proposal_choice", "human_proposal_prob", "invalid_actions", "always_valid_actions",
            "time_increase", "drive_growth", "no_activated_motivation")
# drive_growth is searched per drive: NSoc and NRes (Sec 3.3.1 gives each a growth condition); NEng always grows
GROWTH_SEARCH = {"NSoc": ["always", "human_not_near", "not_lowered"], "NRes": ["always", "robot_moved", "not_lowered"]}


@dataclass(frozen=True)
class Space:
    """What ``suggest`` searches: issue 15's space by default; tools/error_search.py (issue 25) widens the
    ranges where issue 15's best points sat at an end and adds its readings (``extra``)."""

    searched: tuple = SEARCHED
    initial_q: tuple = (-5.0, 20.0)
    no_intention: tuple = (0.3, 0.8)
    leave_probs: tuple = (0.0, 0.02, 0.05, 0.1)
    growth: Mapping = field(default_factory=lambda: dict(GROWTH_SEARCH))
    extra: Mapping = field(default_factory=dict)  # {choice: its values}, categoricals beyond issue 15's
    steps: Mapping = field(default_factory=lambda: {"initial_q": (1, 2)})  # neighbours: grid steps a float moves


ISSUE_15 = Space()
DOD_SEARCH = (0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 1.0)
# the objective's weights (docs/FIDELITY.md): a statement met or a number inside counts 1
W_TREND, W_DIST, W_TEXT = 0.25, 0.02, 0.5


# -- distance from the text ----------------------------------------------------------------

# the thesis's literal reading of each choice it speaks to (choices not listed are free)
LITERAL = {
    "serving_growth": ("always", "Table 4.2, Sec 4.2.1: every drive grows with every iteration"),
    "scold_drive_change": (">0", "Sec 3.3.1: getting scolded increases NAch"),
    "human_proposal_choice": ("random", "Table 4.3: the desired action of leave is MoveToR or MoveToC"),
    "human_proposal_prob": (1.0, "Algorithm 2 line 17: the human always proposes on a miss"),
    "value_max_over": ("all", "Eq 3.15-3.16: the max runs over A_o"),
    "invalid_actions": ("excluded", "Table 3.3: the constraints say which actions can be performed"),
    "always_valid_actions": ([], "Table 3.3: Rest and Chat have constraints"),
    "drive_growth": ({}, "Table 4.2, Sec 4.2.1: every drive grows with every iteration"),
    "no_activated_motivation": ("argmax", "Definition 7, Eq 3.3: in every iteration m_dom is the argmax"),
}


def text_distance(o: dict) -> int:
    """How many open choices depart from the literal reading (each listed action of
    ``always_valid_actions`` counts once)."""
    d = 0
    d += o["serving_growth"] != "always"
    d += not o["scold_drive_change"] > 0
    d += o["human_proposal_choice"] != "random"
    d += o["human_proposal_prob"] < 1.0
    d += o["value_max_over"] != "all"
    d += o["invalid_actions"] != "excluded"
    d += len(o["always_valid_actions"])
    d += sum(r != "always" for r in o.get("drive_growth", {}).values())  # time_increase: the text is silent
    d += o.get("no_activated_motivation", "argmax") != "argmax"
    return int(d)


# -- one evaluation ---------------------------------------------------------------------------

def _configs(open_: dict, dods) -> dict[str, RunConfig]:
    base = explicit(RunConfig(overrides=tuple(open_.items())), SC)
    cfgs = {"base": base, "xi=0.0": point_config("xi", 0.0, base), "xi=2.0": point_config("xi", 2.0, base),
            "pseudo=False": point_config("pseudo", False, base)}
    for v in dods:
        cfgs[f"dod={v}"] = point_config("dod", v, base)
    return cfgs


def _rescale(agg: dict, n_from: int, n_to: int) -> dict:
    """The aggregate with every 95% half-width as it would be with ``n_to`` seeds at the same spread."""
    f = t975(n_to - 1) / t975(n_from - 1) * math.sqrt(n_from / n_to)

    def walk(x):
        if isinstance(x, dict) and "ci95" in x:
            m, (lo, hi) = x["mean"], x["ci95"]
            return {**x, "ci95": [m - (m - lo) * f, m + (hi - m) * f]}
        return {k: walk(v) for k, v in x.items()} if isinstance(x, dict) else x

    return walk(agg)


def trends(M: dict) -> dict:
    """The six trend checks of issue 6 (homeo_sim.report.analysis), pass or fail."""
    m = lambda lab, k: M[lab][k]["mean"]  # noqa: E731
    serving = DRIVES[SC.serving]
    return {
        "HSR rises with DoD": m("dod=1.0", "HSR") - m("dod=0.0", "HSR") >= DOD_HSR_GAIN,
        "RSR falls with DoD": m("dod=0.0", "RSR") - m("dod=1.0", "RSR") >= DOD_RSR_DROP,
        "HSR at DoD 0 stays useful": m("dod=0.0", "HSR") >= DOD0_HSR_MIN,
        "RSR improves with xi": m("xi=2.0", "RSR") - m("xi=0.0", "RSR") >= XI_RSR_GAIN,
        "pseudo update raises HSR": m("base", "HSR") - m("pseudo=False", "HSR") >= PSEUDO_HSR_GAIN,
        "pseudo update lowers the serving drive's CDA":
            M["pseudo=False"]["CDA"][serving]["mean"] > M["base"]["CDA"][serving]["mean"],
    }


def evaluate(open_: dict, seeds: list[int], dods=DOD_SEARCH, scale_to: int | None = None, workers: int = 1) -> dict:
    """Run the configurations the score needs on ``seeds``; return the fidelity score and its parts."""
    cfgs = _configs(open_, dods)
    M = {}
    for lab, cfg in cfgs.items():
        agg = aggregate([r.metrics for r in run_seeds(cfg, seeds, workers)], DRIVES)
        M[lab] = _rescale(agg, len(seeds), scale_to) if scale_to else agg
    M["pseudo=True"] = M["base"]  # the default run has the pseudo update on
    base = cfgs["base"]
    fid = fidelity(SC.reference, M, {**SWEEPS, "dod": tuple(dods)}, {"dod": base.dod})
    tr = trends(M)
    dist = sum(min(r["distance"], 10.0) for r in fid["table"])
    out = {"open": open_, "inside": fid["table_inside"], "met": fid["statements_met"], "trends": sum(tr.values()),
           "text_distance": text_distance(open_), "sum_distance": dist,
           "inside_names": [r["metric"] for r in fid["table"] if r["inside"]],
           "unmet": [s["id"] for s in fid["statements"] if not s["agrees"]],
           "failed_trends": [k for k, ok in tr.items() if not ok],
           "HSR": M["base"]["HSR"]["mean"], "RSR": M["base"]["RSR"]["mean"],
           "base": {k: M["base"][k] for k in ("HSR", "RSR")} | {"CDA": M["base"]["CDA"], "CEDA": M["base"]["CEDA"]},
           "fidelity": fid}
    out["score"] = score(out)
    return out


def score(e: dict) -> float:
    """The objective: numbers inside plus statements met, a little for the trends and for closeness,
    less W_TEXT per departure from the literal text."""
    return (e["inside"] + e["met"] + W_TREND * e["trends"] - W_DIST * e["sum_distance"]
            - W_TEXT * e["text_distance"])


# -- the search ------------------------------------------------------------------------------

def suggest(trial, start: dict, space: Space = ISSUE_15) -> dict:
    """One point of the joint space (every searched open choice at once)."""
    o = dict(start)
    o["initial_q"] = trial.suggest_float("initial_q", *space.initial_q, step=0.5)
    o["scold_drive_change"] = trial.suggest_float("scold_drive_change", 0.0, 10.0, step=1.0)
    o["serving_growth"] = trial.suggest_categorical("serving_growth", ["always", "expressed", "unsatisfied"])
    o["reward_span"] = trial.suggest_categorical("reward_span", ["iteration", "action"])
    o["on_leave_effects"] = trial.suggest_categorical("on_leave_effects", [True, False])
    o["tie_break"] = trial.suggest_categorical("tie_break", ["first", "last"])
    o["value_max_over"] = trial.suggest_categorical("value_max_over", ["all", "valid"])
    o["metrics_sample"] = trial.suggest_categorical("metrics_sample", ["end", "after_action"])
    o["human_no_intention_prob"] = trial.suggest_float("human_no_intention_prob", *space.no_intention, step=0.05)
    o["human_leave_prob"] = trial.suggest_categorical("human_leave_prob", list(space.leave_probs))
    o["human_return_prob"] = trial.suggest_float("human_return_prob", 0.2, 1.0, step=0.1)
    o["human_proposal_choice"] = trial.suggest_categorical("human_proposal_choice", ["random", "MoveToR", "MoveToC"])
    o["human_proposal_prob"] = trial.suggest_float("human_proposal_prob", 0.5, 1.0, step=0.1)
    o["invalid_actions"] = trial.suggest_categorical("invalid_actions", ["excluded", "no_effect"])
    free = trial.suggest_categorical("always_valid_actions", ["none", "Rest", "Chat", "Rest+Chat"])
    o["always_valid_actions"] = [] if free == "none" else free.split("+")
    o["time_increase"] = trial.suggest_categorical("time_increase", ["after_action", "before_action"])
    g = {d: trial.suggest_categorical(f"growth_{d}", readings) for d, readings in space.growth.items()}
    o["drive_growth"] = {d: r for d, r in g.items() if r != "always"}
    o["no_activated_motivation"] = trial.suggest_categorical("no_activated_motivation", ["argmax", "none"])
    for name, values in space.extra.items():
        o[name] = trial.suggest_categorical(name, list(values))
    return o


def _params(o: dict, space: Space = ISSUE_15) -> dict:
    """An open block as Optuna parameters (to enqueue a known point)."""
    p = {k: o[k] for k in space.searched if k not in ("always_valid_actions", "drive_growth")}
    p["always_valid_actions"] = "+".join(o["always_valid_actions"]) or "none"
    for d in space.growth:
        p[f"growth_{d}"] = o.get("drive_growth", {}).get(d, "always")
    return p


def _with_defaults(o: dict) -> dict:
    """An open block of an older trial (before a choice was searched) with the choice at its default."""
    return {"time_increase": "after_action", "drive_growth": {}, "no_activated_motivation": "argmax", **o}


def _distributions(trial) -> dict:
    """The parameter distributions of the space (from a trial that suggested every parameter)."""
    return dict(trial.distributions)


class SeedSetError(ValueError):
    """A seed set that is not ``A-B`` or ``A`` with 0 <= A <= B (``str()``: one line)."""


def _seeds(spec: str) -> list[int]:
    """``A-B`` (or ``A``) as the seeds A..B; SeedSetError for anything else."""
    m = re.fullmatch(r"\s*(\d+)\s*(?:-\s*(\d+)\s*)?", spec, re.ASCII)
    lo, hi = (int(m[1]), int(m[2] or m[1])) if m else (0, -1)
    if hi < lo:
        raise SeedSetError(f"not a seed set A-B with 0 <= A <= B: {spec!r}"[:120].replace("\n", " "))
    return list(range(lo, hi + 1))


def current_open(keys=None) -> dict:
    """The scenario's searched choices as a search writes them (JSON values: a tuple as a list)."""
    return json.loads(json.dumps({k: getattr(SC.open, k) for k in (keys or SEARCHED)}))


# the hints of a resumed search (issue 15, second part): the new readings one at a time around the default
RESUME_HINTS = ({"time_increase": "before_action"}, {"drive_growth": {"NSoc": "human_not_near"}},
                {"drive_growth": {"NSoc": "not_lowered"}}, {"drive_growth": {"NRes": "robot_moved"}},
                {"drive_growth": {"NRes": "not_lowered"}}, {"no_activated_motivation": "none"})


def diff(o: dict, ref: dict, keys=SEARCHED) -> str:
    """The ``keys`` on which ``o`` differs from ``ref``, as ``key=JSON``."""
    # get: an open block read from a trials file may lack a key (error_search); missing on both sides is no change
    ch = [f"{k}={json.dumps(o[k])}" for k in keys if o.get(k) != ref.get(k)]
    return ", ".join(ch) or "(as the current default)"


def _space(optuna, space: Space = ISSUE_15) -> dict:
    """The search space's distributions (for trials added from an earlier search)."""
    class _Probe:  # records the distributions suggest() asks for
        def __init__(self):
            self.distributions = {}

        def _rec(self, name, dist):
            self.distributions[name] = dist
            return dist.to_external_repr(dist.to_internal_repr(
                dist.choices[0] if hasattr(dist, "choices") else dist.low))

        def suggest_float(self, name, low, high, step=None):
            return self._rec(name, optuna.distributions.FloatDistribution(low, high, step=step))

        def suggest_categorical(self, name, choices):
            return self._rec(name, optuna.distributions.CategoricalDistribution(choices))

    probe = _Probe()
    suggest(probe, current_open(space.searched), space)
    return probe.distributions


def run(trials: int, search_seeds: str, confirm_seeds: str, n_confirm: int, sampler_seed: int, out: str,
        workers: int = 1, resume_from: str | None = None, validate: tuple[str, int] | None = None) -> dict:
    """The search. ``resume_from``: a trials.jsonl of an earlier search (same seeds and objective): its
    trials enter the study as completed ones (choices searched only since then at their defaults), the
    new trials continue their numbering, and the confirmation ranks old and new together."""
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    s_seeds, c_seeds = _seeds(search_seeds), _seeds(confirm_seeds)
    if set(s_seeds) & set(c_seeds):
        raise SystemExit("calibrate.py: error: --search-seeds and --confirm-seeds overlap")
    validation = _validation(validate, s_seeds, c_seeds)  # a bad set stops us before the search, not after it
    earlier = read_trials(resume_from) if resume_from else []  # a bad file stops us before any output is cut
    outp = Path(out)
    outp.mkdir(parents=True, exist_ok=True)
    log = (outp / "trials.jsonl").open("w")
    start = current_open()
    t0 = time.time()
    study = optuna.create_study(direction="maximize",
                                sampler=optuna.samplers.TPESampler(seed=sampler_seed, multivariate=True))
    evals: list[dict] = []
    if resume_from:
        space = _space(optuna)
        for e in earlier:
            p = _params(e["open"])
            for k, dist in space.items():  # snap floats onto the grid (JSON round trips)
                if isinstance(dist, optuna.distributions.FloatDistribution) and dist.step:
                    p[k] = round(round((p[k] - dist.low) / dist.step) * dist.step + dist.low, 6)
            study.add_trial(optuna.trial.create_trial(params=p, distributions=space, value=e["score"]))
            evals.append(e)
        for hint in RESUME_HINTS:
            study.enqueue_trial(_params({**start, **hint}))
    else:
        study.enqueue_trial(_params(start))  # the current default is trial 0
        # and three hints from the earlier, independent search (issue 15: the initial Q value sets how long
        # the robot explores; a less busy human and a small scolding helped)
        for hint in ({"initial_q": 5.0}, {"initial_q": 10.0}, {"initial_q": 10.0, "human_no_intention_prob": 0.65,
                                                               "scold_drive_change": 3.0}):
            study.enqueue_trial(_params({**start, **hint}))

    def objective(trial):
        o = suggest(trial, start)
        return _scored(o, s_seeds, len(c_seeds), workers, trial.number, evals, log, t0, "trial")["score"]

    study.optimize(objective, n_trials=trials)
    log.close()
    return confirm(evals, time.time() - t0, trials, s_seeds, c_seeds, n_confirm, sampler_seed, outp, workers,
                   validation)


def _scored(o: dict, seeds: list[int], n_to: int, workers: int, number: int, evals: list, log, t0: float,
            what: str, label: str = "") -> dict:
    """One point scored on ``seeds`` (intervals rescaled to ``n_to`` seeds), numbered, kept in ``evals``,
    written to ``log`` and reported on one progress line."""
    e = evaluate(o, seeds, scale_to=n_to, workers=workers)
    e.pop("fidelity")
    e["trial"] = number
    evals.append(e)
    log.write(json.dumps(e) + "\n")
    log.flush()
    print(f"{what} {number:4d}: score {e['score']:6.2f}  inside {e['inside']:2d}/12  met {e['met']:2d}/10  "
          f"trends {e['trends']}/6  text {e['text_distance']}  HSR {e['HSR']:.3f} RSR {e['RSR']:.3f}  "
          f"{label + '  ' if label else ''}({time.time() - t0:.0f} s)", file=sys.stderr, flush=True)
    return e


class TrialsFileError(ValueError):
    """A trials file that cannot be read (``str()``: one line)."""


def read_trials(paths: str) -> list[dict]:
    """The trials of one or more (comma-separated) ``trials.jsonl`` files of earlier searches, each
    completed with the current defaults and scored as this search scores; TrialsFileError if any
    file or line cannot be."""
    evals = []
    for path in paths.split(","):
        try:
            lines = Path(path).read_text().splitlines()
        except (OSError, UnicodeDecodeError) as exc:
            raise TrialsFileError(f"{path}: {getattr(exc, 'strerror', None) or exc}") from None
        for n, line in enumerate(lines, 1):
            if not line.strip():
                continue
            try:
                e = json.loads(line)
                e["open"] = _with_defaults(e["open"])
                e["text_distance"] = text_distance(e["open"])
                e["score"] = score(e)
                _params(e["open"])
            except (ValueError, KeyError, TypeError, AttributeError) as exc:
                raise TrialsFileError(f"{path}:{n}: not a trial of this search ({type(exc).__name__}: "
                                      f"{str(exc)[:80]})".replace("\n", " ")) from None
            evals.append(e)
    return evals


def confirm_from(path: str, search_seeds: str, confirm_seeds: str, n_confirm: int, sampler_seed: int, out: str,
                 workers: int = 1, validate: tuple[str, int] | None = None) -> dict:
    """The confirmation stage alone, from a search's ``trials.jsonl`` (e.g. a search stopped early:
    with the same sampler seed its first N trials are those of ``--trials N``)."""
    evals = read_trials(path)
    outp = Path(out)
    outp.mkdir(parents=True, exist_ok=True)
    s_seeds, c_seeds = _seeds(search_seeds), _seeds(confirm_seeds)
    return confirm(evals, None, len(evals), s_seeds, c_seeds, n_confirm, sampler_seed, outp, workers,
                   _validation(validate, s_seeds, c_seeds))


def _validation(validate: tuple[str, int] | None, s_seeds: list[int], c_seeds: list[int]):
    """``(validate seeds, how many)`` checked apart from the search's and the confirmation's seeds."""
    if not validate or not validate[1]:
        return None
    v_seeds = _seeds(validate[0])
    if set(v_seeds) & (set(s_seeds) | set(c_seeds)):
        raise SystemExit("calibrate.py: error: --validate-seeds overlap the search or confirmation seeds")
    return v_seeds, validate[1]


def best_distinct(evals: list[dict], k: int | None = None) -> list[dict]:
    """The ``k`` best-scored points (default: all), each open block once (its best trial)."""
    seen, out = set(), []
    for e in sorted(evals, key=lambda e: -e["score"]):
        key = json.dumps(e["open"], sort_keys=True)
        if key not in seen:
            seen.add(key)
            out.append(e)
    return out[:k]


def confirm(evals, t_search, trials, s_seeds, c_seeds, n_confirm, sampler_seed, outp: Path, workers: int,
            validate: tuple[list[int], int] | None = None) -> dict:
    t0 = time.time()
    start = current_open()
    # confirm the best few distinct points (and the current default) on seeds never searched
    ranked = best_distinct(evals)
    v_seeds = []
    if validate:  # re-rank the best few on seeds of their own: the search's 8 seeds overrate its best points
        v_seeds, k = validate
        vlog = (outp / "validate.jsonl").open("w")
        again = []
        for p in ranked[:k]:
            v = evaluate(p["open"], v_seeds, scale_to=len(c_seeds), workers=workers)
            v.pop("fidelity")
            v["trial"], v["search_score"] = p["trial"], p["score"]
            again.append(v)
            vlog.write(json.dumps(v) + "\n")
            vlog.flush()
            print(f"validated trial {p['trial']}: score {p['score']:.2f} -> {v['score']:.2f}  inside {p['inside']} -> "
                  f"{v['inside']}/12  met {p['met']} -> {v['met']}/10", file=sys.stderr, flush=True)
        vlog.close()
        ranked = sorted(again, key=lambda e: -e["score"])
    picks = ranked[:n_confirm]
    if not any(p["open"] == start for p in picks) and any(e["open"] == start for e in evals):
        picks.append(next(e for e in evals if e["open"] == start))
    conf = []
    for p in picks:
        c = evaluate(p["open"], c_seeds, dods=SWEEPS["dod"], workers=workers)
        c["search"] = {k: p[k] for k in ("trial", "score", "inside", "met", "trends")}
        conf.append(c)
        print(f"confirmed trial {p['trial']}: inside {c['inside']}/12 met {c['met']}/10 trends {c['trends']}/6 "
              f"text {c['text_distance']}", file=sys.stderr, flush=True)
    chosen = select(conf)
    res = {"command": " ".join(sys.argv), "trials": trials, "search_seeds": s_seeds, "validate_seeds": v_seeds,
           "confirm_seeds": c_seeds,
           "sampler_seed": sampler_seed, "weights": {"trend": W_TREND, "distance": W_DIST, "text": W_TEXT},
           "search_s": t_search, "confirm_s": time.time() - t0, "confirmed": conf, "chosen": chosen["open"],
           "current": start}
    (outp / "joint.json").write_text(json.dumps(res, indent=1, default=str))
    print_result(res)
    return res


def select(conf: list[dict]) -> dict:
    """Fits best while staying closest to the text: among the confirmed points whose fit (numbers
    inside + statements met) is within 1 of the best fit, the one closest to the text; then the
    better fit, more trends, the smaller summed distance."""
    best_fit = max(c["inside"] + c["met"] for c in conf)
    near = [c for c in conf if c["inside"] + c["met"] >= best_fit - 1]
    return min(near, key=lambda c: (c["text_distance"], -(c["inside"] + c["met"]), -c["trends"], c["sum_distance"]))


def print_result(res: dict) -> None:
    cur = res["current"]
    took = f"{res['search_s'] / 60:.0f} min" if res["search_s"] else "time not recorded"
    v = res.get("validate_seeds")
    also = f"; best re-ranked on validation seeds {v[0]}-{v[-1]}" if v else ""
    print(f"\n{res['trials']} trials x {len(res['search_seeds'])} search seeds "
          f"({res['search_seeds'][0]}-{res['search_seeds'][-1]}), {took}{also}; confirmation on "
          f"seeds {res['confirm_seeds'][0]}-{res['confirm_seeds'][-1]}, {res['confirm_s'] / 60:.0f} min\n")
    print("| trial | changes from the current default | text distance | Table 4.5 inside (search -> confirm) | "
          "statements met (search -> confirm) | trends | HSR | RSR | summed distance |")
    print("|---|---|---|---|---|---|---|---|---|")
    for c in sorted(res["confirmed"], key=lambda c: (-(c["inside"] + c["met"]), c["text_distance"])):
        s = c["search"]
        mark = "**" if c["open"] == res["chosen"] else ""
        print(f"| {mark}{s['trial']}{mark} | {diff(c['open'], cur)} | {c['text_distance']} | {s['inside']} -> {c['inside']} | "
              f"{s['met']} -> {c['met']} | {c['trends']}/6 | {c['HSR']:.3f} | {c['RSR']:.3f} | {c['sum_distance']:.1f} |")
    print("\nChosen open block (searched keys):\n```json\n" + json.dumps(res["chosen"], indent=1) + "\n```")


# -- refinement around the adopted block (issue 15, third part) ----------------------------------

# an initial Q value two grid steps away as well: the issue's main lever (how long the robot explores)
def neighbours(o: dict, space: Space = ISSUE_15) -> list[dict]:
    """The one-step neighbourhood of an open block in the searched space: each float by the grid steps of
    ``space.steps`` (one by default) either way, each categorical set to each of its other values. Moves
    that cannot change a run are left out (``human_return_prob`` and ``on_leave_effects`` while the human
    never leaves)."""
    import optuna

    dists, here, out = _space(optuna, space), _params(o, space), []
    for name, dist in dists.items():
        if name in ("human_return_prob", "on_leave_effects") and not o["human_leave_prob"]:
            continue
        if isinstance(dist, optuna.distributions.FloatDistribution):
            values = [round(here[name] + sign * k * dist.step, 6) for k in space.steps.get(name, (1,)) for sign in (-1, 1)]
            values = [v for v in values if dist.low <= v <= dist.high]
        else:
            values = [c for c in dist.choices if c != here[name]]
        out += [suggest(optuna.trial.FixedTrial({**here, name: v}), o, space) for v in values]
    return out


def _moves(o: dict, ref: dict) -> dict:
    return {k: o[k] for k in SEARCHED if o[k] != ref[k]}


def refine(validate_seeds: str, confirm_seeds: str, n_confirm: int, combine: int, out: str, workers: int = 1) -> dict:
    """Around the current default: its one-step neighbours, then the best ``combine`` single moves
    combined in pairs and all together, each on ``validate_seeds`` (used by no earlier search or
    confirmation); the ``n_confirm`` best distinct points by their validation score (and the default)
    then confirmed on ``confirm_seeds`` exactly as a search's best points are (``confirm``). Choosing on
    validation seeds keeps the confirmation seeds out of the choice, and 20 validation seeds overrate
    a point far less than the search's 8 do."""
    v_seeds, c_seeds = _seeds(validate_seeds), _seeds(confirm_seeds)
    if set(v_seeds) & set(c_seeds):
        raise SystemExit("calibrate.py: error: --validate-seeds and --confirm-seeds overlap")
    outp = Path(out)
    outp.mkdir(parents=True, exist_ok=True)
    log = (outp / "refine.jsonl").open("w")
    start, t0, evals = current_open(), time.time(), []

    def run_point(o, label):
        return _scored(o, v_seeds, len(c_seeds), workers, len(evals), evals, log, t0, "point", label)

    base = run_point(start, "(the current default)")
    singles = [run_point(o, diff(o, start)) for o in neighbours(start)]
    better = sorted((e for e in singles if e["score"] > base["score"]), key=lambda e: -e["score"])
    best_moves: list[dict] = []
    for e in better:  # the best single move of each distinct key
        m = _moves(e["open"], start)
        if not any(m.keys() & b.keys() for b in best_moves):
            best_moves.append(m)
        if len(best_moves) == combine:
            break
    combos = [{**a, **b} for i, a in enumerate(best_moves) for b in best_moves[i + 1:]]
    if len(best_moves) > 2:
        combos.append({k: v for m in best_moves for k, v in m.items()})
    for c in combos:
        run_point({**start, **c}, diff({**start, **c}, start))
    log.close()
    return confirm(evals, time.time() - t0, len(evals), v_seeds, c_seeds, n_confirm, None, outp, workers)

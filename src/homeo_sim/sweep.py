"""Parameter sweeps of Section 4.2.3-4.2.5 (Figs 4.3-4.5) on one process pool.

Every (configuration, seed) pair is one job; all jobs of a sweep or of the whole report
share one ``ProcessPoolExecutor`` over all cores. A job is seeded only by its own seed and
results are put back in job order, so the numbers do not depend on the worker count.
Identical configurations (e.g. xi = 1 in the xi sweep and the pseudo-on point, both the
thesis's default run) are run once.

A job returns its end-of-run metrics (the layout of ``homeo-sim run``), its learning speed
(see ``learning_speed``) and, when asked, its curves downsampled to about
``CURVE_POINTS`` points (float32) so that pickling between processes stays cheap.
"""

from __future__ import annotations

import json
import math
import sys
from dataclasses import dataclass, field, replace
from typing import Iterable, Sequence

import numpy as np

from homeo_decision.scenario import Scenario
from homeo_decision.scenario.reference import DOD_SWEEP, PSEUDO_SWEEP, XI_SWEEP
from homeo_msgs_py.learning import DOD, PSEUDO_UPDATE, XI

from .metrics import INSECURE
from .parallel import keeps, parallel_map
from .runner import RUN_LEARNING, RunConfig, Simulation, cached_scenario
from .stats import aggregate

# the sweeps of the thesis: Fig 4.3 (xi), Fig 4.5 (DoD 0..1 by 0.1), Fig 4.4 (pseudo update on/off)
SWEEPS: dict[str, tuple] = {
    XI_SWEEP: (0.0, 0.25, 0.5, 0.75, 1.0, 1.5, 2.0),
    DOD_SWEEP: tuple(round(i / 10, 1) for i in range(11)),
    PSEUDO_SWEEP: (True, False),
}
SWEPT = {XI_SWEEP: XI, DOD_SWEEP: DOD, PSEUDO_SWEEP: PSEUDO_UPDATE}  # the learning parameter each sweep varies

# learning speed: the first iteration at which a trailing moving window of LEARNING_WINDOW
# iterations reaches HSR >= LEARN_HSR (resp. RSR >= LEARN_RSR); windows shorter than
# LEARNING_WINDOW (the first iterations) do not count.
LEARNING_WINDOW = 200
LEARN_HSR = 0.80
LEARN_RSR = 0.85
CURVE_POINTS = 500


def point_config(param: str, value, base: RunConfig) -> RunConfig:
    """The configuration of one sweep point (a value its parameter's declaration refuses: ValueError)."""
    spec = SWEPT.get(param)
    if spec is None:
        raise ValueError(f"unknown sweep parameter {param!r}; known: {', '.join(SWEEPS)}")
    return replace(base, **{spec.name: spec.check(value)})  # RunConfig's fields bear the parameters' names


def explicit(cfg: RunConfig, sc: Scenario) -> RunConfig:
    """``cfg`` with its learning parameters (DoD, xi, pseudo update) spelled out from the scenario, so
    equal runs compare equal."""
    value = lambda s: sc.learning[s.name] if getattr(cfg, s.name) is None else getattr(cfg, s.name)  # noqa: E731
    return replace(cfg, **{s.name: s.check(value(s)) for s in RUN_LEARNING})


def _key(cfg: RunConfig) -> str:
    d = {k: getattr(cfg, k) for k in cfg.__dataclass_fields__ if k not in ("seed", "trace", "save_q")}
    return json.dumps(d, sort_keys=True, default=repr)


# -- one job ---------------------------------------------------------------------------

@keeps
@dataclass
class JobResult:
    seed: int
    metrics: dict
    learning: dict  # {"HSR": t or None, "RSR": t or None, "both": t or None}
    curves: dict | None = None
    extra: dict = field(default_factory=dict)


def window_rates(expressed: np.ndarray, satisfied: np.ndarray, secure: np.ndarray, window: int) -> tuple[np.ndarray, np.ndarray]:
    """HSR and RSR over the trailing ``window`` iterations (fewer at the start); NaN HSR without intentions."""
    def trailing(x):
        c = np.concatenate(([0.0], np.cumsum(x, dtype=float)))
        hi = np.arange(1, len(x) + 1)
        lo = np.maximum(hi - window, 0)
        return c[hi] - c[lo], hi - lo

    n_exp, _ = trailing(expressed)
    n_sat, _ = trailing(satisfied)
    n_sec, n = trailing(secure)
    with np.errstate(invalid="ignore", divide="ignore"):
        hsr = np.where(n_exp > 0, n_sat / np.maximum(n_exp, 1), np.nan)
    return hsr, n_sec / n


def learning_speed(w_hsr: np.ndarray, w_rsr: np.ndarray, window: int = LEARNING_WINDOW,
                   hsr_level: float = LEARN_HSR, rsr_level: float = LEARN_RSR) -> dict:
    """First iteration (1-based) whose full trailing window reaches the level; None if never."""
    full = np.arange(1, len(w_hsr) + 1) >= window
    ok_h = full & (np.nan_to_num(w_hsr, nan=-1.0) >= hsr_level)
    ok_r = full & (w_rsr >= rsr_level)

    def first(mask):
        i = np.flatnonzero(mask)
        return int(i[0]) + 1 if len(i) else None

    return {"HSR": first(ok_h), "RSR": first(ok_r), "both": first(ok_h & ok_r)}


def downsample(n: int, points: int = CURVE_POINTS) -> np.ndarray:
    """Indices of the kept iterations: every k-th, ending at the last (k = n // points)."""
    k = max(1, n // points)
    return np.arange(n - 1, -1, -k)[::-1]


def run_job(cfg: RunConfig, curves: bool = False) -> JobResult:
    """One episode; returns metrics, learning speed and (optionally) downsampled curves."""
    sc = cached_scenario(cfg)
    sim = Simulation(sc, replace(cfg, series=True, trace=None, save_q=None))
    res = sim.run(cfg.iterations)
    s = res.series
    drives = np.column_stack([s["drives"][n] for n in sc.drive_names])
    secure = (drives < INSECURE).all(axis=1)
    w_hsr, w_rsr = window_rates(s["expressed"], s["satisfied"], secure, LEARNING_WINDOW)
    out = JobResult(cfg.seed, res.metrics, learning_speed(w_hsr, w_rsr), extra={"stages": res.stages})
    ctl = getattr(sim.policy, "controller", None)
    if ctl is not None:
        out.extra["dod_final"] = ctl.dod
        hist = ctl.history
        ts = np.array([h[0] for h in hist])
        vals = np.array([h[1] for h in hist])
    if curves:
        idx = downsample(cfg.iterations)
        f32 = lambda a: np.asarray(a, dtype=np.float32)[idx]  # noqa: E731
        out.curves = {
            "t": (idx + 1).astype(np.int32),
            "HSR": f32(s["HSR"]), "RSR": f32(s["RSR"]),
            "wHSR": f32(w_hsr), "wRSR": f32(w_rsr),
            "CDA": {k: f32(v) for k, v in s["CDA"].items()},
            "CEDA": {k: f32(v) for k, v in s["CEDA"].items()},
            "drives": {k: f32(v) for k, v in s["drives"].items()},
        }
        if ctl is not None:
            # DoD in force after each kept iteration (a step function of the adjustments)
            out.curves[DOD.name] = vals[np.searchsorted(ts, idx + 1, side="right") - 1].astype(np.float32)
    return out


def _run_job_args(a: tuple) -> JobResult:
    cfg, curves = a
    return run_job(cfg, curves)


def run_jobs(cfgs: Sequence[RunConfig], seeds: Iterable[int], workers=None, curves: bool = False,
             bar=None) -> list[list[JobResult]]:
    """Run every configuration with every seed; ``out[i][j]`` is cfgs[i] with seeds[j].

    Duplicate configurations run once. ``workers`` processes (default: all cores) or a
    ``parallel.Pool`` share the jobs; the results do not depend on it. ``bar`` counts finished jobs.
    """
    seeds = list(seeds)
    keys = [_key(c) for c in cfgs]
    uniq: dict[str, RunConfig] = {}
    for k, c in zip(keys, cfgs):
        uniq.setdefault(k, c)
    jobs = [(k, s) for k in uniq for s in seeds]
    results = parallel_map(_run_job_args, [(replace(uniq[k], seed=s), curves) for k, s in jobs], workers, bar)
    done = dict(zip(jobs, results))
    return [[done[(k, s)] for s in seeds] for k in keys]


def progress_bar(total: int, quiet: bool, desc: str | None = None, unit: str = "run"):
    from tqdm import tqdm

    return tqdm(total=total, unit=unit, desc=desc, disable=True if quiet else None, file=sys.stderr, leave=False,
                dynamic_ncols=True)


def n_jobs(cfgs: Sequence[RunConfig], seeds: Sequence[int]) -> int:
    return len({_key(c) for c in cfgs}) * len(list(seeds))


# -- summaries --------------------------------------------------------------------------

def median_time(ts: Sequence[int | None]) -> dict:
    """Median first-reach iteration over seeds (never = infinity) and how many seeds reached it."""
    vals = sorted(math.inf if t is None else t for t in ts)
    n = len(vals)
    med = vals[n // 2] if n % 2 else (vals[n // 2 - 1] + vals[n // 2]) / 2
    return {"median": None if math.isinf(med) else med, "reached": sum(t is not None for t in ts), "of": n,
            "per_seed": list(ts)}


def summarize_point(results: Sequence[JobResult], drive_names: Sequence[str]) -> dict:
    return aggregate([r.metrics for r in results], drive_names)


def sweep(param: str, base: RunConfig, seeds: Iterable[int], workers=None, quiet: bool = True,
          curves: bool = False) -> tuple[dict, list[list[JobResult]]]:
    """Run one sweep; returns ``{"param", "points": [{"value", "metrics"}]}`` and the raw job results."""
    if param not in SWEEPS:
        raise ValueError(f"unknown sweep parameter {param!r}; known: {', '.join(SWEEPS)}")
    seeds = list(seeds)
    sc = cached_scenario(base)
    base = explicit(base, sc)
    values = SWEEPS[param]
    cfgs = [point_config(param, v, base) for v in values]
    with progress_bar(n_jobs(cfgs, seeds), quiet, f"sweep {param}") as bar:
        raw = run_jobs(cfgs, seeds, workers, curves, bar)
    points = [{"value": v, "metrics": summarize_point(rs, sc.drive_names)} for v, rs in zip(values, raw)]
    return {"param": param, "points": points}, raw


def format_sweep(out: dict, n_seeds: int, serving: str) -> str:
    """A text table of a sweep: mean [95% interval] of the headline metrics per point (and the
    CDA of the scenario's serving drive)."""
    def cell(d):
        return f"{d['mean']:6.3f} [{d['ci95'][0]:6.3f},{d['ci95'][1]:6.3f}]" if n_seeds > 1 else f"{d['mean']:6.3f}"

    w = 23 if n_seeds > 1 else 6
    head = f"{out['param']:>7}  " + "  ".join(f"{h:>{w}}" for h in ("HSR", "RSR", "CDA all", "CEDA all", f"CDA {serving}"))
    lines = [head]
    for p in out["points"]:
        m = p["metrics"]
        v = p["value"]
        vs = ("on" if v else "off") if isinstance(v, bool) else f"{v:g}"
        cells = [m["HSR"], m["RSR"], m["CDA"]["all"], m["CEDA"]["all"], m["CDA"][serving]]
        lines.append(f"{vs:>7}  " + "  ".join(f"{cell(c):>{w}}" for c in cells))
    return "\n".join(lines)

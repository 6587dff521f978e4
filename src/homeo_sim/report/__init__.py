"""``homeo-sim report``: every table and figure of Section 4.2 (Table 4.5, Figs 4.1-4.5), the
baselines, and the adaptive DoD, as PNGs plus ``report.md`` and ``results.json``.

All runs (the default run, the three sweeps, the baselines and the adaptive DoD) are one set of
jobs on one process pool (``sweep.run_jobs``). ``analysis`` computes the numbers and checks,
``figures`` draws, ``markdown`` writes report.md. Comparisons with published numbers come from
the scenario's ``reference`` block; a scenario without one gets the runs, figures and tables only.
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

from ..parallel import slots
from ..runner import RunConfig, cached_scenario
from ..sweep import explicit, n_jobs, progress_bar, run_jobs, summarize_point
from .analysis import _analyse, _jsonable, baselines_for, report_configs  # noqa: F401 (re-exported)
from .figures import _figures, fig_dod, fig_pseudo, fig_xi
from .markdown import _markdown

__all__ = ["baselines_for", "build_report", "fig_dod", "fig_pseudo", "fig_xi", "report_configs"]

def build_report(out_dir: str | Path, seeds: int = 10, iterations: int = 5000, workers=None,
                 quiet: bool = False, scenario: str | None = None, overrides: tuple = (), first_seed: int = 0) -> dict:
    """Run everything, write the figures, ``report.md`` and ``results.json`` into ``out_dir``."""
    t0 = time.perf_counter()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    base0 = RunConfig(iterations=iterations, scenario=scenario, overrides=tuple(overrides))
    sc = cached_scenario(base0)
    base = explicit(base0, sc)
    cfgs = report_configs(base, baselines_for(sc))
    seed_list = list(range(first_seed, first_seed + seeds))
    labels = list(cfgs)
    nw = slots(workers, n_jobs(list(cfgs.values()), seed_list))
    with progress_bar(n_jobs(list(cfgs.values()), seed_list), quiet, "report") as bar:
        raw = run_jobs([cfgs[k] for k in labels], seed_list, workers, True, bar)
    R = dict(zip(labels, raw))
    t_runs = time.perf_counter() - t0
    names = sc.drive_names
    M = {k: summarize_point(v, names) for k, v in R.items()}
    data = _analyse(sc, base, R, M, seeds)
    data["first_seed"] = first_seed
    _figures(out, sc, R, M, data)
    t_total = time.perf_counter() - t0
    data["timing"] = {"runs_s": t_runs, "total_s": t_total, "workers": nw, "cpu_count": os.cpu_count(),
                      "jobs": n_jobs(list(cfgs.values()), seed_list)}
    (out / "report.md").write_text(_markdown(sc, base, M, data, seeds))
    (out / "results.json").write_text(json.dumps(_jsonable(data), indent=1))
    return data

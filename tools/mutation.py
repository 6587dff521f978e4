"""The core's mutation score, per module, with mutmut (a tool dependency: tools/requirements-mutation.lock).

Each module of the core that holds an equation of the thesis or a metric is mutated on its own, in its
own folder ``out/mutation/<module>/`` (mutmut's ``mutants/`` and its results stay there: a second run
tests only what changed, an interrupted one goes on where it stopped), against the fast ROS-free tests
below (mutmut runs, for each mutant, the tests that call the mutated function). A surviving mutant is
either killed by a test that hand-computes the case or listed in EQUIVALENT with the reason no test can
kill it; the score counts the listed ones apart.

Usage: make mutation [MODULES="reward objectq"] [MUTATION_JOBS=1] [MUTATION_BUDGET=1800]
       .venv/bin/python tools/mutation.py [--jobs N] [--budget SECONDS] [--survivors] [--no-run] [MODULE ...]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "out" / "mutation"

SIM = ["test_sim_world_human.py", "test_energy_readings.py", "test_fidelity.py", "test_scenario.py"]
DECISION = ["test_objectq.py", "test_reward.py", "test_baselines.py", "test_determinism.py"]
INTENTION = ["test_intention_core.py", "test_intention_cases.py"]  # the hand-computed cases of Section 2.3
MODULES = {  # module -> its source file and the fast ROS-free tests of it (with tests/test_core_cases.py: the
    # cases written by hand for its survivors); mutmut runs, for each mutant, those of them that call it
    "reward": ("src/homeo_decision/reward.py", DECISION),
    "objectq": ("src/homeo_decision/objectq.py", DECISION),
    "motivation": ("src/homeo_decision/motivation.py", ["test_motivation.py", "test_fidelity.py", *DECISION]),
    "drives": ("src/homeo_decision/drives.py", ["test_motivation.py", *SIM]),
    "agent": ("src/homeo_decision/agent.py", DECISION),
    "metrics": ("src/homeo_sim/metrics.py", ["test_metrics.py", "test_sim_world_human.py"]),
    "intention_model": ("src/homeo_intention/model.py", INTENTION),
    "intention_em": ("src/homeo_intention/em.py", INTENTION),
    "world": ("src/homeo_sim/world.py", SIM),
    "body": ("src/homeo_sim/body.py", SIM),
    "human": ("src/homeo_sim/human.py", SIM),
}

# mutant -> why no test can tell it from the original (it computes the same thing on every input)
DRAW = ("a uniform draw on [0, 1) compared with a probability: < and <= (>= and >) differ only when the draw equals "
        "it exactly, one 53-bit float in 2^53; no seed of a test reaches it")
CACHE = "the phase cache's span: the same phase is found again for each of its ticks"
SAFE_GUARDED = ("EM's guarded division where the plain one was: the same quotient wherever a total is > 0, and no "
                "total is 0 where the plain one was taken")
SAFE_PLAIN = "EM's plain division where the guarded one was, only with strength > 0: every total is then >= strength > 0"
EQUIVALENT: dict[str, str] = {
    # DecisionCore.phase caches the phase of a span of ticks; these change only when it is looked up again
    # (phase_at gives the same phase for every tick of the span), or an empty span the first lookup fills
    **{f"homeo_decision.agent.xǁDecisionCoreǁ{m}": CACHE for m in (
        "__init____mutmut_36", "__init____mutmut_37", "__init____mutmut_38", "phase__mutmut_4", "phase__mutmut_12",
        "phase__mutmut_14", "phase__mutmut_15", "phase__mutmut_16", "set_tick_offset__mutmut_7",
        "set_tick_offset__mutmut_9")},
    "homeo_decision.agent.xǁDecisionCoreǁphase__mutmut_23": 'float("INF") is float("inf")',
    **{f"homeo_decision.drives.xǁ{m}": "a clamp's boundary moved onto the bound gives the bound's own value (0 or 100)"
       for m in ("DriveDynamicsǁapply_action__mutmut_9", "DriveDynamicsǁapply_action__mutmut_14",
                 "DriveDynamicsǁapply_time__mutmut_11", "DriveDynamicsǁapply_time__mutmut_16",
                 "DriveModelǁset_body__mutmut_7", "DriveModelǁset_body__mutmut_12")},
    # pseudo_serving = satisfied: the serving drive d <= 100 (Definition 1) moved by -100 or -101 clamps to 0 alike
    "homeo_decision.agent.xǁDecisionCoreǁlearn__mutmut_60": "d - 101 clamps to 0 as d - 100 does, for any d <= 100",
    "homeo_decision.agent.xǁDecisionCoreǁlearn__mutmut_78": "k = -2 is no drive's index, as k = -1: no bonus either",
    "homeo_decision.drives.xǁDriveModelǁapply_feedback__mutmut_11": "feedback 0 returned earlier: >= 0 is > 0 for the rest",
    "homeo_decision.drives.xǁDriveDynamicsǁ__init____mutmut_10": "the drives outside the dynamics' subset are never read",
    "homeo_decision.drives.xǁDriveModelǁapply_time__mutmut_29": "no drive has index -2 either: none is skipped",
    # Eq 3.3's loop from index 0: intens[0] against itself as the top so far, > never holds, >= sets (0, intens[0])
    # again, and a NaN compares false either way
    "homeo_decision.motivation.x_dominant__mutmut_12": "argmax from index 0: intens[0] > itself never holds",
    "homeo_decision.motivation.x_dominant__mutmut_19": "argmax from index 0: intens[0] >= itself sets best 0 again",
    "homeo_decision.motivation.x_clamp__mutmut_4": "x = 0 gives 0.0 for x: the bound's own value (-0.0 == 0.0)",
    "homeo_decision.motivation.x_clamp__mutmut_9": "x = 100 gives 100.0 for x: the bound's own value",
    # the loader gives every prior as a tuple of Python floats (scenario/load.py's dist): a float64 array either way
    **{f"homeo_intention.model.x_prior_params__mutmut_{n}": "the priors as numpy takes them: floats make a float array "
       "with or without dtype=float" for n in (7, 9, 11, 13)},
    # em.py's `safe` only picks x / tot over np.divide(..., where=tot > 0), which divides the same wherever tot > 0:
    # a mutant that picks the guarded division more often computes the same; one that picks the plain one more
    # often does so only with strength > 0, where every total is >= strength > 0 for priors that are distributions
    # (P(I) sums to 1: sum y >= strength K; rho: n_k + strength; a channel's pseudo counts sum to strength)
    **{f"homeo_intention.em.xǁEMDataǁ__init____mutmut_{n}": SAFE_GUARDED for n in (41, 45, 46, 48, 50, 52)},
    **{f"homeo_intention.em.xǁEMDataǁ__init____mutmut_{n}": SAFE_PLAIN for n in (42, 43, 44, 47, 49, 51)},
    **{f"homeo_intention.em.x_em_step__mutmut_{n}": SAFE_GUARDED for n in (42, 47, 63, 74, 87)},
    "homeo_intention.em.xǁEMDataǁ__init____mutmut_99": "one more row of ones below the table, which no cell points at",
    "homeo_sim.metrics.x_stage_marks__mutmut_11": "range(10, 102, 10) is range(10, 101, 10): 10, 20, ..., 100",
    "homeo_sim.metrics.x_stage_marks__mutmut_21": "t = n (t <= n) is in the set already: | {n}",
    "homeo_sim.metrics.x_summarize__mutmut_28": "numpy's 0 / 0 is nan, as the guarded branch gives",
    "homeo_sim.human.xǁSimHumanǁadvance__mutmut_2": DRAW,  # u < p_leave
    "homeo_sim.human.xǁSimHumanǁadvance__mutmut_6": DRAW,  # u < p_return
    "homeo_sim.human.xǁSimHumanǁadvance__mutmut_14": DRAW,  # random() < p_none
    "homeo_sim.human.xǁSimHumanǁproposal__mutmut_1": DRAW,  # random() >= p_propose
    "homeo_sim.human.xǁSimHumanǁobserve__mutmut_7": DRAW,  # u() < noise
    "homeo_sim.human.xǁSimHumanǁobserve__mutmut_18": DRAW,  # x >= row[k]: a draw equal to a cumulative probability
    # Outcome's last fields: satisfied defaults to False; true_intention False for 0 compares and indexes as 0
    "homeo_sim.human.xǁSimHumanǁrespond__mutmut_13": "true_intention False for 0: False == 0 and indexes as 0 in every reader",
    "homeo_sim.human.xǁSimHumanǁrespond__mutmut_14": "satisfied=False is Outcome's default",
    "homeo_sim.human.xǁSimHumanǁrespond__mutmut_62": "satisfied=False is Outcome's default",
    # stream_from's fallback for an exception without text: set_state wraps KeyError/TypeError/ValueError in a
    # ValueError with its text, and numpy's OverflowError names the int: no exception reaching it has empty text
    **{f"homeo_sim.human.x_stream_from__mutmut_{n}": "the type-name fallback of an exception with no text, which "
       "no exception reaching it lacks" for n in (23, 26, 27)},
    "homeo_sim.metrics.xǁMetricRecorderǁrecord__mutmut_13": "x >= 0.0 for x > 0.0 adds x = 0 where it added 0",
    "homeo_sim.metrics.xǁMetricRecorderǁarrays__mutmut_16": "numpy's reshape takes any negative size as the unknown one",
    "homeo_sim.metrics.xǁMetricRecorderǁsummary__mutmut_22": 'float("NAN") is float("nan")',
    "homeo_sim.metrics.x_summarize__mutmut_33": 'float("NAN") is float("nan")',
    "homeo_sim.metrics.x_summarize__mutmut_9": "thresholds as numpy takes them: Python numbers make a float array either way",
    "homeo_sim.metrics.x_summarize__mutmut_11": "thresholds as numpy takes them: Python numbers make a float array either way",
    "homeo_sim.metrics.x_cumulative_series__mutmut_13": "thresholds as numpy takes them: a float array either way",
    "homeo_sim.metrics.x_cumulative_series__mutmut_15": "thresholds as numpy takes them: a float array either way",
    "homeo_sim.metrics.x_cumulative_series__mutmut_4": "t = 1..N as integers divides to the same floats",
    "homeo_sim.metrics.x_cumulative_series__mutmut_7": "t = 1..N as integers divides to the same floats",
    "homeo_sim.metrics.x_cumulative_series__mutmut_38": "np.errstate only silences warnings; the values are the same",
    "homeo_sim.metrics.x_cumulative_series__mutmut_39": "np.errstate only silences warnings; the values are the same",
    "homeo_sim.metrics.x_cumulative_series__mutmut_40": "np.errstate only silences warnings; the values are the same",
    "homeo_sim.metrics.x_cumulative_series__mutmut_41": "np.errstate only silences warnings; the values are the same",
}


def _mutmut_config(source: str, tests: list) -> str:
    """mutmut runs pytest in ``mutants/``, on its copy of tests/ (with the mutated src/ first on the path), with
    ``--rootdir=.``: the tests are selected there too (``tests/...``, the copies) and the repository's pytest
    settings read with ``-c``. A selection of the repository's own tests/ (or its rootdir) would import each test
    module from there first, and every mutant's run would then stop at pytest's "import file mismatch" with
    the copy, a failure mutmut counts as a kill; and a test written since the last run would be named by a
    path that does not exist from ``mutants/``, the same false kill."""
    tests = ", ".join(json.dumps(f"tests/{t}") for t in [*tests, "test_core_cases.py"])
    return ("[tool.mutmut]\n"
            'source_paths = ["src"]\n'
            'also_copy = ["docs"]\n'  # a test reads docs/ beside its tests/ (test_fidelity: FIDELITY.md)
            f"only_mutate = [{json.dumps(source)}]\n"
            f"pytest_add_cli_args_test_selection = [{tests}]\n"
            f'pytest_add_cli_args = ["-p", "no:xdist", "-p", "no:cacheprovider", "-c", {json.dumps(str(ROOT / "pyproject.toml"))}]\n')


def _fresh_copy(work: Path, source: str) -> None:
    """mutmut copies src/ once and never again: the unmutated modules are copied anew on every run, so that
    a module changed since (a test's helper, the scenario) is the one tested."""
    for p in (work / "mutants" / "src").rglob("*"):
        rel = p.relative_to(work / "mutants")
        if p.is_file() and str(rel) != source and not p.name.endswith(".meta"):
            p.unlink()


def run_module(name: str, jobs: int, budget: float) -> dict:
    source, tests = MODULES[name]
    work = OUT / name
    work.mkdir(parents=True, exist_ok=True)
    (work / "pyproject.toml").write_text(_mutmut_config(source, tests))
    for d in ("src", "tests", "docs"):  # what mutmut copies into mutants/ (also_copy)
        if not (work / d).exists():
            (work / d).symlink_to(ROOT / d)
    _fresh_copy(work, source)
    mutmut = [str(Path(sys.executable).with_name("mutmut"))]
    env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1")
    t = time.monotonic()
    # mutmut keeps a verdict until the mutant changes: the survivors of an earlier run lose theirs, so that the
    # tests written since for them are run on them
    meta = work / "mutants" / (source + ".meta")
    if meta.is_file():
        data = json.loads(meta.read_text())
        data["exit_code_by_key"] = {k: (None if v == 0 else v) for k, v in data["exit_code_by_key"].items()}
        meta.write_text(json.dumps(data))
    try:
        with open(work / "run.log", "w") as log:
            subprocess.run(["nice", "-n", "10", *mutmut, "run", "--max-children", str(jobs)], cwd=work, env=env,
                           stdout=log, stderr=subprocess.STDOUT, timeout=budget, check=False)
    except subprocess.TimeoutExpired:
        print(f"  {name}: stopped after its budget of {budget:.0f} s; the next run goes on from here", file=sys.stderr)
    return {"status": results(mutmut, work), "seconds": time.monotonic() - t}


def results(mutmut: list, work: Path) -> dict:
    """Every mutant's status as mutmut keeps it in ``work`` (empty before a first run)."""
    if not (work / "mutants").is_dir():
        return {}
    res = subprocess.run([*mutmut, "results", "--all", "true"], cwd=work, capture_output=True, text=True, check=False)
    status = {}
    for line in res.stdout.splitlines():
        key, _, st = line.strip().rpartition(": ")
        if key:
            status[key] = st
    return status


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("modules", nargs="*", help=f"default: all ({', '.join(MODULES)})")
    ap.add_argument("--jobs", type=int, default=int(os.environ.get("MUTATION_JOBS", "1")), help="mutmut's children")
    ap.add_argument("--budget", type=float, default=1800.0, help="wall seconds per module (then it stops; rerun goes on)")
    ap.add_argument("--survivors", action="store_true", help="list every surviving mutant (mutmut show NAME in its folder)")
    ap.add_argument("--no-run", action="store_true", help="print the scores kept on disk, running nothing")
    a = ap.parse_args(argv)
    unknown = [m for m in a.modules if m not in MODULES]
    if unknown:
        ap.error(f"unknown module {', '.join(unknown)} (known: {', '.join(MODULES)})")
    if shutil.which("mutmut", path=str(Path(sys.executable).parent)) is None:
        ap.error("mutmut is not installed in this venv: make mutation-setup")
    if a.jobs < 1 or a.budget <= 0:
        ap.error("--jobs and --budget must be positive")
    total = {"killed": 0, "equivalent": 0, "survived": 0, "other": 0}
    print(f"{'module':16} {'mutants':>7} {'killed':>6} {'equiv':>5} {'surv':>5} {'other':>5} {'score':>6} {'time':>6}")
    for name in a.modules or MODULES:
        mutmut = [str(Path(sys.executable).with_name("mutmut"))]
        r = {"status": results(mutmut, OUT / name), "seconds": 0.0} if a.no_run else run_module(name, a.jobs, a.budget)
        c = {k: 0 for k in total}
        survivors = []
        for key, st in r["status"].items():
            if st in ("killed", "timeout"):
                c["killed"] += 1
            elif key in EQUIVALENT:
                c["equivalent"] += 1
            elif st == "survived":
                c["survived"] += 1
                survivors.append(key)
            else:  # not checked, no tests, suspicious: counted against the score
                c["other"] += 1
                survivors.append(f"{key} ({st})")
        n = sum(c.values())
        score = c["killed"] / (n - c["equivalent"]) if n > c["equivalent"] else float("nan")
        print(f"{name:16} {n:7d} {c['killed']:6d} {c['equivalent']:5d} {c['survived']:5d} {c['other']:5d} "
              f"{score:6.1%} {r['seconds']:5.0f}s", flush=True)
        if a.survivors:
            for s in survivors:
                print(f"    {s}")
        for k in total:
            total[k] += c[k]
    n = sum(total.values())
    if n > total["equivalent"]:
        print(f"{'core':16} {n:7d} {total['killed']:6d} {total['equivalent']:5d} {total['survived']:5d} "
              f"{total['other']:5d} {total['killed'] / (n - total['equivalent']):6.1%}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

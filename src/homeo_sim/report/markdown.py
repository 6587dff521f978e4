"""``report.md``: the report's tables and figures as markdown, from the analysed data."""

from __future__ import annotations

import json

from homeo_decision.scenario.reference import DOD_SWEEP, PSEUDO_SWEEP, XI_SWEEP
from homeo_msgs_py.learning import DOD, XI

from ..runner import RunConfig
from ..sweep import LEARN_HSR, LEARN_RSR, LEARNING_WINDOW
from .analysis import BASELINES, POLICY_LABELS, _fmt, _t
from .fidelity import format_goals

def _markdown(sc, base: RunConfig, M: dict, d: dict, seeds: int) -> str:
    names = sc.drive_names
    serving = names[sc.serving]
    ref = sc.reference  # published numbers to compare with; None: the comparisons are skipped
    T45 = ref.metrics if ref is not None else {}
    says = ref.statements if ref is not None else None
    tm = d["timing"]
    L = []
    w = L.append
    w("# Section 4.2 of the thesis, re-run\n")
    first = d.get("first_seed", 0)
    w(f"{seeds} seeds ({first}..{first + seeds - 1}) x {base.iterations} iterations per configuration; scenario `{sc.name}` "
      f"(Q-layout fingerprint `{sc.fingerprint()}`), defaults DoD {base.dod}, xi {base.xi}, pseudo update "
      f"{'on' if base.pseudo_update else 'off'}. Every number below comes from this run; intervals are Student-t 95% "
      "intervals over seeds. "
      + ("The thesis's figures did not survive in our copy of the text, so beside the sweeps we quote what its prose "
         "says about them.\n" if says else
         f"The scenario has {'no reference block' if ref is None else 'no statements in its reference block'}, "
         "so the comparisons with the thesis's statements are skipped.\n"))
    w(f"Wall time: **{tm['total_s']:.1f} s** for {tm['jobs']} runs on {tm['workers']} worker processes "
      f"({tm['cpu_count']} cores; {tm['runs_s']:.1f} s running, the rest plotting).\n")
    w("Open choices of the scenario in force (see docs/FIDELITY.md):\n")
    w("```json\n" + json.dumps(d["open"], sort_keys=True) + "\n```\n")

    w("## Trend checks\n")
    w("| check | criterion | ours | result |\n|---|---|---|---|")
    for c in d["checks"]:
        w(f"| {c['check']} | {c['criterion']} | {c['ours']} | {'reproduced' if c['ok'] else '**not reproduced**'} |")
    fails = [c for c in d["checks"] if not c["ok"]]
    if fails:
        w("\nWhy the failing checks fail (numbers from this run):\n")
        for c in fails:
            w(f"- **{c['check']}**: {c['why']}")
    w("")

    fid = d["fidelity"]
    if ref is not None:
        w("## Fidelity score\n")
        w(f"**{fid['summary']}.** Per published number: the relative error of our mean over all {seeds} seeds, "
          "(ours - published) / published. Each statement of the text about the sweeps has a criterion written from "
          f"the text (the scenario's `reference.criteria`), checked on each disjoint set of {fid['set_size']} "
          "seeds. Neither rewards noise: more seeds make our mean firmer and the sets more. (The columns *inside* "
          "and *distance* are issue 15's score: whether the published number lies in our 95% interval, and how far "
          f"in half-widths of it, at least {100 * fid['half_width_floor']:g}% of the published value.)\n")
        goals = fid.get("goals", {})
        if goals:
            w("Goals (issue 25): " + format_goals(goals, "**not met**") + ".\n")
        w("| metric | ours: mean [95% interval] | thesis | error | inside | distance (half-widths) |\n"
          "|---|---|---|---|---|---|")
        for r in fid["table"]:
            dg = 3 if r["metric"] in ("HSR", "RSR") else 2
            w(f"| {r['metric'].replace('.', ' ')} | {r['mean']:.{dg}f} [{r['ci95'][0]:.{dg}f}, {r['ci95'][1]:.{dg}f}] | "
              f"{r['thesis']:g} | {100 * r['error']:+.1f}% | {'yes' if r['inside'] else 'no'} | {r['distance']:.2f} |")
        w("")
    if d["statements"]:
        w("## What the thesis says about its figures, against ours\n")
        w(f"*ours* and *holds* are over all {seeds} seeds; *sets* counts the disjoint sets of "
          f"{fid.get('set_size', seeds)} seeds on which the statement holds.\n")
        w("| figure | the thesis says | criterion | ours | holds | sets |\n|---|---|---|---|---|---|")
        for st in d["statements"]:
            w(f"| {st['figure']} | {st['thesis']} | {st['criterion']} | {st['ours']} | {'yes' if st['agrees'] else '**no**'} "
              f"| {st.get('held', '')}/{st.get('of', '')} |")
        w("")
    m = d["table_4_5"]
    w("## Table 4.5: metrics after the run\n")
    if ref is None:
        w("No reference block in the scenario: no published values to compare with.\n")
    thesis = (lambda v: f" {v} |") if ref is not None else (lambda v: "")  # the reference column, when there is one
    w("| metric | drive | ours: mean [95% interval] |" + (" thesis |\n|---|---|---|---|" if ref is not None else "\n|---|---|---|"))
    for k in ("HSR", "RSR"):
        w(f"| {k} | | {_fmt(m[k])} |" + thesis(T45.get(k, "")))
    for k in ("CDA", "CEDA"):
        for n in list(names) + ["all"]:
            w(f"| {k} | {n} | {_fmt(m[k][n], 2)} |" + thesis(T45.get(k, {}).get(n, "")))
    w("\n![Fig 4.1](fig4_1_drives.png)\n\n![Fig 4.2](fig4_2_hsr_rsr.png)\n")

    def sweep_table(param, label, fmtv):
        w(f"| {label} | HSR | RSR | CDA all | CEDA all | CDA {names[sc.serving]} |\n|---|---|---|---|---|---|")
        for p in d["sweeps"][param]:
            mm = p["metrics"]
            w(f"| {fmtv(p['value'])} | {_fmt(mm['HSR'])} | {_fmt(mm['RSR'])} | {_fmt(mm['CDA']['all'], 1)} | "
              f"{_fmt(mm['CEDA']['all'], 2)} | {_fmt(mm['CDA'][names[sc.serving]], 2)} |")

    w("## Fig 4.3: motivation factor xi\n")
    sweep_table(XI_SWEEP, XI.name, lambda v: f"{v:g}")
    w(("\nThe thesis says: " + "; ".join(says[XI_SWEEP]) + ".\n" if says else "") + "\n![Fig 4.3](fig4_3_xi.png)\n")

    w("## Fig 4.4: pseudo update\n")
    sweep_table(PSEUDO_SWEEP, "pseudo update", lambda v: "on" if v else "off")
    e = d["pseudo_early"]
    w("\nEarly stage (cumulative values after 500 and 1000 iterations; learning speed as defined under Baselines):\n")
    w(f"| pseudo update | HSR@500 | HSR@1000 | CDA {names[sc.serving]}@500 | CDA {names[sc.serving]}@1000 | "
      f"first window HSR >= {LEARN_HSR} (median) |\n|---|---|---|---|---|---|")
    for k in ("on", "off"):
        x = e[k]
        w(f"| {k} | {_fmt(x['HSR@500'])} | {_fmt(x['HSR@1000'])} | {_fmt(x[f'CDA_{serving}@500'], 2)} | "
          f"{_fmt(x[f'CDA_{serving}@1000'], 2)} | {_t(x['learn_HSR']['median'])} ({x['learn_HSR']['reached']}/{x['learn_HSR']['of']}) |")
    if says:
        w("\nThe thesis says: " + "; ".join(says[PSEUDO_SWEEP]) + ".\n")
    w("![Fig 4.4](fig4_4_pseudo.png)\n\n![Fig 4.4, first 1000 iterations](fig4_4_pseudo_early.png)\n")

    w("## Fig 4.5: Degree of Dedication\n")
    sweep_table(DOD_SWEEP, "DoD", lambda v: f"{v:g}")
    w(("\nThe thesis says: " + "; ".join(says[DOD_SWEEP]) + ".\n" if says else "") + "\n![Fig 4.5](fig4_5_dod.png)\n")

    w("## Baselines\n")
    w(f"Learning speed = the first iteration at which the rate over the trailing {LEARNING_WINDOW} iterations (a moving "
      f"window, not the cumulative series; only full windows count) reaches HSR >= {LEARN_HSR}, RSR >= {LEARN_RSR}, "
      "or both at once; median over seeds (a seed that never gets there counts as infinitely late), with the number "
      "of seeds that got there.\n")
    w(f"| policy | HSR | RSR | HSR x RSR | CDA all | CEDA all | last {LEARNING_WINDOW} it.: HSR / RSR | "
      f"HSR >= {LEARN_HSR} at | RSR >= {LEARN_RSR} at | both at |\n|---|---|---|---|---|---|---|---|---|---|")
    for p in ["objectq"] + [b for b in BASELINES if b in d["policies"]] + ["adaptive"]:
        x = d["policies"][p]
        mm = x["metrics"]
        lr = x["learn"]
        lt = lambda k: f"{_t(lr[k]['median'])} ({lr[k]['reached']}/{lr[k]['of']})"  # noqa: E731
        w(f"| {POLICY_LABELS[p]} | {_fmt(mm['HSR'])} | {_fmt(mm['RSR'])} | {_fmt(x['HSRxRSR'])} | "
          f"{_fmt(mm['CDA']['all'], 1)} | {_fmt(mm['CEDA']['all'], 2)} | {x['last_window']['HSR']['mean']:.3f} / "
          f"{x['last_window']['RSR']['mean']:.3f} | {lt('HSR')} | {lt('RSR')} | {lt('both')} |")
    rules = f"a fixed-priority selector ({', '.join(r.name for r in sc.rule_policy)})" if sc.rule_policy else \
        "not run (the scenario has no rule_policy block)"
    w(f"\nrandom: a uniformly random valid action. threshold rules: {rules} at the scenario's activation thresholds, "
      "knowing the intention->action mapping. flat Q-learning: "
      "Eq 2.9 over the full Cartesian state, same reward, softmax and schedule, no proposals. homeostatic, no "
      "feedback: Object-Q without the feedback reward and without pseudo updates (the earlier works). "
      "docs/EXPERIMENTS.md has the details.\n")
    w("![Baselines](baselines.png)\n\n![Learning curves](baselines_learning.png)\n")

    w("## Beyond the thesis: adaptive DoD\n")
    a = d["adaptive"]
    bf = a["best_fixed"]
    pa = d["policies"]["adaptive"]
    s = a["settings"]
    w(f"DoD starts at {base.dod} and moves every {s['period']} iterations by "
      f"clip({s['gain']} x (user shortfall - robot shortfall), +-{s['max_step']}), where the shortfalls are the "
      f"distances below target_hsr {s['target_hsr']} and target_rsr {s['target_rsr']} of moving averages "
      f"(time constant {s['horizon']:g}) of the feedback and of the secure indicator (Eq 4.7). See docs/EXPERIMENTS.md.\n")
    w("| | DoD | HSR | RSR | HSR x RSR |\n|---|---|---|---|---|")
    w(f"| adaptive | ends at {_fmt(a['dod_final'], 2)} | {_fmt(pa['metrics']['HSR'])} | {_fmt(pa['metrics']['RSR'])} | "
      f"{_fmt(pa['HSRxRSR'])} |")
    w(f"| best fixed DoD (by HSR x RSR over the 0.1 grid and {base.dod:g}, chosen after the fact) | {bf[DOD.name]:g} | {_fmt(bf['metrics']['HSR'])} | "
      f"{_fmt(bf['metrics']['RSR'])} | {_fmt(bf['HSRxRSR'])} |")
    po = d["policies"]["objectq"]
    w(f"| thesis default | {base.dod:g} | {_fmt(po['metrics']['HSR'])} | {_fmt(po['metrics']['RSR'])} | "
      f"{_fmt(po['HSRxRSR'])} |")
    pdf = a["paired_diff"]
    better = sum(x > 0 for x in pdf["per_seed"])
    w(f"\nAdaptive minus best fixed DoD on HSR x RSR, paired by seed: {pdf['mean']:+.3f} "
      f"[{pdf['ci95'][0]:+.3f}, {pdf['ci95'][1]:+.3f}]; adaptive is ahead in {better} of {len(pdf['per_seed'])} seeds "
      "(the best fixed DoD is picked with hindsight on these same seeds, so it is an optimistic reference).\n")
    w("![Adaptive DoD](adaptive_dod.png)\n")
    return "\n".join(L) + "\n"

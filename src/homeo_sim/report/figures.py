"""The report's figures (matplotlib, Agg backend): Figs 4.1-4.5, the baselines and the adaptive DoD.

``fig_xi``, ``fig_dod`` and ``fig_pseudo`` are also drawn by ``homeo-sim sweep --out``. Lines
of published values are drawn only when the scenario has a ``reference`` block.
"""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

import numpy as np

from homeo_decision.scenario.reference import DOD_SWEEP, XI_SWEEP
from homeo_msgs_py.learning import DOD

from ..stats import t975
from ..sweep import LEARN_HSR, LEARN_RSR, LEARNING_WINDOW, JobResult
from .analysis import BASELINES, POLICY_LABELS, _curve, _get

def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _finish(plt, fig, path, title: str | None = None) -> None:
    """Title, lay out, write the PNG, and free the figure (a report draws many)."""
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _band(arr: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mean and 95% t-interval over seeds (rows), NaN-aware."""
    n = np.sum(~np.isnan(arr), axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.nanmean(arr, axis=0) if arr.shape[0] else arr
        if arr.shape[0] > 1:
            sd = np.nanstd(arr, axis=0, ddof=1)
            h = np.array([t975(int(k) - 1) if k > 1 else np.nan for k in n]) * sd / np.sqrt(np.maximum(n, 1))
        else:
            h = np.zeros_like(mean)
    return mean, mean - h, mean + h


def _plot_band(ax, t, arr, label, color=None, lw=1.5):
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        m, lo, hi = _band(arr)
    line, = ax.plot(t, m, label=label, color=color, lw=lw)
    ax.fill_between(t, lo, hi, color=line.get_color(), alpha=0.2, lw=0)
    return line


def _figures(out: Path, sc, R: dict, M: dict, d: dict) -> None:
    plt = _plt()
    names = sc.drive_names
    base = R["base"]
    t = base[0].curves["t"]
    ref = sc.reference.metrics if sc.reference is not None else {}  # published values, drawn dotted
    st = sc.reference.statements if sc.reference is not None else None

    # Fig 4.1: drives, CDA, CEDA over time (two panels a row)
    rows = max(1, (len(names) + 1) // 2)
    fig, axes = plt.subplots(rows, 2, figsize=(11, 3.5 * rows), sharex=True, squeeze=False)
    for ax, n in zip(axes.flat, names):
        ax.plot(t, base[0].curves["drives"][n], lw=0.5, color="0.6", label=f"{n} (seed 0, every {t[1] - t[0]}th it.)")
        _plot_band(ax, t, _curve(base, "CDA", n), "CDA (mean, 95% band)", "C0")
        _plot_band(ax, t, _curve(base, "CEDA", n), "CEDA (mean, 95% band)", "C3")
        for k, col in (("CDA", "C0"), ("CEDA", "C3")):
            if n in ref.get(k, {}):
                ax.axhline(ref[k][n], color=col, ls=":", lw=1, label=f"thesis {k} {ref[k][n]}")
        ax.set_title(n)
        ax.set_ylim(0, 100)
        ax.legend(fontsize=7, loc="upper right")
    for ax in axes[-1]:
        ax.set_xlabel("iteration")
    for ax in list(axes.flat)[len(names):]:
        ax.axis("off")
    _finish(plt, fig, out / "fig4_1_drives.png", f"Fig 4.1: drives over time ({len(base)} seeds)")

    # Fig 4.2: HSR and RSR over time
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for ax, k in zip(axes, ("HSR", "RSR")):
        arr = _curve(base, k)
        for row in arr:
            ax.plot(t, row, color="0.8", lw=0.5)
        _plot_band(ax, t, arr, f"{k} (mean, 95% band)", "C0")
        if k in ref:
            ax.axhline(ref[k], color="C3", ls=":", label=f"thesis, end: {ref[k]}")
        ax.set_ylim(0, 1.02)
        ax.set_xlabel("iteration")
        ax.set_title({"HSR": "(a) Human Satisfaction Rate", "RSR": "(b) Robot Secure Rate"}[k])
        ax.legend(fontsize=8, loc="lower right")
    _finish(plt, fig, out / "fig4_2_hsr_rsr.png", "Fig 4.2: cumulative HSR and RSR")

    fig_xi(out / "fig4_3_xi.png", d["sweeps"][XI_SWEEP], st)
    other = st["pseudo_unaffected_drive"] if st else None
    fig_pseudo(out / "fig4_4_pseudo.png", R["pseudo=True"], R["pseudo=False"], sc.drive_names[sc.serving], other=other)
    fig_pseudo(out / "fig4_4_pseudo_early.png", R["pseudo=True"], R["pseudo=False"], sc.drive_names[sc.serving],
               until=1000, other=other)
    fig_dod(out / "fig4_5_dod.png", d["sweeps"][DOD_SWEEP], names, st)

    # baselines: end metrics and learning curves
    baselines = [p for p in BASELINES if p in d["policies"]]
    pols = ["objectq"] + baselines + ["adaptive"]
    keys = {"objectq": "base", "adaptive": "adaptive"} | {p: f"policy={p}" for p in baselines}
    fig, ax = plt.subplots(figsize=(11, 4))
    width = 0.26
    x = np.arange(len(pols))
    for j, (k, lab) in enumerate((("HSR", "HSR"), ("RSR", "RSR"), ("HSRxRSR", "HSR x RSR"))):
        vals = [d["policies"][p]["HSRxRSR"] if k == "HSRxRSR" else d["policies"][p]["metrics"][k] for p in pols]
        m = np.array([v["mean"] for v in vals])
        err = np.array([[v["mean"] - v["ci95"][0], v["ci95"][1] - v["mean"]] for v in vals]).T
        ax.bar(x + (j - 1) * width, m, width, yerr=err, capsize=2, label=lab)
    ax.set_xticks(x, [POLICY_LABELS[p] for p in pols], fontsize=8)
    ax.set_ylim(0, 1.05)
    ax.legend(fontsize=8)
    ax.set_title(f"Policies after {d['iterations']} iterations (mean, 95% interval)")
    _finish(plt, fig, out / "baselines.png")

    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for ax, k, lvl in zip(axes, ("wHSR", "wRSR"), (LEARN_HSR, LEARN_RSR)):
        for p in pols:
            _plot_band(ax, t, _curve(R[keys[p]], k), POLICY_LABELS[p], lw=1.2)
        ax.axhline(lvl, color="k", ls=":", lw=1)
        ax.set_ylim(0, 1.02)
        ax.set_xlabel("iteration")
        ax.set_title(f"{k[1:]} over the last {LEARNING_WINDOW} iterations")
    axes[0].legend(fontsize=7, loc="lower right")
    _finish(plt, fig, out / "baselines_learning.png",
            "Learning speed: moving-window rates (dotted: the levels of the learning-speed measure)")

    # adaptive DoD
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    ad = R["adaptive"]
    arr = _curve(ad, DOD.name)
    for row in arr:
        axes[0].plot(t, row, color="0.8", lw=0.5)
    _plot_band(axes[0], t, arr, "adaptive DoD (mean, 95% band)", "C0")
    fixed, best = d["base"][DOD.name], d["adaptive"]["best_fixed"][DOD.name]
    axes[0].axhline(fixed, color="C3", ls=":", label=f"fixed default {fixed}")
    axes[0].axhline(best, color="C2", ls="--", label=f"best fixed DoD (HSR x RSR): {best}")
    axes[0].set_ylim(0, 1)
    axes[0].set_xlabel("iteration")
    axes[0].legend(fontsize=8)
    axes[0].set_title("DoD over time")
    ax = axes[1]
    for p in d["sweeps"][DOD_SWEEP]:
        m = p["metrics"]
        ax.errorbar(m["RSR"]["mean"], m["HSR"]["mean"], xerr=_err(m["RSR"]), yerr=_err(m["HSR"]), fmt="o", color="C0",
                    ms=4, capsize=2)
        ax.annotate(f"{p['value']:g}", (m["RSR"]["mean"], m["HSR"]["mean"]), fontsize=7, xytext=(3, 3),
                    textcoords="offset points")
    m = d["policies"]["adaptive"]["metrics"]
    ax.errorbar(m["RSR"]["mean"], m["HSR"]["mean"], xerr=_err(m["RSR"]), yerr=_err(m["HSR"]), fmt="*", color="C3",
                ms=12, capsize=2, label="adaptive DoD")
    ax.set_xlabel("RSR")
    ax.set_ylabel("HSR")
    ax.set_title("Fixed DoD (labels) vs adaptive")
    ax.legend(fontsize=8)
    _finish(plt, fig, out / "adaptive_dod.png")


def _err(s: dict) -> list:
    return [[s["mean"] - s["ci95"][0]], [s["ci95"][1] - s["mean"]]]


def _sweep_series(points, *path):
    vals = [_get(p["metrics"], *path) for p in points]
    m = np.array([v["mean"] for v in vals])
    err = np.array([[v["mean"] - v["ci95"][0], v["ci95"][1] - v["mean"]] for v in vals]).T
    return m, err


def fig_xi(path: Path, points: list, statements: dict | None = None) -> None:
    """Fig 4.3: CDA/CEDA (a) and HSR/RSR (b) against xi (with the reference's RSR(xi 0) bound, if any)."""
    plt = _plt()
    x = [p["value"] for p in points]
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for k in ("CDA", "CEDA"):
        m, e = _sweep_series(points, k, "all")
        axes[0].errorbar(x, m, yerr=e, marker="o", capsize=3, label=f"{k} (all drives)")
    axes[0].set_title("(a) CDA and CEDA")
    for k in ("HSR", "RSR"):
        m, e = _sweep_series(points, k)
        axes[1].errorbar(x, m, yerr=e, marker="o", capsize=3, label=k)
    if statements:
        xb = statements["rsr_at_xi0_below"]
        axes[1].axhline(xb, color="0.5", ls=":", lw=1, label=f"thesis: RSR(xi 0) below {xb:g}")
    axes[1].set_ylim(0, 1.02)
    axes[1].set_title("(b) HSR and RSR")
    for ax in axes:
        ax.set_xlabel("motivation factor xi")
        ax.legend(fontsize=8)
    _finish(plt, fig, path, "Fig 4.3: effect of the motivation factor (mean, 95% interval)")


def fig_dod(path: Path, points: list, names: Sequence[str], statements: dict | None = None) -> None:
    """Fig 4.5: HSR, RSR, CDA and CEDA against DoD (with the reference's HSR at DoD 0, if any)."""
    plt = _plt()
    x = [p["value"] for p in points]
    fig, axes = plt.subplots(2, 2, figsize=(11, 7), sharex=True)
    for ax, k in zip(axes[0], ("HSR", "RSR")):
        m, e = _sweep_series(points, k)
        ax.errorbar(x, m, yerr=e, marker="o", capsize=3, label="ours")
        ax.set_ylim(0, 1.02)
        ax.set_title(f"({'a' if k == 'HSR' else 'b'}) {k}")
    if statements:
        h0 = statements["hsr_at_dod0"]
        axes[0][0].plot([0], [h0], "s", color="C3", label=f"thesis: about {h0:g} at DoD 0")
    axes[0][0].legend(fontsize=8)
    for ax, k, lab in zip(axes[1], ("CDA", "CEDA"), ("c", "d")):
        for n in list(names) + ["all"]:
            m, e = _sweep_series(points, k, n)
            ax.errorbar(x, m, yerr=e, marker="o", ms=3, capsize=2, label=n, lw=2 if n == "all" else 1)
        ax.set_title(f"({lab}) {k}")
        ax.set_xlabel("Degree of Dedication")
        ax.legend(fontsize=7)
    _finish(plt, fig, path, "Fig 4.5: effect of the Degree of Dedication (mean, 95% interval)")


def fig_pseudo(path: Path, on: Sequence[JobResult], off: Sequence[JobResult], serving: str, until: int | None = None,
               other: str | None = None) -> None:
    """Fig 4.4: HSR, RSR, CDA, CEDA, the serving drive and (panel f) ``other`` drive over time, with and without
    pseudo update (the thesis shows its battery drive there: the reference block names it)."""
    plt = _plt()
    t = on[0].curves["t"]
    sel = slice(None) if until is None else slice(0, int(np.searchsorted(t, until, side="right")))
    panels = [("(a) HSR", ("HSR",)), ("(b) RSR", ("RSR",)), ("(c) CDA (all)", ("CDA", "all")),
              ("(d) CEDA (all)", ("CEDA", "all")), (f"(e) {serving}", ("drives", serving))]
    if other is not None and other in on[0].curves["drives"]:
        panels.append((f"(f) {other}", ("drives", other)))
    fig, axes = plt.subplots(2, 3, figsize=(13, 7))
    for ax, (title, path_) in zip(axes.flat, panels):
        for rs, lab, col in ((on, "with pseudo update", "C0"), (off, "without", "C3")):
            _plot_band(ax, t[sel], _curve(rs, *path_)[:, sel], lab, col, lw=1.2)
        ax.set_title(title + (" (raw, mean over seeds)" if path_[0] == "drives" else ""))
        ax.set_xlabel("iteration")
        if path_[0] in ("HSR", "RSR"):
            ax.set_ylim(0, 1.02)
    axes.flat[0].legend(fontsize=8)
    for ax in list(axes.flat)[len(panels):]:
        ax.axis("off")
    _finish(plt, fig, path, "Fig 4.4: effect of the pseudo update" + (f", first {until} iterations" if until else "")
            + f" ({len(on)} seeds, 95% bands)")

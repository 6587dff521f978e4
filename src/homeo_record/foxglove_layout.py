"""A Foxglove layout for a live run (``--foxglove``), built from a scenario's names.

``python -m homeo_record.foxglove_layout [SCENARIO] > docs/foxglove-layout.json`` writes the one in
the repository (the thesis scenario; tests/test_live.py checks it is current). Panels: drives with
their thresholds, intensities, the dominant motivation over time, HSR and RSR of the run so far,
the interaction (action, feedback, proposal) and a Publish panel that plays the human
(``--human person``).
"""

from __future__ import annotations

import json
import sys


def _plot(title: str, paths: list[str], y: tuple | None = None) -> dict:
    cfg = {"title": title, "paths": [{"value": p, "enabled": True, "timestampMethod": "receiveTime"} for p in paths],
           "showLegend": True, "legendDisplay": "floating", "xAxisVal": "timestamp", "followingViewWidth": 60}
    if y:
        cfg["minYValue"], cfg["maxYValue"] = y
    return cfg


def _states(title: str, paths: list[str]) -> dict:
    return {"title": title, "paths": [{"value": p, "timestampMethod": "receiveTime"} for p in paths],
            "isSynced": True}


def layout(sc) -> dict:
    drives = [f"/homeo/drives.drives.{d}" for d in sc.drive_names]
    cfg = {
        "Plot!drives": _plot("drives (Table 4.2)", drives, (0, 100)),
        "Plot!intensities": _plot("intensities (Eq 3.2)", [f"/homeo/drives.intensities.{m}" for m in sc.motivation_names]),
        "StateTransitions!mdom": _states("dominant motivation (Eq 3.3) and intention",
                                         ["/homeo/drives.m_dom", "/homeo/intention.intention"]),
        "Plot!rates": _plot("HSR (Eq 4.1), RSR (Eq 4.6) so far", ["/homeo/run_status.metrics.HSR",
                                                                  "/homeo/run_status.metrics.RSR"], (0, 1)),
        "StateTransitions!log": _states("interaction: action, feedback, proposal",
                                        ["/homeo/outcome.action", "/homeo/outcome.feedback", "/homeo/outcome.proposal"]),
        "RawMessages!outcome": {"topicPath": "/homeo/outcome", "diffEnabled": False, "expansion": "all"},
        "Publish!human": {"topicName": "/homeo/human_input", "datatype": "homeo/human_input",
                          "buttonText": "send as the human", "buttonColor": "#2a7",
                          "value": json.dumps({"feedback": "praise"})},
    }
    col = lambda a, b, pct=50: {"first": a, "second": b, "direction": "column", "splitPercentage": pct}  # noqa: E731
    row = lambda a, b, pct=50: {"first": a, "second": b, "direction": "row", "splitPercentage": pct}  # noqa: E731
    tree = row(col(col("Plot!drives", "Plot!intensities"), col("StateTransitions!mdom", "Plot!rates")),
               col(col("StateTransitions!log", "RawMessages!outcome", 40), "Publish!human", 80), 60)
    return {"configById": cfg, "globalVariables": {}, "userNodes": {}, "playbackConfig": {"speed": 1}, "layout": tree}


def main(argv=None) -> int:
    from homeo_decision.scenario import ScenarioError, load_scenario

    argv = sys.argv[1:] if argv is None else argv
    try:
        sc = load_scenario(argv[0] if argv else None)
    except ScenarioError as exc:
        print(f"foxglove_layout: error: {exc}", file=sys.stderr)
        return 2
    print(json.dumps(layout(sc), indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())

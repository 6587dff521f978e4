"""Scenario files shipped with the package; ``thesis.json`` is the default."""

from pathlib import Path

SCENARIO_DIR = Path(__file__).resolve().parent


def default_scenario_path() -> Path:
    return SCENARIO_DIR / "thesis.json"

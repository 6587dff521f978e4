"""Scenario files shipped with the package; ``thesis.json`` is the default.

Any other ``*.json`` here can be named by its stem (``--scenario workshop``) as well as by path.
"""

from pathlib import Path

SCENARIO_DIR = Path(__file__).resolve().parent


def default_scenario_path() -> Path:
    return SCENARIO_DIR / "thesis.json"


def shipped_scenarios() -> list[str]:
    """Names of the scenario files shipped with the package."""
    return sorted(p.stem for p in SCENARIO_DIR.glob("*.json"))

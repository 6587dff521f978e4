"""Shared fixtures: the thesis scenario, a tiny two-object toy scenario, world-code helpers."""

from __future__ import annotations

import copy
import json

import pytest

from homeo_decision.scenario import load_scenario, scenario_from_dict
from homeo_decision.scenarios import default_scenario_path


def _toy_dict() -> dict:
    """One located object ``box`` (at B, status off/on) plus the null object; two intentions.

    Drives: NAch (Serving, threshold 0, internal) and NEng (Survival, threshold 50, body).
    Stimulus: a recognised intention adds 20 to Serving.
    Actions: box -> TurnOn (only when the box is near), TurnOff; null -> Wait, GoB, GoH.
    Learning: one phase, alpha 0.5 and tau 2.0; gamma 0.5; xi 1; DoD 0.5 (so w = [1, 1]).
    """
    return {
        "schema": "homeo-scenario",
        "version": 1,
        "name": "toy",
        "drives": [
            {"name": "NAch", "motivation": "Serving", "threshold": 0, "rate": 3, "source": "internal"},
            {"name": "NEng", "motivation": "Survival", "threshold": 50, "rate": 2, "source": "body"},
        ],
        "serving_drive": "NAch",
        "locations": ["H", "B"],
        "human": {"location": "H"},
        "objects": {"box": {"location": "B", "variables": {"status": ["off", "on"]}}},
        "stimuli": [{"name": "intention_recognised", "when": {"intention": ["!none"]}, "effects": {"Serving": 20}}],
        "actions": [
            {"name": "TurnOn", "object": "box", "requires": {"box.distance": ["near"]},
             "effects": [{"set": {"box.status": "on"}}]},
            {"name": "TurnOff", "object": "box", "effects": [{"set": {"box.status": "off"}}]},
            {"name": "Wait", "object": "null"},
            {"name": "GoB", "object": "null", "effects": [{"set": {"robot.location": "B"}}]},
            {"name": "GoH", "object": "null", "effects": [{"set": {"robot.location": "H"}}]},
        ],
        "intentions": [
            {"name": "on", "desired": ["TurnOn"], "reasonable": {"box.status": ["off"]}},
            {"name": "come", "desired": ["GoH"], "reasonable": {"human.relation": ["far"]}},
        ],
        "feedback": {"value": 10, "praise_drive_change": -10},
        "learning": {"gamma": 0.5, "xi": 1.0, "dod": 0.5,
                     "schedule": [{"from": 0, "alpha": 0.5, "tau": 2.0}], "pseudo_update": True},
        "open": {"initial_q": 0.0, "initial_location": "H"},
    }


@pytest.fixture(scope="session", autouse=True)
def _own_data_dir(tmp_path_factory):
    """The nodes' default data directory (``HOMEO_DATA_DIR``) in this session's temporary folder, not
    the repository's ``out/``: tests that leave it to the default (checkpoints, Q-tables) write there,
    and two pytest-xdist workers never share one."""
    import os

    old = os.environ.get("HOMEO_DATA_DIR")
    os.environ["HOMEO_DATA_DIR"] = str(tmp_path_factory.mktemp("data") / "out")
    yield
    if old is None:
        os.environ.pop("HOMEO_DATA_DIR", None)
    else:
        os.environ["HOMEO_DATA_DIR"] = old


@pytest.fixture
def toy_raw():
    """A builder of fresh toy-scenario dicts (mutate freely)."""
    return _toy_dict


@pytest.fixture
def toy():
    return scenario_from_dict(_toy_dict())


@pytest.fixture(scope="session")
def thesis():
    """The shipped thesis scenario (do not mutate)."""
    return load_scenario()


@pytest.fixture
def thesis_raw():
    """A fresh copy of the thesis scenario as a dict."""
    return copy.deepcopy(json.loads(default_scenario_path().read_text()))


def encode_world(sc, loc, *, presence="present", intention="none", **status):
    """World code with the robot at ``loc``; ``status`` sets ``<object>.status`` (others initial)."""
    values = {"robot.location": loc, "human.presence": presence, "intention": intention}
    values.update(sc.open.initial_objects)
    for obj, val in status.items():
        values[f"{obj}.status"] = val
    return sc.encode(values)


@pytest.fixture
def enc():
    return encode_world

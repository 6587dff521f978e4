"""Property-based: the file inputs added by the restructuring (the scenario's rule_policy, reference
and open blocks; the Pepper config) are hostile until decoded. Any JSON value in any of their
places becomes a valid scenario/config or a one-line ScenarioError/ConfigError, never another
exception."""

from __future__ import annotations

import copy
import json

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from homeo_decision.scenario import ScenarioError, scenario_from_dict
from homeo_decision.scenarios import default_scenario_path
from pepper_bridge.config import ConfigError, config_from_dict, default_config_path

JSON = st.recursive(st.none() | st.booleans() | st.integers(-10**6, 10**6) | st.floats(allow_nan=True)
                    | st.text(max_size=12), lambda inner: st.lists(inner, max_size=4)
                    | st.dictionaries(st.text(max_size=10), inner, max_size=4), max_leaves=12)
SCENARIO = json.loads(default_scenario_path().read_text())
CONFIG = json.loads(default_config_path().read_text())


def _paths(obj, prefix=()):
    """Every place (key path) inside a JSON value."""
    yield prefix
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield from _paths(v, prefix + (i,))


def _replace(obj, path, value):
    out = copy.deepcopy(obj)
    if not path:
        return value
    cur = out
    for k in path[:-1]:
        cur = cur[k]
    cur[path[-1]] = value
    return out


SCENARIO_PLACES = [p for p in _paths(SCENARIO) if p and p[0] in ("rule_policy", "reference", "open", "ongoing")]
CONFIG_PLACES = list(_paths(CONFIG))


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(SCENARIO_PLACES), JSON)
def test_any_value_in_the_new_scenario_blocks_is_a_scenario_or_a_one_line_error(path, value):
    try:
        scenario_from_dict(_replace(SCENARIO, path, value))
    except ScenarioError as exc:
        assert "\n" not in str(exc) and str(exc)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(CONFIG_PLACES), JSON)
def test_any_value_anywhere_in_the_pepper_config_is_a_config_or_a_one_line_error(path, value):
    try:
        config_from_dict(_replace(CONFIG, path, value), "fuzz.json")
    except ConfigError as exc:
        assert "\n" not in str(exc) and str(exc)


def test_the_places_cover_the_new_blocks():
    assert any(p[0] == "rule_policy" for p in SCENARIO_PLACES) and any(p[0] == "reference" for p in SCENARIO_PLACES)
    assert any(p[0] == "ongoing" for p in SCENARIO_PLACES)  # issue 25
    assert len(CONFIG_PLACES) > 40

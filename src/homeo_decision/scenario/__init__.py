"""The scenario: drives, objects, actions, constraints, effects, stimuli, intentions (data, not code).

``model`` holds what a scenario is, ``load`` reads and validates a file (its ``open`` block:
``open_choices``), ``compile`` turns it
into per-world-code lookup tables; ``rule_policy`` and ``reference`` validate the optional
blocks of the rule baseline and of published numbers. Import from here.
"""

from .compile import _compile, _holds, holds
from .load import ANY_ACTION, load_scenario, scenario_from_dict
from .model import (DISTANCES, NONE_INTENTION, NULL_OBJECT, OBS_CHANNELS, PRESENCE, RELATIONS, SCHEMA,
                    SCHEMA_VERSION, ActionSpec, Compiled, DriveSpec, IntentionSpec, ObservationSpec, ReferenceSpec,
                    RuleCandidate, RuleSpec, Scenario, ScenarioError)
from .open_choices import OpenChoices

__all__ = [
    "ANY_ACTION", "DISTANCES", "NONE_INTENTION", "NULL_OBJECT", "OBS_CHANNELS", "PRESENCE",
    "RELATIONS", "SCHEMA", "SCHEMA_VERSION", "ActionSpec", "Compiled", "DriveSpec", "IntentionSpec", "OpenChoices",
    "ObservationSpec", "ReferenceSpec", "RuleCandidate", "RuleSpec", "Scenario", "ScenarioError", "_compile",
    "_holds", "holds", "load_scenario", "scenario_from_dict",
]

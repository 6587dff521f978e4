"""The scenario-aware base of every homeo node: parameters ``scenario`` and ``overrides``, the
scenario's message vocabulary, and ``run_scenario_node`` (a bad scenario is a one-line exit 2)."""

from __future__ import annotations

import json
from typing import Callable

from rcl_interfaces.msg import ParameterDescriptor

from homeo_msgs_py.node_base import HomeoNode, NodeConfigError, run_node

from .codec import vocabulary
from .scenario import ScenarioError, load_scenario


class ScenarioNode(HomeoNode):
    def __init__(self, name: str, **kw):
        super().__init__(name, **kw)
        self.declare_parameter("scenario", "", ParameterDescriptor(
            description="scenario JSON file ('' = the thesis scenario); fixed at start", read_only=True))
        self.declare_parameter("overrides", "{}", ParameterDescriptor(
            description="JSON object of open-choice overrides, as homeo-sim --set; fixed at start", read_only=True))
        self.sc = load_node_scenario(self.get_parameter("scenario").value, self.get_parameter("overrides").value)
        self.voc = vocabulary(self.sc)


def load_node_scenario(path: str, overrides: str):
    try:
        ov = json.loads(overrides or "{}")
    except json.JSONDecodeError as exc:
        raise NodeConfigError(f"parameter overrides is not JSON: {exc}") from None
    if not isinstance(ov, dict):
        raise NodeConfigError("parameter overrides must be a JSON object")
    return load_scenario(path or None, overrides=ov)


def run_scenario_node(factory: Callable, args=None) -> int:
    return run_node(factory, args, config_errors=(ScenarioError,))

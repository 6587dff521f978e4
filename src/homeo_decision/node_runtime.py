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
        self.declare_fixed("scenario", "", ParameterDescriptor(
            description="scenario JSON file ('' = the thesis scenario); fixed at start"))
        # KEY=VALUE items as homeo-sim --set (VALUE JSON or a word); '' items are ignored. A list of
        # strings, not a JSON object: ros2 param load re-reads a string through YAML, and '{...}'
        # would come back as a mapping
        self.declare_fixed("overrides", [""], ParameterDescriptor(
            description="open-choice overrides, KEY=VALUE items as homeo-sim --set; fixed at start"))
        self.sc = load_node_scenario(self.get_parameter("scenario").value, self.get_parameter("overrides").value)
        self.voc = vocabulary(self.sc)


def overrides_param(overrides: dict) -> list[str]:
    """The ``overrides`` parameter of a node for these open-choice overrides."""
    return [f"{k}={json.dumps(v, separators=(',', ':'))}" for k, v in overrides.items()] or [""]


def load_node_scenario(path: str, overrides):
    from argparse import ArgumentTypeError

    from homeo_msgs_py.cli_args import setting

    ov = {}
    for item in overrides or []:
        if not isinstance(item, str):
            raise NodeConfigError("parameter overrides must be a list of KEY=VALUE strings")
        if item:
            try:
                k, v = setting(item)
            except ArgumentTypeError as exc:
                raise NodeConfigError(f"parameter overrides: {exc}") from None
            ov[k] = v
    return load_scenario(path or None, overrides=ov)


def run_scenario_node(factory: Callable, args=None) -> int:
    return run_node(factory, args, config_errors=(ScenarioError,))

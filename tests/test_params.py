"""Every node's parameters survive ``ros2 param dump`` then ``ros2 param load`` (issue 11).

There is no ``ros2`` command line here, so the test does what its two verbs do, with the same
libraries: ``dump`` lists and gets every parameter and prints ``yaml.dump({node: {"ros__parameters":
values}}, default_flow_style=False)`` (ros2cli ros2param/verb/dump.py); ``load`` is rclpy's own
``AsyncParameterClient.load_parameter_file`` (what ros2param's ``load_parameter_file`` calls), which
re-reads every value through YAML. Then a change of a start-only parameter is refused with a reason.
"""

from __future__ import annotations

import pytest
import yaml

from rosgraph import Probe, fresh_domain, sim_graph, sim_opts


pytestmark = pytest.mark.ros


def _dump(probe, client, node: str) -> str:
    from rclpy.parameter import parameter_value_to_python

    fut = client.list_parameters()
    assert probe.spin_until(fut.done, 20.0)
    names = sorted(fut.result().result.names)
    fut = client.get_parameters(names)
    assert probe.spin_until(fut.done, 20.0)
    values = [parameter_value_to_python(v) for v in fut.result().values]
    out: dict = {}
    for name, value in zip(names, values):  # nested names as dump's insert_dict does
        d = out
        *path, last = name.split(".")
        for part in path:
            d = d.setdefault(part, {})
        d[last] = value
    return yaml.dump({node: {"ros__parameters": out}}, default_flow_style=False)


@pytest.mark.parametrize("node", ["/homeo_world", "/homeo_intention", "/homeo_drives", "/homeo_decision"])
def test_dump_then_load_sets_every_parameter(tmp_path, node):
    from rclpy.parameter_client import AsyncParameterClient

    d = fresh_domain()
    with sim_graph(sim_opts(iterations=0, rate=5.0, overrides=(("initial_q", 0.5),), data_dir=str(tmp_path)), d):
        probe = Probe(d)
        try:
            client = AsyncParameterClient(probe.node, node)
            assert client.wait_for_services(timeout_sec=60.0), f"{node} has no parameter services"
            text = _dump(probe, client, node)
            assert "initial_q=0.5" in text  # a JSON object here would come back as a YAML mapping (rclpy#1507)
            f = tmp_path / "params.yaml"
            f.write_text(text)
            fut = client.load_parameter_file(str(f))
            assert probe.spin_until(fut.done, 20.0)
            failed = [r.reason for r in fut.result().results if not r.successful]
            # rclpy declares this one read-only on every Jazzy node: ``ros2 param load`` reports it on any
            # node, as the ROS 2 parameters tutorial shows (osrf/ros2_test_cases#1117); all of ours load
            assert failed == ["Trying to set a read-only parameter: start_type_description_service."], (failed, text)
            # a start-only parameter keeps its value: a change is refused with the reason
            r = probe.set_param(node, "data_dir", str(tmp_path / "elsewhere"))
            assert not r.successful and "set when the node starts" in r.reason
        finally:
            probe.close()

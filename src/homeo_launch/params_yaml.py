"""A world's parameters file (``config/params.yaml`` is the simulation's; ``config/`` holds one per shipped world):
every node's parameters with their defaults.

Read off the nodes themselves (each built once in this process, as ``ros2 param dump`` would read
them), so the files cannot drift from the declarations; ROS's own parameters (``use_sim_time``...)
are left out, ``data_dir`` is the launchers' default ``out``. In ``ros2 param dump``'s format: a
file for ``ros2 param load`` and for ``params_file:=`` of the launch files, as is any file ``ros2 param
dump`` writes. ``tests/test_ros2_workspace.py`` checks the shipped files are these.

    python -m homeo_launch.params_yaml sim > config/params.yaml
    python -m homeo_launch.params_yaml NAME > my_world.yaml     # any world of the registry
"""

from __future__ import annotations

import os
import sys

from homeo_msgs_py.data_dir import DEFAULT as DATA_DIR  # the launchers' default data directory

ROS_OWN = ("use_sim_time", "start_type_description_service")  # rclpy declares these on every node


def node_classes() -> list:
    """(node name, class) of the graph's nodes."""
    from homeo_decision.drives_node import DrivesNode
    from homeo_decision.node import DecisionNode
    from homeo_decision.world_node import WorldNode
    from homeo_intention.node import IntentionNode
    from homeo_msgs_py.graph import WORLD

    return [(WORLD, WorldNode), ("homeo_intention", IntentionNode), ("homeo_drives", DrivesNode),
            ("homeo_decision", DecisionNode)]


def defaults(world: str = "sim") -> dict:
    """``{"/NODE": {"ros__parameters": {name: default}}}`` for the graph with ``world``."""
    import rclpy

    from .processes import dds_defaults

    os.environ.update(dds_defaults())  # the nodes stay on this machine, as a launcher's do
    os.environ.pop("HOMEO_AUTH_FILE", None)  # no graph secret: the defaults of an unsigned node
    rclpy.init(args=["--ros-args", "-p", f"world:={world}", "-p", f"data_dir:={DATA_DIR}"])
    out = {}
    stdout = os.dup(1)
    os.dup2(2, 1)  # what the nodes' libraries print (libqi's notes) goes to stderr, not into the file
    try:
        for name, cls in node_classes():
            node = cls()
            try:
                out[f"/{name}"] = {"ros__parameters": {
                    k: list(p.value) if isinstance(p.value, (list, tuple)) else p.value
                    for k, p in sorted(node._parameters.items()) if k not in ROS_OWN and not k.startswith("qos_")}}
            finally:
                node.destroy_node()
    finally:
        rclpy.try_shutdown()
        sys.stdout.flush()
        os.dup2(stdout, 1)
        os.close(stdout)
    return out


def render(world: str = "sim") -> str:
    import yaml

    head = f"# every node's parameters and their defaults, world {world}: python -m homeo_launch.params_yaml {world}\n"
    return head + yaml.safe_dump(defaults(world), sort_keys=False, default_flow_style=False)


if __name__ == "__main__":
    from homeo_decision.world_api import WorldConfigError, world_class

    world = sys.argv[1] if len(sys.argv) > 1 else "sim"
    try:
        world_class(world)
    except WorldConfigError as exc:
        print(f"params_yaml: error: {exc}", file=sys.stderr)
        sys.exit(2)
    sys.stdout.write(render(world))

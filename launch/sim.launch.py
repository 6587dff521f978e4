"""``ros2 launch homeo_robot sim.launch.py [name:=value ...]``: a shortcut for ``world.launch.py world:=sim``, the node
graph with the simulated world and human, as ``homeo-launch sim`` starts it (``--show-args`` lists the arguments)."""

from homeo_launch.ros_launch import launch_description


def generate_launch_description():
    return launch_description("sim")

"""``ros2 launch homeo_robot sim.launch.py [name:=value ...]``: the node graph with the simulated world and human, as
``homeo-launch sim`` starts it (``homeo_launch.ros_launch``; ``ros2 launch homeo_robot sim.launch.py --show-args``
lists the arguments)."""

from homeo_launch.ros_launch import launch_description


def generate_launch_description():
    return launch_description("sim")

"""``ros2 launch homeo_robot pepper.launch.py [name:=value ...]``: the node graph with the Pepper world (a robot, or standin:=true), as
``homeo-launch pepper`` starts it (``homeo_launch.ros_launch``; ``ros2 launch homeo_robot pepper.launch.py --show-args``
lists the arguments)."""

from homeo_launch.ros_launch import launch_description


def generate_launch_description():
    return launch_description("pepper")

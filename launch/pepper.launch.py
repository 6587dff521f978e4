"""``ros2 launch homeo_robot pepper.launch.py [name:=value ...]``: a shortcut for ``world.launch.py world:=pepper``, the
node graph with the Pepper world (a robot, or standin:=true), as ``homeo-launch pepper`` starts it (``--show-args``
lists the arguments)."""

from homeo_launch.ros_launch import launch_description


def generate_launch_description():
    return launch_description("pepper")

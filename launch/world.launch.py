"""``ros2 launch homeo_robot world.launch.py world:=NAME [name:=value ...]``: the node graph with any world of the
``homeo_robot.worlds`` registry, as ``homeo-launch NAME`` starts it (``homeo_launch.ros_launch``); ``--show-args`` lists
the arguments, every installed world's own among them."""

from homeo_launch.ros_launch import launch_description


def generate_launch_description():
    return launch_description()

"""homeo_launch: the launcher and its ROS-launch glue, for any world of the registry; no world is named here.

``homeo-launch NAME`` (``cli``, ``front``: a world's declarations make its command), the graph of node
processes (``launch``, ``processes``, ``monitor``, ``supervise``), the shared options (``options``), and
``ros2 launch`` (``ros_launch``, ``watch``, ``params_yaml``). It may import every package of layers 1-4 and
``homeo_record`` (recording and live view); only ``homeo_ops`` imports it, and it finds the commands other
packages add through entry points (``homeo_robot.commands``), not through imports (tests/test_layers.py).
"""

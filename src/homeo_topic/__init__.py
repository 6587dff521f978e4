"""homeo_topic: ``homeo-topic``, the project's small stand-in for ``ros2 topic echo/pub`` and ``ros2 param``
on a pip-only install (the real ROS 2 command line needs a ROS 2 install). It may import ``homeo_msgs_py``
and ``homeo_decision`` only; nothing imports it (tests/test_layers.py).
"""

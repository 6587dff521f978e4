"""pepper_bridge: the decision system on a SoftBank Pepper through NAOqi (libqi), ROS-free core.

- ``bridge.PepperBridge``: readings -> world/body dicts, actions -> NAOqi calls, events -> outcome;
- ``standin.StandinRobot`` / ``homeo-pepper-standin``: a Pepper on loopback for tests and demos;
- ``field``: the field test of Section 4.3 (Tables 4.7, 4.8) without ROS.

See docs/PEPPER.md.
"""

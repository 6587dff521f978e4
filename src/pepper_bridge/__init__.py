"""pepper_bridge: the decision system on a SoftBank Pepper through NAOqi (libqi), ROS-free core.

- ``environment.PepperEnvironment``: the robot behind the environment boundary (reset / observe /
  step), over ``bridge.PepperBridge`` (readings -> world/body dicts, actions -> NAOqi calls,
  events -> outcome); ``config``: what the scenario's names mean on the robot;
- ``world_side.PepperWorldSide`` and ``node``: the robot in the graph, on the shared lockstep driver;
- ``standin.StandinRobot`` / ``homeo-pepper-standin``: a Pepper on loopback for tests and demos.

The field test of Section 4.3 (Tables 4.7, 4.8) is ``pepper_bridge.field``. See docs/PEPPER.md.
"""

"""homeo_ops: the operations tools, apart from the launcher: ``homeo-launch bench | soak | recover`` (added to
the launcher's command through the entry points ``homeo_robot.commands``), the floor chain the bench measures
against, the profiler, and the in-memory bus that runs the graph's hosts without DDS (``bus``: the soak and
the equivalence tests). It may import every other package; none imports it (tests/test_layers.py).
"""

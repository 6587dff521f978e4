"""homeo_record: recording, replay and live view of a graph's run, for any world.

The launcher's tap (``tap``), rosbag2 bags in MCAP written at the writers or at the tap (``record``),
reading them back (``bag``), ``homeo-replay`` (``replay``, ``policy_eval``: the world's result from the bag,
the interaction, plots, a policy judged offline) and the Foxglove live view (``live``, ``foxglove_layout``).
It may import the packages of layers 1-4; the launcher and the operations tools import it
(tests/test_layers.py).
"""

"""homeo_intention: Bayesian intention recognition (Section 2.3, Eq 2.10) without ROS.

``IntentionModel`` (the Bayesian network, EM learning) and ``OracleModel`` (the true intention)
share ``recognise(obs) -> Recognition`` and ``learn(obs, label)``; ``node.py`` wraps them in ROS.
"""

from .model import IntentionModel, OracleModel, Recognition, make_model
from .model_io import IntentionModelError
from .observation import UnknownObservation

__all__ = ["IntentionModel", "OracleModel", "Recognition", "make_model", "IntentionModelError", "UnknownObservation"]

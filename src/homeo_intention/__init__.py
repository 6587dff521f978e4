"""homeo_intention: Bayesian intention recognition (Section 2.3, Eq 2.10) without ROS.

``IntentionModel`` is the Bayesian network that learns the user by EM; ``recognition.py`` makes it
the robot's recognition part (``make_recognition``); ``node.py`` hosts that part in the graph.
"""

from .model import IntentionModel, Recognition
from .model_io import IntentionModelError
from .observation import UnknownObservation
from .recognition import BayesRecognition, make_recognition

__all__ = ["IntentionModel", "Recognition", "BayesRecognition", "make_recognition", "IntentionModelError",
           "UnknownObservation"]

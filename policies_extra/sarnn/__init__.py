"""RMB's Spatial Attention RNN as a LeRobot policy plugin (``--policy.type=sarnn``)."""

from .configuration_sarnn import SARNNConfig
from .modeling_sarnn import SARNNPolicy
from .processor_sarnn import make_sarnn_pre_post_processors

__all__ = ["SARNNConfig", "SARNNPolicy", "make_sarnn_pre_post_processors"]

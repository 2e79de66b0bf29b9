"""RMB's MLP policy as a LeRobot policy plugin (``--policy.type=mlp``)."""

from .configuration_mlp import MLPConfig
from .modeling_mlp import MLPPolicy
from .processor_mlp import make_mlp_pre_post_processors

__all__ = ["MLPConfig", "MLPPolicy", "make_mlp_pre_post_processors"]

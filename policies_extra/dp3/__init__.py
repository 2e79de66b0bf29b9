"""3D Diffusion Policy (Ze et al., RSS 2024) as a LeRobot policy plugin (``--policy.type=dp3``)."""

from .configuration_dp3 import DP3Config
from .modeling_dp3 import DP3Policy
from .processor_dp3 import make_dp3_pre_post_processors

__all__ = ["DP3Config", "DP3Policy", "make_dp3_pre_post_processors"]

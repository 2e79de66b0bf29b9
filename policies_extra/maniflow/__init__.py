"""ManiFlow (Yan et al., CoRL 2025) as a LeRobot plugin (``--policy.type=maniflow``)."""

from .configuration_maniflow import CPU_SIZE, ManiFlowConfig
from .modeling_maniflow import ManiFlowPolicy
from .processor_maniflow import make_maniflow_pre_post_processors

__all__ = ["CPU_SIZE", "ManiFlowConfig", "ManiFlowPolicy", "make_maniflow_pre_post_processors"]

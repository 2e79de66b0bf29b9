"""Flow Policy (Zhang et al., AAAI 2025) as a LeRobot plugin (``--policy.type=flow_policy``)."""

from .configuration_flow_policy import FlowPolicyConfig
from .modeling_flow_policy import FlowPolicy
from .processor_flow_policy import make_flow_policy_pre_post_processors

__all__ = ["FlowPolicy", "FlowPolicyConfig", "make_flow_policy_pre_post_processors"]

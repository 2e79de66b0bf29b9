"""Pre/post-processors of Flow Policy: DP3's, i.e. LeRobot's default pipelines.

State and action are scaled to [-1, 1] (``MIN_MAX``, RMB's ``limits`` normaliser); depth passes
unchanged because the policy makes metric point clouds from it (``VISUAL: IDENTITY``).
"""

from __future__ import annotations

from typing import Any

import torch
from lerobot.processor import PolicyAction, PolicyProcessorPipeline

from rmb_lerobot.policies_extra.dp3.processor_dp3 import make_dp3_pre_post_processors

from .configuration_flow_policy import FlowPolicyConfig


def make_flow_policy_pre_post_processors(
    config: FlowPolicyConfig,
    dataset_stats: dict[str, dict[str, torch.Tensor]] | None = None,
) -> tuple[
    PolicyProcessorPipeline[dict[str, Any], dict[str, Any]],
    PolicyProcessorPipeline[PolicyAction, PolicyAction],
]:
    """Rename -> batch -> device -> normalize in; unnormalize -> cpu out (as DP3)."""
    return make_dp3_pre_post_processors(config, dataset_stats)

"""Pre/post-processors of ManiFlow: DP3's, i.e. LeRobot's default pipelines.

State and action are scaled to [-1, 1] (``MIN_MAX``); images pass unchanged (``VISUAL:
IDENTITY``, inherited from the dp3 config): RGB in [0, 1] feeds the ResNet, whose GroupNorm
needs no dataset statistics, and depth must stay metric for the point cloud.
"""

from __future__ import annotations

from typing import Any

import torch
from lerobot.processor import PolicyAction, PolicyProcessorPipeline

from rmb_lerobot.policies_extra.dp3.processor_dp3 import make_dp3_pre_post_processors

from .configuration_maniflow import ManiFlowConfig


def make_maniflow_pre_post_processors(
    config: ManiFlowConfig,
    dataset_stats: dict[str, dict[str, torch.Tensor]] | None = None,
) -> tuple[
    PolicyProcessorPipeline[dict[str, Any], dict[str, Any]],
    PolicyProcessorPipeline[PolicyAction, PolicyAction],
]:
    """Rename -> batch -> device -> normalize in; unnormalize -> cpu out (as DP3)."""
    return make_dp3_pre_post_processors(config, dataset_stats)

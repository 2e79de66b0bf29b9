"""Pre/post-processors of DP3: LeRobot's default pipelines.

State and action are scaled to [-1, 1] (``MIN_MAX``, as DP3's ``limits`` normaliser); images,
depth included, pass unchanged (``VISUAL: IDENTITY``, enforced by the config): the policy turns
the depth into metric point clouds itself, so checkpoints need no custom processor step.
"""

from __future__ import annotations

from typing import Any

import torch
from lerobot.processor import (
    PolicyAction,
    PolicyProcessorPipeline,
    make_default_pre_post_processors,
)

from .configuration_dp3 import DP3Config


def make_dp3_pre_post_processors(
    config: DP3Config,
    dataset_stats: dict[str, dict[str, torch.Tensor]] | None = None,
) -> tuple[
    PolicyProcessorPipeline[dict[str, Any], dict[str, Any]],
    PolicyProcessorPipeline[PolicyAction, PolicyAction],
]:
    """Rename -> batch -> device -> normalize in; unnormalize -> cpu out (as Diffusion)."""
    return make_default_pre_post_processors(config, dataset_stats, normalizer_device=config.device)

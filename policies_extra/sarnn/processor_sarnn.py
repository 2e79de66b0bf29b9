"""Pre/post-processors of SARNN: LeRobot's default pipelines.

Images are not normalized (``VISUAL: IDENTITY``): SARNN reconstructs them, in [0, 1] as RMB.
"""

from __future__ import annotations

from typing import Any

import torch
from lerobot.processor import (
    PolicyAction,
    PolicyProcessorPipeline,
    make_default_pre_post_processors,
)

from .configuration_sarnn import SARNNConfig


def make_sarnn_pre_post_processors(
    config: SARNNConfig,
    dataset_stats: dict[str, dict[str, torch.Tensor]] | None = None,
) -> tuple[
    PolicyProcessorPipeline[dict[str, Any], dict[str, Any]],
    PolicyProcessorPipeline[PolicyAction, PolicyAction],
]:
    """Rename -> batch -> device -> normalize in; unnormalize -> cpu out (as ACT)."""
    return make_default_pre_post_processors(config, dataset_stats, normalizer_device=config.device)

"""Pre/post-processors of the MLP policy: LeRobot's default pipelines (normalize, batch, device)."""

from __future__ import annotations

from typing import Any

import torch
from lerobot.processor import (
    PolicyAction,
    PolicyProcessorPipeline,
    make_default_pre_post_processors,
)

from .configuration_mlp import MLPConfig


def make_mlp_pre_post_processors(
    config: MLPConfig,
    dataset_stats: dict[str, dict[str, torch.Tensor]] | None = None,
) -> tuple[
    PolicyProcessorPipeline[dict[str, Any], dict[str, Any]],
    PolicyProcessorPipeline[PolicyAction, PolicyAction],
]:
    """Rename -> batch -> device -> normalize in; unnormalize -> cpu out (as ACT)."""
    return make_default_pre_post_processors(config, dataset_stats, normalizer_device=config.device)

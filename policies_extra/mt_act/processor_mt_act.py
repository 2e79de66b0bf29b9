"""Pre/post-processors of MT-ACT: ACT's (LeRobot's default pipelines).

The task string travels through them untouched as complementary data (``batch["task"]``); the
policy embeds it itself, so no tokenizer step is needed.
"""

from __future__ import annotations

from typing import Any

import torch
from lerobot.policies.act.processor_act import make_act_pre_post_processors
from lerobot.processor import PolicyAction, PolicyProcessorPipeline

from .configuration_mt_act import MTACTConfig


def make_mt_act_pre_post_processors(
    config: MTACTConfig,
    dataset_stats: dict[str, dict[str, torch.Tensor]] | None = None,
) -> tuple[
    PolicyProcessorPipeline[dict[str, Any], dict[str, Any]],
    PolicyProcessorPipeline[PolicyAction, PolicyAction],
]:
    """Rename -> batch -> device -> normalize in; unnormalize -> cpu out (as ACT)."""
    return make_act_pre_post_processors(config, dataset_stats)

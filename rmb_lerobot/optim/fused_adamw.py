"""The ``adamw_fused`` LeRobot optimizer type; importing this module registers it (see
:mod:`rmb_lerobot.optim`)."""

from __future__ import annotations

from dataclasses import asdict, dataclass

import torch
from lerobot.optim.optimizers import AdamWConfig, OptimizerConfig, OptimizerParams

from rmb_lerobot.optim import FUSED_ADAMW


@OptimizerConfig.register_subclass(FUSED_ADAMW)
@dataclass
class FusedAdamWConfig(AdamWConfig):
    """LeRobot's :class:`~lerobot.optim.optimizers.AdamWConfig` (same fields and defaults),
    built with ``fused=True``."""

    def build(self, params: OptimizerParams) -> torch.optim.Optimizer:
        """``torch.optim.AdamW(params, fused=True, ...)`` with this config's options.

        Args:
            params: Parameters or parameter groups, as LeRobot's policies give them.

        Returns:
            The optimizer.
        """
        kwargs = asdict(self)
        kwargs.pop("grad_clip_norm")  # applied by LeRobot's training loop, not the optimizer
        return torch.optim.AdamW(params, fused=True, **kwargs)

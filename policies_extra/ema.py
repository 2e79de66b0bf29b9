"""An exponential moving average (EMA) of a policy's weights, as diffusion_policy's ``EMAModel``.

DP3, Flow Policy and ManiFlow predict with averaged weights (RMB's trainers sample from the EMA
copy): the last weights of a short, noisy run are a worse policy than their recent average.
LeRobot's train loop calls ``policy.update()`` after each optimizer step, which moves the
average; it is saved and loaded with the policy like any other parameters.
"""

from __future__ import annotations

import copy

import torch
from torch import nn


def ema_decay(update: int, power: float, max_decay: float) -> float:
    """Decay of the ``update``-th average (1-based): 0 for the first two (copies), then
    1 - (1 + k) ** -power capped, as diffusion_policy's ``EMAModel`` with RMB's settings
    (update_after_step 0, inv_gamma 1; TrainDiffusionPolicy3d.py, TrainFlowPolicy.py)."""
    k = max(0, update - 2)
    return 0.0 if k == 0 else min(1.0 - (1.0 + k) ** -power, max_decay)


@torch.no_grad()
def ema_update(average: nn.Module, model: nn.Module, decay: float) -> None:
    """Move ``average``'s parameters towards ``model``'s (``decay`` of the old kept); copy the
    buffers."""
    for avg, current in zip(average.parameters(), model.parameters(), strict=True):
        avg.lerp_(current, 1.0 - decay)
    for avg, current in zip(average.buffers(), model.buffers(), strict=True):
        avg.copy_(current)


class EmaWeights:
    """Mixin for a policy whose trained network is ``self.model``: an untrained copy
    ``self.ema_model`` follows it, one average per optimizer step (``update``).

    The config supplies ``ema_power`` and ``ema_max_decay``. A policy without an average sets
    ``self.ema_model = None`` (no class-level default: ``nn.Module`` keeps submodules in
    ``_modules``, which a class attribute would shadow).
    """

    model: nn.Module
    ema_model: nn.Module | None

    def init_ema(self) -> None:
        """Make the average (call after ``self.model`` exists); the config is shared, not copied."""
        shared = {id(self.config): self.config}
        self.ema_model = copy.deepcopy(self.model, shared).requires_grad_(False)
        self.register_buffer("ema_updates", torch.zeros((), dtype=torch.long))

    @torch.no_grad()
    def update(self) -> None:
        """Move the EMA weights towards the trained ones (after each optimizer step)."""
        if self.ema_model is None:
            return
        self.ema_updates += 1
        cfg = self.config
        decay = ema_decay(int(self.ema_updates), cfg.ema_power, cfg.ema_max_decay)
        ema_update(self.ema_model, self.model, decay)

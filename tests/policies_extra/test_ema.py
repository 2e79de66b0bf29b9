"""The weight average DP3, Flow Policy and ManiFlow predict with (diffusion_policy's EMAModel)."""

from __future__ import annotations

import itertools

import pytest
import torch
from torch import nn

from rmb_lerobot.policies_extra.ema import EmaWeights, ema_decay, ema_update


def test_ema_decay_warms_up_like_diffusion_policys_ema():
    decays = [ema_decay(n, power=0.75, max_decay=0.9999) for n in range(1, 6)]
    assert decays[:2] == [0.0, 0.0]  # the first two updates copy the weights
    assert decays[2] == pytest.approx(1 - 2**-0.75)
    assert all(a < b for a, b in itertools.pairwise(decays[2:]))
    assert ema_decay(10**9, power=0.75, max_decay=0.9999) == 0.9999


def test_ema_update_keeps_decay_of_the_old_weights_and_copies_buffers():
    average, model = nn.BatchNorm1d(2), nn.BatchNorm1d(2)
    with torch.no_grad():
        average.weight.fill_(1.0)
        model.weight.fill_(3.0)
        model.running_mean.fill_(5.0)
    ema_update(average, model, decay=0.75)
    torch.testing.assert_close(average.weight, torch.full((2,), 1.5))  # 0.75 * 1 + 0.25 * 3
    torch.testing.assert_close(average.running_mean, torch.full((2,), 5.0))


class Averaged(EmaWeights, nn.Module):
    def __init__(self):
        super().__init__()
        self.config = type("Config", (), {"ema_power": 0.75, "ema_max_decay": 0.9999})()
        self.model = nn.Linear(3, 1)
        self.init_ema()


def test_the_average_lags_the_trained_weights_and_is_never_optimised():
    policy = Averaged()
    assert not any(p.requires_grad for p in policy.ema_model.parameters())
    assert policy.ema_model is not policy.model and int(policy.ema_updates) == 0
    history = []
    for step in range(1, 21):
        with torch.no_grad():
            policy.model.weight.fill_(float(step))  # a weight that rises steadily
        policy.update()
        history.append(policy.ema_model.weight[0, 0].item())
    assert history[:2] == [1.0, 2.0]  # copies
    assert all(h < s for h, s in zip(history[2:], range(3, 21), strict=True))  # lags behind
    assert all(a < b for a, b in itertools.pairwise(history))  # but follows
    assert int(policy.ema_updates) == 20
    assert "ema_updates" in policy.state_dict()  # saved with the policy

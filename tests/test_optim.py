"""``--optimizer.type=adamw_fused``: LeRobot's AdamW, same update, PyTorch's fused kernel."""

from __future__ import annotations

import draccus
import pytest
import torch
from lerobot.configs.train import TrainPipelineConfig
from lerobot.optim.optimizers import AdamWConfig, OptimizerConfig
from lerobot.policies.act.configuration_act import ACTConfig

from rmb_lerobot.optim import FUSED_ADAMW, fused_adamw_args
from rmb_lerobot.optim.fused_adamw import FusedAdamWConfig


def two_groups(seed: int) -> tuple[torch.nn.Module, list[dict]]:
    """A small model and ACT-style parameter groups (a second group with its own lr)."""
    torch.manual_seed(seed)
    model = torch.nn.Sequential(torch.nn.Linear(6, 16), torch.nn.ReLU(), torch.nn.Linear(16, 3))
    groups = [
        {"params": list(model[0].parameters())},
        {"params": list(model[2].parameters()), "lr": 1e-5},
    ]
    return model, groups


def train(config: OptimizerConfig, seed: int, steps: int = 20) -> list[torch.Tensor]:
    model, groups = two_groups(seed)
    optimizer = config.build(groups)
    generator = torch.Generator().manual_seed(seed)
    for _ in range(steps):
        x = torch.randn(32, 6, generator=generator)
        loss = (model(x) - x[:, :3]).square().mean()
        loss.backward()
        optimizer.step()
        optimizer.zero_grad()
    return [p.detach().clone() for p in model.parameters()]


def test_lerobot_knows_the_type_by_name():
    assert OptimizerConfig.get_choice_class(FUSED_ADAMW) is FusedAdamWConfig
    assert FusedAdamWConfig().type == FUSED_ADAMW


def test_it_builds_a_fused_adamw_with_the_configs_options():
    config = FusedAdamWConfig(lr=3e-4, weight_decay=1e-4, betas=(0.8, 0.99), eps=1e-6)
    optimizer = config.build(two_groups(0)[1])
    assert isinstance(optimizer, torch.optim.AdamW)
    assert optimizer.defaults["fused"] is True
    assert optimizer.defaults["lr"] == 3e-4
    assert optimizer.defaults["betas"] == (0.8, 0.99)
    assert optimizer.param_groups[1]["lr"] == 1e-5  # a group's own lr is kept


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_training_matches_lerobots_adamw_to_float_rounding(seed):
    options = {"lr": 1e-3, "weight_decay": 1e-4}
    fused = train(FusedAdamWConfig(**options), seed)
    plain = train(AdamWConfig(**options), seed)
    start = [p.detach() for p in two_groups(seed)[0].parameters()]
    for a, b, p0 in zip(fused, plain, start, strict=True):
        torch.testing.assert_close(a, b, rtol=1e-5, atol=1e-6)
        assert not torch.equal(a, p0)  # it did train


def test_the_training_arguments_parse_into_lerobots_train_config(tmp_path):
    args = [
        "--dataset.repo_id=local/x",
        f"--dataset.root={tmp_path}",
        "--policy.type=act",
        "--policy.push_to_hub=false",
        f"--output_dir={tmp_path / 'out'}",
        *fused_adamw_args(lr=1e-4, weight_decay=1e-4),
    ]
    config = draccus.parse(TrainPipelineConfig, args=args)
    config.validate()  # the preset would replace the optimizer; off, ours stays
    assert isinstance(config.policy, ACTConfig)
    assert isinstance(config.optimizer, FusedAdamWConfig)
    assert (config.optimizer.lr, config.optimizer.weight_decay) == (1e-4, 1e-4)
    assert config.optimizer.grad_clip_norm == AdamWConfig().grad_clip_norm
    scheduler = config.scheduler.build(config.optimizer.build(two_groups(0)[1]), 100)
    assert scheduler.get_last_lr() == [1e-4, 1e-5]  # constant: no warm-up, no decay

"""ManiFlow as a LeRobot plugin: a DiT-X over image or point-cloud tokens, consistency flow
training against an EMA copy, few-step Euler sampling.

The point-cloud pipeline is DP3's (tested in ``test_dp3.py``); here: the config (the paper's
defaults), both observation encoders, the training objective, the EMA, inference, persistence
and the CLIs.
"""

from __future__ import annotations

import numpy as np
import pytest
import torch
from lerobot.configs.policies import PreTrainedConfig
from lerobot.configs.types import FeatureType, PolicyFeature
from lerobot.policies.factory import get_policy_class
from safetensors.torch import load_file

from rmb_lerobot.policies_extra.maniflow import CPU_SIZE, ManiFlowConfig, ManiFlowPolicy
from rmb_lerobot.registration import registered_policy_types

STATE_DIM = ACTION_DIM = 7  # as conftest's ``features`` / ``observation`` fixtures
IMAGE = (3, 32, 32)
FRONT = "observation.images.front"
DEPTH = "observation.images.front_depth"
TINY = {
    "n_layer": 2,
    "n_head": 2,
    "n_emb": 32,
    "resnet_width": 16,
    "state_mlp_dims": (16, 16),
    "num_points": 64,
    "encoder_channels": (16, 32),
    "encoder_output_dim": 16,
    "camera_fovy": 45.0,
    "horizon": 8,
    "n_action_steps": 4,
    "num_inference_steps": 3,
    "device": "cpu",
}


def make_maniflow(features, obs_encoder: str = "image", **overrides) -> ManiFlowPolicy:
    inputs, outputs = features
    if obs_encoder == "pointcloud":
        inputs = {**inputs, DEPTH: PolicyFeature(FeatureType.VISUAL, (1, *IMAGE[1:]))}
    torch.manual_seed(0)
    config = ManiFlowConfig(
        input_features=inputs, output_features=outputs, obs_encoder=obs_encoder, **TINY | overrides
    )
    return ManiFlowPolicy(config)


def box_scene(batch: int, steps: int) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """Image (B, T, 3, H, W) and depth (B, T, 1, H, W, mm) of a box at a per-sample place, and
    actions that point at the box: learnable from either camera input."""
    h, w = IMAGE[1:]
    rgb = torch.zeros(batch, steps, 3, h, w)
    depth = torch.full((batch, steps, 1, h, w), 800.0)  # table at 0.8 m
    place = torch.zeros(batch, 2)
    for i in range(batch):
        row, col = 4 + (3 * i) % (h - 12), 4 + (5 * i) % (w - 12)
        rgb[i, :, :, row : row + 8, col : col + 8] = torch.tensor([1.0, 0.6, 0.2])[:, None, None]
        depth[i, :, :, row : row + 8, col : col + 8] = 600.0
        place[i] = torch.tensor([row / h, col / w])
    return rgb, depth, place


def windows(policy: ManiFlowPolicy, batch: int) -> dict[str, torch.Tensor]:
    cfg = policy.config
    rgb, depth, place = box_scene(batch, cfg.n_obs_steps)
    action = (2 * place - 1).repeat(1, 4)[:, None, :ACTION_DIM].repeat(1, cfg.horizon, 1)
    return {
        "observation.state": torch.zeros(batch, cfg.n_obs_steps, STATE_DIM),
        FRONT: rgb,
        DEPTH: depth,
        "action": action,
        "action_is_pad": torch.zeros(batch, cfg.horizon, dtype=torch.bool),
    }


def test_maniflow_is_our_policy_type_and_found_by_lerobots_convention():
    assert "maniflow" in registered_policy_types()
    assert PreTrainedConfig.get_choice_class("maniflow") is ManiFlowConfig
    assert get_policy_class("maniflow") is ManiFlowPolicy


def test_config_defaults_are_the_papers(features):
    config = ManiFlowConfig(device="cpu")
    assert (config.n_layer, config.n_head, config.n_emb) == (12, 8, 768)  # DiT-X
    assert (config.horizon, config.n_obs_steps, config.resnet_width) == (16, 2, 64)
    assert (config.flow_batch_ratio, config.flow_t_alpha, config.flow_t_beta) == (0.75, 1.0, 1.5)
    assert (config.num_inference_steps, config.consistency_time_steps) == (10, 10)
    assert config.obs_encoder == "image" and config.optimizer_betas == (0.9, 0.95)
    with pytest.raises(ValueError, match="obs_encoder"):
        ManiFlowConfig(obs_encoder="voxels")
    with pytest.raises(ValueError, match="multiple of n_head"):
        ManiFlowConfig(n_emb=100, n_head=8)
    inputs, outputs = features
    state_only = {"observation.state": inputs["observation.state"]}
    with pytest.raises(ValueError, match="RGB camera"):
        make_maniflow((state_only, outputs))
    no_depth = ManiFlowConfig(
        input_features=inputs, output_features=outputs, obs_encoder="pointcloud", device="cpu"
    )
    with pytest.raises(ValueError, match="depth"):
        ManiFlowPolicy(no_depth)


def test_the_cpu_size_is_small_and_the_ema_is_a_frozen_copy(features):
    policy = make_maniflow(features, **CPU_SIZE)
    trained = sum(p.numel() for p in policy.model.parameters())
    assert 0.5e6 < trained < 1.5e6  # 0.95 M with one camera (the paper's size: 192.3 M)
    assert sum(p.numel() for p in policy.get_optim_params()) == trained
    assert not any(p.requires_grad for p in policy.ema_model.parameters())
    assert any(isinstance(m, torch.nn.GroupNorm) for m in policy.model.image_encoder.modules())
    assert not any(isinstance(m, torch.nn.BatchNorm2d) for m in policy.modules())


def test_image_tokens_are_the_resnets_feature_cells(features):
    """Stride 32: a 64 x 96 camera gives 2 x 3 tokens per frame, or 1 when pooled."""
    inputs, outputs = features
    inputs = {**inputs, FRONT: PolicyFeature(FeatureType.VISUAL, (3, 64, 96))}
    obs = {"observation.state": torch.zeros(2, 2, STATE_DIM), FRONT: torch.rand(2, 2, 3, 64, 96)}
    for pool, cells in ((False, 6), (True, 1)):
        policy = make_maniflow((inputs, outputs), pool_image_features=pool)
        tokens = policy.model.observation_tokens(policy.model_inputs(obs))
        assert tokens.shape == (2, 2 * (1 + cells), 32)  # 2 frames x (state + camera cells)
    with pytest.raises(ValueError, match="observation tokens"):
        policy = make_maniflow((inputs, outputs))
        policy.model.observation_tokens({**obs, FRONT: torch.rand(2, 2, 3, 32, 32)})


@pytest.mark.parametrize("obs_encoder", ["image", "pointcloud"])
def test_shapes_and_a_training_step(features, obs_encoder):
    policy = make_maniflow(features, obs_encoder)
    batch = windows(policy, 4)
    inputs = policy.model_inputs(batch)
    tokens = policy.model.observation_tokens(inputs)
    assert tokens.shape == (4, 2 * 2, 32)  # 2 frames x (state + camera or cloud) tokens
    if obs_encoder == "pointcloud":
        assert inputs["cloud"].shape == (4, 2, 64, 3)

    policy.train()
    loss, info = policy.forward(batch)
    assert torch.isfinite(loss) and set(info) == {"flow_loss", "consistency_loss"}
    loss.backward()
    torch.optim.AdamW(policy.get_optim_params(), lr=1e-2).step()
    ema, current = next(policy.ema_model.parameters()), next(policy.model.parameters())
    assert not torch.equal(ema, current)
    policy.update()  # what lerobot-train calls after each optimizer step; the first copies
    assert torch.equal(ema, current) and int(policy.ema_updates) == 1
    assert policy.predict_action_chunk(batch).shape == (4, 4, ACTION_DIM)


def test_the_straight_flow_to_the_actions_has_zero_loss(features):
    """Both objectives are minimal (zero) for the velocity field that runs straight from any
    point to the batch's actions: the flow target a - z and the consistency target (the EMA's
    extrapolated end, from the current point) both equal (a - x_t) / (1 - t)."""
    policy = make_maniflow(features)
    batch = windows(policy, 8)
    actions = batch["action"]

    def straight(scale: float):
        def velocity(x, t, dt, tokens):
            # The teacher sees the batch's last (consistency) rows, the student all of them.
            target = actions[-len(x) :]
            return scale * (target - x) / (1 - t).clamp_min(1e-6).view(-1, 1, 1)

        return velocity

    def loss_with(scale: float) -> float:
        policy.ema_model.velocity = straight(1.0)
        policy.model.velocity = straight(scale)
        torch.manual_seed(0)
        return policy.forward(batch)[0].item()

    assert loss_with(1.0) < 1e-10
    assert loss_with(1.2) > 1e-4


def test_loss_and_few_step_error_decrease_on_a_tiny_batch(features, fit_batch):
    """Fresh noise and times every step make the loss noisy: compare it on the same draws."""
    policy = make_maniflow(features)
    batch = windows(policy, 8)
    target = batch["action"][:, 1:5]  # the executed actions, from the current frame on

    def evaluate() -> tuple[float, float]:
        with torch.no_grad():
            torch.manual_seed(123)
            loss = float(np.mean([policy.forward(batch)[0].item() for _ in range(4)]))
            torch.manual_seed(1)
            error = (policy.predict_action_chunk(batch) - target).abs().mean().item()
        return loss, error

    loss_before, error_before = evaluate()
    fit_batch(policy, batch, update=True)
    loss_after, error_after = evaluate()
    assert loss_after < 0.5 * loss_before  # about 0.15 of it after 100 steps
    assert error_after < 0.7 * error_before  # 3 Euler steps of the EMA land near the actions


def test_few_step_inference_is_deterministic_given_a_seed(
    features, observation, assert_seeded_chunks
):
    policy = make_maniflow(features)
    assert_seeded_chunks(policy, observation(2), n_actions=4)


def test_save_load_round_trip_gives_identical_actions(features, observation, ema_save_load):
    policy = make_maniflow(features)
    loaded, expected, got = ema_save_load(policy, lambda: windows(policy, 2), observation(1))
    assert loaded.config.type == "maniflow" and loaded.config.n_emb == 32
    assert int(loaded.ema_updates) == 3
    torch.testing.assert_close(got, expected)


def test_lerobot_train_then_eval_on_an_rmb_env(train_and_eval, tmp_path):
    """Image encoder at a tiny size, evaluated on Insert's 32x32 front camera."""
    size = [f"--policy.{k}={v}" for k, v in TINY.items() if k in CPU_SIZE]
    info = train_and_eval(
        "maniflow",
        [*size, "--policy.obs_encoder=image", "--policy.horizon=8", "--policy.n_action_steps=4"],
    )
    assert info["overall"]["n_episodes"] == 1
    # lerobot-train called policy.update() after each of its 3 steps: the EMA is trained.
    checkpoint = tmp_path / "train" / "checkpoints" / "last" / "pretrained_model"
    assert int(load_file(checkpoint / "model.safetensors")["ema_updates"]) == 3

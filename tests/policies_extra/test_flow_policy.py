"""Flow Policy as a LeRobot plugin: DP3's networks, consistency flow matching, one-step sampling.

The point-cloud pipeline is DP3's and tested in ``test_dp3.py``; here: the config defaults (RMB's),
the training objective, one-step inference, the EMA copy, persistence and the CLIs.
"""

from __future__ import annotations

import numpy as np
import pytest
import torch
from lerobot.configs.policies import PreTrainedConfig
from lerobot.configs.types import FeatureType, PolicyFeature
from lerobot.policies.factory import get_policy_class
from safetensors.torch import load_file

from rmb_lerobot.policies_extra.dp3 import DP3Policy
from rmb_lerobot.policies_extra.flow_policy import FlowPolicy, FlowPolicyConfig
from rmb_lerobot.registration import registered_policy_types

STATE_DIM = ACTION_DIM = 7
SIZE = 32
DEPTH = "observation.images.front_depth"
TINY = {
    "num_points": 64,
    "encoder_channels": (16, 32),
    "encoder_output_dim": 16,
    "state_mlp_dims": (16, 16),
    "down_dims": (32, 64),
    "diffusion_step_embed_dim": 16,
    "camera_fovy": 45.0,
    "device": "cpu",
}


def features() -> tuple[dict, dict]:
    inputs = {
        "observation.state": PolicyFeature(FeatureType.STATE, (STATE_DIM,)),
        DEPTH: PolicyFeature(FeatureType.VISUAL, (1, SIZE, SIZE)),
    }
    return inputs, {"action": PolicyFeature(FeatureType.ACTION, (ACTION_DIM,))}


def make_flow_policy(**overrides) -> FlowPolicy:
    inputs, outputs = features()
    torch.manual_seed(0)
    config = FlowPolicyConfig(input_features=inputs, output_features=outputs, **TINY | overrides)
    return FlowPolicy(config)


def test_flow_policy_is_our_policy_type_and_found_by_lerobots_convention():
    assert "flow_policy" in registered_policy_types()
    assert PreTrainedConfig.get_choice_class("flow_policy") is FlowPolicyConfig
    assert get_policy_class("flow_policy") is FlowPolicy
    assert issubclass(FlowPolicy, DP3Policy)  # DP3's inputs, history and action queue


def test_config_defaults_are_rmbs():
    config = FlowPolicyConfig(device="cpu")
    # RMB TrainFlowPolicy: horizon 8, 2 observations, 4 actions; Conditional_ConsistencyFM.
    assert (config.horizon, config.n_obs_steps, config.n_action_steps) == (8, 2, 4)
    assert config.action_delta_indices == list(range(-1, 7))
    assert (config.num_segments, config.eps, config.delta, config.alpha) == (2, 1e-2, 1e-2, 1e-5)
    assert (config.boundary, config.num_inference_steps, config.use_ema) == (1.0, 1, True)
    with pytest.raises(ValueError, match="num_segments"):
        FlowPolicyConfig(num_segments=0)
    with pytest.raises(ValueError, match="n_action_steps"):
        FlowPolicyConfig(n_action_steps=8)


def test_shapes_a_training_step_and_the_ema_update(depth_box):
    policy = make_flow_policy()
    batch = depth_box.windows(4, policy)
    state, cloud = policy.model_inputs(batch)
    assert state.shape == (4, 2, STATE_DIM) and cloud.shape == (4, 2, 64, 3)

    params = policy.get_optim_params()
    assert all(p.requires_grad for p in params)
    assert not any(p.requires_grad for p in policy.ema_model.parameters())  # not optimised
    policy.train()
    loss, _ = policy.forward(batch)
    loss.backward()
    torch.optim.AdamW(params, lr=1e-2).step()
    assert torch.isfinite(loss)

    ema = next(policy.ema_model.parameters())
    trained = next(policy.model.parameters())
    assert not torch.equal(ema, trained)
    policy.update()  # what lerobot-train calls after each optimizer step; the first copies
    assert torch.equal(ema, trained) and int(policy.ema_updates) == 1
    assert policy.predict_action_chunk(batch).shape == (4, 4, ACTION_DIM)


def test_the_straight_path_velocity_minimises_the_loss(depth_box):
    """Consistency flow matching is minimal (zero) for the velocity of the straight noise ->
    action path, the field whose one Euler step from noise gives the actions."""
    policy = make_flow_policy()
    batch = depth_box.windows(8, policy)
    state, cloud = policy.model_inputs(batch)
    actions = batch["action"]

    def straight(scale: float):
        return lambda x, t, cond: scale * (actions - x) / (1 - t).clamp_min(1e-6).view(-1, 1, 1)

    policy.model.velocity = straight(1.0)
    torch.manual_seed(0)
    assert policy.model.compute_loss(state, cloud, actions) < 1e-10
    policy.model.velocity = straight(1.2)
    torch.manual_seed(0)
    assert policy.model.compute_loss(state, cloud, actions) > 1e-6


def test_loss_and_one_step_error_decrease_on_a_tiny_batch(depth_box, fit_batch):
    """The loss is O(delta^2) and noisy (fresh noise and times every step), so it is compared
    on the same draws before and after training."""
    policy = make_flow_policy()
    batch = depth_box.windows(8, policy)
    state, cloud = policy.model_inputs(batch)
    target = policy.model.executed(batch["action"])

    def evaluate() -> tuple[float, float]:
        with torch.no_grad():
            torch.manual_seed(123)
            loss = np.mean([policy.forward(batch)[0].item() for _ in range(8)])
            torch.manual_seed(1)
            error = (policy.model.generate_actions(state, cloud) - target).abs().mean().item()
        return loss, error

    loss_before, error_before = evaluate()
    fit_batch(policy, batch)
    loss_after, error_after = evaluate()
    assert loss_after < 0.7 * loss_before  # about 0.5 after 100 steps
    assert error_after < 0.9 * error_before  # one step from noise moves towards the actions


def test_one_step_inference_is_deterministic_given_a_seed(depth_box, assert_seeded_chunks):
    policy = make_flow_policy()
    assert_seeded_chunks(policy, depth_box.observation(2), n_actions=4)


def test_few_step_inference_is_a_config_choice(depth_box):
    """The same weights and noise: 3 Euler steps (the velocity at t = eps, 1/3, 2/3 of the way)
    give another chunk than the default single step at t = eps."""
    one, three = make_flow_policy(), make_flow_policy(num_inference_steps=3)  # both seeded 0
    torch.testing.assert_close(three.state_dict(), one.state_dict())
    times: dict[int, list[float]] = {1: [], 3: []}
    for steps, policy in ((1, one), (3, three)):
        model = policy.sampling_model()  # the EMA copy
        velocity = model.velocity

        def recording(x, t, cond, velocity=velocity, seen=times[steps]):
            seen.append(t.item())
            return velocity(x, t, cond)

        model.velocity = recording
    noise = torch.randn(1, one.config.horizon, ACTION_DIM)
    with torch.no_grad():
        chunk_1 = one.predict_action_chunk(depth_box.observation(1), noise=noise)
        chunk_3 = three.predict_action_chunk(depth_box.observation(1), noise=noise)
    assert chunk_1.shape == chunk_3.shape == (1, 4, ACTION_DIM)
    eps = one.config.eps
    assert times[1] == pytest.approx([eps])
    assert times[3] == pytest.approx([eps, eps + (1 - eps) / 3, eps + 2 * (1 - eps) / 3])
    assert (chunk_3 - chunk_1).abs().max() > 1e-3


def test_save_load_round_trip_gives_identical_actions(depth_box, ema_save_load):
    policy = make_flow_policy()
    loaded, expected, got = ema_save_load(
        policy, lambda: depth_box.windows(2, policy), depth_box.observation(1)
    )
    assert loaded.config.type == "flow_policy" and loaded.config.camera_fovy == 45.0
    assert int(loaded.ema_updates) == 3
    torch.testing.assert_close(got, expected)


def test_lerobot_train_then_eval_on_an_rmb_env(expert_depth_dataset, train_and_eval_on, tmp_path):
    result = train_and_eval_on(
        expert_depth_dataset,
        "flow_policy",
        ["--policy.num_points=64", "--policy.down_dims=[32,64]"],
        [
            "--env.cameras=[front]",
            f"--env.image_width={SIZE}",
            f"--env.image_height={SIZE}",
            "--env.depth=true",  # delivers observation.images.front_depth
        ],
    )
    config = result["config"]
    assert config["type"] == "flow_policy" and config["camera_fovy"] == 45.0
    assert (config["horizon"], config["num_inference_steps"]) == (8, 1)
    assert result["eval"]["overall"]["n_episodes"] == 1
    # lerobot-train called policy.update() after each of its 3 steps: the EMA is trained.
    checkpoint = tmp_path / "train" / "checkpoints" / "last" / "pretrained_model"
    assert int(load_file(checkpoint / "model.safetensors")["ema_updates"]) == 3

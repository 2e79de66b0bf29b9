"""RMB's MLP policy as a LeRobot plugin: API, learning, persistence, and LeRobot's CLIs."""

from __future__ import annotations

import torch
from lerobot.configs.policies import PreTrainedConfig
from lerobot.configs.types import FeatureType, PolicyFeature
from lerobot.policies.factory import get_policy_class, make_pre_post_processors
from lerobot.processor import make_default_pre_post_processors

from rmb_lerobot.policies_extra.mlp import MLPConfig, MLPPolicy
from rmb_lerobot.registration import registered_policy_types

STATE_DIM = ACTION_DIM = 7  # as the ``features`` fixture
IMAGE = (3, 32, 32)
FRONT = "observation.images.front"
SMALL = {"state_feature_dim": 32, "hidden_dims": [64, 64], "device": "cpu"}


def make_policy(features, **overrides) -> MLPPolicy:
    inputs, outputs = features
    torch.manual_seed(0)
    return MLPPolicy(
        MLPConfig(input_features=inputs, output_features=outputs, **SMALL, **overrides)
    )


def test_mlp_is_our_policy_type_and_found_by_lerobots_convention():
    assert "mlp" in registered_policy_types()
    assert PreTrainedConfig.get_choice_class("mlp") is MLPConfig
    assert get_policy_class("mlp") is MLPPolicy


def test_config_follows_act_chunking_and_obs_history():
    config = MLPConfig(n_obs_steps=3, chunk_size=5, n_action_steps=2, device="cpu")
    assert config.observation_delta_indices == [-2, -1, 0]
    assert config.action_delta_indices == [0, 1, 2, 3, 4]
    assert MLPConfig(device="cpu").observation_delta_indices is None
    assert config.get_optimizer_preset().lr == config.optimizer_lr
    try:
        MLPConfig(chunk_size=2, n_action_steps=3, device="cpu")
    except ValueError as exc:
        assert "n_action_steps" in str(exc)
    else:  # pragma: no cover
        raise AssertionError("n_action_steps > chunk_size must be rejected")


def test_only_rgb_cameras_feed_the_resnet(features):
    inputs, outputs = features
    inputs = {
        **inputs,
        "observation.images.front_depth": PolicyFeature(FeatureType.VISUAL, (1, 8, 8)),
    }
    config = MLPConfig(input_features=inputs, output_features=outputs, device="cpu")
    try:
        config.validate_features()
    except ValueError as exc:
        assert "front_depth" in str(exc)
    else:  # pragma: no cover
        raise AssertionError("a 1-channel camera must be rejected")


def test_shapes_and_a_training_step(features, observation):
    policy = make_policy(features, n_obs_steps=2, chunk_size=4, n_action_steps=2)
    params = policy.get_optim_params()
    assert isinstance(params, list) and all(isinstance(p, torch.nn.Parameter) for p in params)
    batch = {key: torch.stack([v, v], dim=1) for key, v in observation(3).items()}
    batch["action"] = torch.randn(3, 4, ACTION_DIM)
    batch["action_is_pad"] = torch.tensor([[False] * 4, [False] * 4, [False, False, True, True]])
    assert policy.predict_action_chunk(batch).shape == (3, 4, ACTION_DIM)

    policy.train()
    optimizer = torch.optim.AdamW(params, lr=1e-4)
    loss, info = policy.forward(batch)
    loss.backward()
    optimizer.step()
    assert loss.ndim == 0 and torch.isfinite(loss) and info["mse_loss"] == loss.item()


def test_padded_actions_do_not_count(features, observation):
    policy = make_policy(features, chunk_size=3, n_action_steps=3)
    batch = {**observation(2), "action": torch.zeros(2, 3, ACTION_DIM)}
    batch["action_is_pad"] = torch.tensor([[False, False, True], [False, True, True]])
    loss, _ = policy.forward(batch)
    batch["action"][batch["action_is_pad"]] = 1e3
    assert torch.allclose(policy.forward(batch)[0], loss)


def test_overfits_a_tiny_batch(features, observation):
    # The ResNet is frozen only to keep this CPU test fast (Adam over its 11M weights costs
    # ~0.5 s a step on 2 shared cores); the step above trains it, and its features still feed
    # the head here. Frozen weights must drop out of the optimizer's parameters.
    policy = make_policy(features, chunk_size=2, n_action_steps=2)
    policy.model.backbone.requires_grad_(False)
    assert len(policy.get_optim_params()) == 8  # state encoder (2) + 3-layer head (6)
    batch = {**observation(8), "action": torch.randn(8, 2, ACTION_DIM)}
    optimizer = torch.optim.Adam(policy.get_optim_params(), lr=3e-3)
    policy.train()
    losses = []
    for _ in range(30):
        loss, _ = policy.forward(batch)
        optimizer.zero_grad()
        loss.backward()
        optimizer.step()
        losses.append(loss.item())
    assert losses[-1] < 0.25 * losses[0], losses


def test_select_action_runs_the_queue_of_a_chunk(features, observation):
    policy = make_policy(features, n_obs_steps=2, chunk_size=4, n_action_steps=2)
    obs = observation(2)
    policy.reset()
    actions = [policy.select_action(obs) for _ in range(2)]
    # The first query sees the first observation repeated n_obs_steps times (LeRobot's rule).
    chunk = policy.predict_action_chunk({k: torch.stack([v, v], dim=1) for k, v in obs.items()})
    torch.testing.assert_close(torch.stack(actions, dim=1), chunk[:, :2])
    assert len(policy._action_queue) == 0
    policy.select_action(observation(2, seed=1))  # refills the queue from a new history
    assert len(policy._action_queue) == 1
    policy.reset()
    torch.testing.assert_close(policy.select_action(obs), actions[0])


def test_save_load_round_trip_gives_identical_actions(features, tmp_path, observation):
    policy = make_policy(features, chunk_size=2, n_action_steps=1)
    stats = {
        "observation.state": {"mean": torch.ones(STATE_DIM), "std": 2 * torch.ones(STATE_DIM)},
        FRONT: {"mean": torch.full((3, 1, 1), 0.4), "std": torch.full((3, 1, 1), 0.2)},
        "action": {"mean": torch.full((ACTION_DIM,), 0.5), "std": torch.full((ACTION_DIM,), 3.0)},
    }
    pre, post = make_default_pre_post_processors(policy.config, stats)
    for part in (policy, pre, post):
        part.save_pretrained(tmp_path)

    config = PreTrainedConfig.from_pretrained(tmp_path)
    assert config.type == "mlp" and config.hidden_dims == [64, 64]
    loaded = get_policy_class(config.type).from_pretrained(tmp_path)
    pre2, post2 = make_pre_post_processors(config, pretrained_path=str(tmp_path))

    obs = observation(1, seed=3)
    policy.reset()
    loaded.reset()
    for _ in range(3):
        expected = post(policy.select_action(pre(obs)))
        torch.testing.assert_close(post2(loaded.select_action(pre2(obs))), expected)


def test_lerobot_train_then_eval_on_an_rmb_env(train_and_eval):
    info = train_and_eval(
        "mlp", ["--policy.chunk_size=4", "--policy.n_action_steps=2", "--policy.hidden_dims=[64]"]
    )
    assert info["overall"]["n_episodes"] == 1

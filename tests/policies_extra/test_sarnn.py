"""SARNN as a LeRobot plugin: layers, sequence training, stateful rollout, persistence, CLIs."""

from __future__ import annotations

import torch
from lerobot.configs.policies import PreTrainedConfig
from lerobot.configs.types import FeatureType, PolicyFeature
from lerobot.policies.factory import get_policy_class, make_pre_post_processors
from lerobot.processor import make_default_pre_post_processors

from rmb_lerobot.policies_extra.sarnn import SARNNConfig, SARNNPolicy
from rmb_lerobot.policies_extra.sarnn.modeling_sarnn import InverseSpatialSoftmax, SpatialSoftmax
from rmb_lerobot.registration import registered_policy_types

STATE_DIM = ACTION_DIM = 7  # as the ``features`` fixture
IMAGE = (3, 32, 32)
FRONT = "observation.images.front"
QUIET = {"state_noise_std": 0.0, "image_noise_std": 0.0, "keypoint_loss_warmup_steps": 0}


def make_policy(features, **overrides) -> SARNNPolicy:
    inputs, outputs = features
    torch.manual_seed(0)
    kwargs = {"image_size": None, "sequence_length": 6, "frame_skip": 1, "device": "cpu"}
    return SARNNPolicy(
        SARNNConfig(input_features=inputs, output_features=outputs, **kwargs | overrides)
    )


def test_sarnn_is_our_policy_type_and_found_by_lerobots_convention():
    assert "sarnn" in registered_policy_types()
    assert PreTrainedConfig.get_choice_class("sarnn") is SARNNConfig
    assert get_policy_class("sarnn") is SARNNPolicy


def test_windows_pair_each_step_with_the_next_command():
    config = SARNNConfig(sequence_length=3, frame_skip=6, device="cpu")
    # Observations at steps 0..L (the last is only an image/keypoint target), actions at 1..L:
    # what is learnt at frame 6k is the command at frame 6(k+1), held for 6 env steps.
    assert config.observation_delta_indices == [0, 6, 12, 18]
    assert config.action_delta_indices == [6, 12, 18]
    assert config.normalization_mapping["VISUAL"].value == "IDENTITY"  # images are targets


def test_spatial_softmax_finds_a_peak_and_the_heatmap_returns_it():
    features = torch.zeros(1, 1, 9, 17)
    features[0, 0, 2, 12] = 1.0
    keypoint = SpatialSoftmax(9, 17, temperature=1e-4)(features)
    torch.testing.assert_close(keypoint, torch.tensor([[[12 / 16, 2 / 8]]]))
    heatmap = InverseSpatialSoftmax(9, 17, heatmap_size=0.1)(keypoint)
    assert heatmap.shape == (1, 1, 9, 17)
    assert heatmap.flatten().argmax() == 2 * 17 + 12 and heatmap.max() == 1.0


def test_shapes_and_a_training_step(features, windows):
    policy = make_policy(features, image_size=(24, 24))
    batch = windows(6)
    n_windows = batch["action"].shape[0]
    out = policy.model.run_sequence(
        batch["observation.state"][:, :-1], [policy.model.resize(batch[FRONT])]
    )
    assert out.states.shape == (n_windows, 6, ACTION_DIM)
    assert out.keypoints[0].shape == (n_windows, 7, 5, 2)
    assert out.next_keypoints[0].shape == (n_windows, 6, 5, 2)
    assert out.images[0].shape == (n_windows, 6, 3, 24, 24)

    params = policy.get_optim_params()
    assert isinstance(params, list) and all(isinstance(p, torch.nn.Parameter) for p in params)
    policy.train()
    loss, info = policy.forward(batch)
    loss.backward()
    torch.optim.Adam(params).step()
    assert torch.isfinite(loss) and set(info) >= {"state_loss", "image_loss", "keypoint_loss"}
    assert int(policy.train_steps) == 1


def test_every_camera_gets_its_own_branch_depth_included(features, windows, observation):
    inputs, outputs = features
    depth = "observation.images.front_depth"
    inputs = {**inputs, depth: PolicyFeature(FeatureType.VISUAL, (1, 20, 24))}
    policy = make_policy((inputs, outputs), image_size=None)
    assert len(policy.model.cameras) == 2
    batch = windows(3)
    batch[depth] = torch.rand(batch[FRONT].shape[0], 4, 1, 20, 24)
    loss, _ = policy.forward(batch)
    assert torch.isfinite(loss)
    obs = {**observation(2), depth: torch.rand(2, 1, 20, 24)}
    assert policy.select_action(obs).shape == (2, ACTION_DIM)


def test_padded_steps_do_not_count(features, windows):
    policy = make_policy(features, **QUIET)
    batch = windows(6)
    batch["action_is_pad"][:, 4:] = True
    loss, _ = policy.forward(batch)
    batch["action"][:, 4:] = 1e3
    batch[FRONT][:, 5:] = 1.0  # image targets of the padded steps
    torch.testing.assert_close(policy.forward(batch)[0], loss)


def test_keypoint_loss_weight_ramps_up_on_an_s_curve(features, windows):
    policy = make_policy(features, keypoint_loss_warmup_steps=4)
    policy.train()
    weights = []
    for _ in range(6):
        weights.append(policy.forward(windows(2))[1]["keypoint_weight"])
    assert weights[0] == 0.0 and weights[-1] == weights[-2] == policy.config.keypoint_loss_weight
    assert weights == sorted(weights)


def test_overfits_a_tiny_batch_of_sequences(features, windows):
    policy = make_policy(features, image_size=(16, 16), **QUIET)
    batch = {key: value[::3] for key, value in windows(6).items()}  # 6 windows of 6 steps
    optimizer = torch.optim.Adam(policy.get_optim_params(), lr=3e-3)
    policy.train()
    losses = []
    for _ in range(40):
        loss, info = policy.forward(batch)
        optimizer.zero_grad()
        loss.backward()
        optimizer.step()
        losses.append((loss.item(), info["state_loss"]))
    assert losses[-1][0] < 0.25 * losses[0][0], losses
    assert losses[-1][1] < 0.25 * losses[0][1], losses


def test_rollout_is_stateful_holds_commands_and_resets(features, observation):
    policy = make_policy(features, frame_skip=3)
    policy.reset()
    obs = [observation(2, seed=i) for i in range(7)]
    actions = [policy.select_action(o) for o in obs]
    for i in (1, 2, 4, 5):  # held between LSTM steps (every frame_skip env steps)
        torch.testing.assert_close(actions[i], actions[i - 1])
    assert not torch.allclose(actions[3], actions[0])

    policy.reset()
    first = policy.predict_action_chunk(obs[0])
    assert first.shape == (2, 1, ACTION_DIM)
    torch.testing.assert_close(first[:, 0], actions[0])
    # Same input, different recurrent state -> a different command.
    assert not torch.allclose(policy.predict_action_chunk(obs[0]), first)


def test_save_load_round_trip_gives_identical_actions(features, tmp_path, observation):
    policy = make_policy(features, image_size=(16, 16))
    stats = {
        "observation.state": {"mean": torch.ones(STATE_DIM), "std": 2 * torch.ones(STATE_DIM)},
        "action": {"mean": torch.full((ACTION_DIM,), 0.5), "std": torch.full((ACTION_DIM,), 3.0)},
    }
    pre, post = make_default_pre_post_processors(policy.config, stats)
    for part in (policy, pre, post):
        part.save_pretrained(tmp_path)

    config = PreTrainedConfig.from_pretrained(tmp_path)
    assert config.type == "sarnn" and tuple(config.image_size) == (16, 16)
    loaded = get_policy_class(config.type).from_pretrained(tmp_path)
    pre2, post2 = make_pre_post_processors(config, pretrained_path=str(tmp_path))

    policy.reset()
    loaded.reset()
    for seed in range(4):
        obs = observation(1, seed=seed)
        expected = post(policy.select_action(pre(obs)))
        torch.testing.assert_close(post2(loaded.select_action(pre2(obs))), expected)


def test_lerobot_train_then_eval_on_an_rmb_env(train_and_eval):
    info = train_and_eval(
        "sarnn",
        ["--policy.sequence_length=4", "--policy.frame_skip=2", "--policy.image_size=[32,32]"],
    )
    assert info["overall"]["n_episodes"] == 1

"""DP3 as a LeRobot plugin: point clouds from depth, training, rollout, persistence, CLIs.

The env/dataset test checks what the policy relies on: an RMB env type with ``--env.depth=true``
hands the policy the same depth (key, layout, unit) as the converted dataset it was trained on.
"""

from __future__ import annotations

import json
import math
import shutil

import numpy as np
import pytest
import torch
from lerobot.configs.policies import PreTrainedConfig
from lerobot.configs.types import FeatureType, NormalizationMode, PolicyFeature
from lerobot.datasets import LeRobotDataset, LeRobotDatasetMetadata
from lerobot.envs.utils import preprocess_observation
from lerobot.policies.factory import get_policy_class, make_policy, make_pre_post_processors
from safetensors.torch import load_file

from rmb_lerobot import keys as K
from rmb_lerobot import lerobot_names as N
from rmb_lerobot.envs.lerobot_config import ENV_CONFIGS
from rmb_lerobot.envs.registry import ENVS
from rmb_lerobot.envs.workspace import RMB_TABLE
from rmb_lerobot.pointcloud import transform_points
from rmb_lerobot.policies_extra.dp3 import DP3Config, DP3Policy
from rmb_lerobot.policies_extra.dp3.configuration_dp3 import DEFAULT_CROP
from rmb_lerobot.policies_extra.dp3.point_cloud import DepthPointClouds
from rmb_lerobot.registration import registered_policy_types

STATE_DIM = ACTION_DIM = 7
SIZE = 32
FRONT = "observation.images.front"
DEPTH = "observation.images.front_depth"
TINY = {
    "num_points": 64,
    "encoder_channels": (16, 32),
    "encoder_output_dim": 16,
    "state_mlp_dims": (16, 16),
    "down_dims": (32, 64),
    "diffusion_step_embed_dim": 16,
    "horizon": 8,
    "n_action_steps": 4,
    "camera_fovy": 45.0,
    "device": "cpu",
}


def features(color: bool = False) -> tuple[dict, dict]:
    inputs = {
        "observation.state": PolicyFeature(FeatureType.STATE, (STATE_DIM,)),
        DEPTH: PolicyFeature(FeatureType.VISUAL, (1, SIZE, SIZE)),
    }
    if color:
        inputs[FRONT] = PolicyFeature(FeatureType.VISUAL, (3, SIZE, SIZE))
    return inputs, {"action": PolicyFeature(FeatureType.ACTION, (ACTION_DIM,))}


def make_dp3(color: bool = False, **overrides) -> DP3Policy:
    inputs, outputs = features(color)
    torch.manual_seed(0)
    config = DP3Config(input_features=inputs, output_features=outputs, **TINY | overrides)
    return DP3Policy(config)


def test_dp3_is_our_policy_type_and_found_by_lerobots_convention():
    assert "dp3" in registered_policy_types()
    assert PreTrainedConfig.get_choice_class("dp3") is DP3Config
    assert get_policy_class("dp3") is DP3Policy


def test_config_windows_defaults_and_checks():
    config = DP3Config(device="cpu")
    # The current frame and the previous one; actions from the previous frame on.
    assert config.observation_delta_indices == [-1, 0]
    assert config.action_delta_indices == list(range(-1, 15))
    assert (config.num_points, config.n_action_steps, config.num_inference_steps) == (512, 8, 10)
    with pytest.raises(ValueError, match="IDENTITY"):
        DP3Config(normalization_mapping={"VISUAL": NormalizationMode.MEAN_STD})
    with pytest.raises(ValueError, match="n_action_steps"):
        DP3Config(horizon=8, n_action_steps=8)
    inputs, outputs = features(color=True)
    config = DP3Config(input_features=inputs, output_features=outputs, use_pc_color=True)
    assert (config.depth_key, config.color_key, config.point_dim) == (DEPTH, FRONT, 6)
    rgb_only = {key: ft for key, ft in inputs.items() if key != DEPTH}
    rgb_only = DP3Config(input_features=rgb_only, output_features=outputs, device="cpu")
    with pytest.raises(ValueError, match="exactly one depth camera"):
        rgb_only.validate_features()


def test_point_clouds_are_metric_cropped_and_fixed_size(depth_box):
    config = DP3Config(camera_fovy=60.0, num_points=128, crop_max=(2, 2, 1.0), device="cpu")
    clouds = DepthPointClouds(config)
    depth = depth_box.depth_mm((2, 3))
    cloud = clouds(depth)
    assert cloud.shape == (2, 3, 128, 3) and cloud.dtype == torch.float32
    # The 3 m wall is cropped away; the table and the box remain, in metres.
    z = cloud[..., 2].unique()
    torch.testing.assert_close(z, torch.tensor([0.6, 0.8]))
    # Pinhole geometry: the widest table point is at half the field of view horizontally.
    half_width = 0.8 * math.tan(math.radians(30.0))  # fovy 60 deg, square image
    assert cloud[..., 0].min() == pytest.approx(-half_width, rel=1e-5)
    # Same frame, same cloud (memoised by content).
    assert torch.equal(clouds(depth[:1, :1]), cloud[:1, :1])


def test_colored_points_carry_the_rgb_of_their_pixel(depth_box):
    config = DP3Config(camera_fovy=45.0, num_points=32, use_pc_color=True, device="cpu")
    rgb = torch.zeros(1, 3, SIZE, SIZE)
    rgb[:, 0] = 1.0  # red table and box
    cloud = DepthPointClouds(config)(depth_box.depth_mm((1,)), rgb)
    assert cloud.shape == (1, 32, 6)
    torch.testing.assert_close(cloud[0, :, 3:], torch.tensor([1.0, 0, 0]).expand(32, 3))


def test_shapes_and_a_training_step(depth_box):
    policy = make_dp3()
    batch = depth_box.windows(4, policy)
    state, cloud = policy.model_inputs(batch)
    assert state.shape == (4, 2, STATE_DIM) and cloud.shape == (4, 2, 64, 3)
    assert policy.model.global_condition(state, cloud).shape == (4, 2 * (16 + 16))

    params = policy.get_optim_params()
    assert isinstance(params, list) and all(isinstance(p, torch.nn.Parameter) for p in params)
    policy.train()
    loss, _ = policy.forward(batch)
    loss.backward()
    torch.optim.AdamW(params).step()
    assert torch.isfinite(loss)
    assert policy.predict_action_chunk(batch).shape == (4, 4, ACTION_DIM)


def test_samples_from_the_average_of_its_weights_as_rmb(depth_box, fit_batch):
    config = DP3Config(device="cpu")
    # RMB's TrainDiffusionPolicy3d: EMAModel(power=0.75, max_value=0.9999), on by default.
    assert (config.use_ema, config.ema_power, config.ema_max_decay) == (True, 0.75, 0.9999)
    policy = make_dp3()
    batch = depth_box.windows(4, policy)
    fit_batch(policy, batch, steps=5, update=True)  # lerobot-train calls update() per step
    assert int(policy.ema_updates) == 5
    assert policy.sampling_model() is policy.ema_model
    assert not torch.equal(next(policy.ema_model.parameters()), next(policy.model.parameters()))
    noise = torch.randn(4, policy.config.horizon, ACTION_DIM)
    policy.eval()
    state, cloud = policy.model_inputs(batch)
    from_average = policy.ema_model.generate_actions(state, cloud, noise=noise)
    torch.testing.assert_close(policy.predict_action_chunk(batch, noise=noise), from_average)

    plain = make_dp3(use_ema=False)
    assert plain.ema_model is None and plain.sampling_model() is plain.model
    assert not any(key.startswith("ema") for key in plain.state_dict())
    with pytest.raises(ValueError, match="ema_max_decay"):
        DP3Config(ema_max_decay=1.0)


def test_save_load_keeps_the_average(depth_box, ema_save_load):
    policy = make_dp3()
    loaded, expected, got = ema_save_load(
        policy, lambda: depth_box.windows(2, policy), depth_box.observation(1)
    )
    assert loaded.config.use_ema and int(loaded.ema_updates) == 3
    torch.testing.assert_close(got, expected)


def test_overfits_a_tiny_batch(depth_box):
    policy = make_dp3()
    batch = depth_box.windows(8, policy)
    optimizer = torch.optim.AdamW(policy.get_optim_params(), lr=3e-3)
    policy.train()
    torch.manual_seed(0)
    losses = []
    for _ in range(60):
        loss, _ = policy.forward(batch)
        optimizer.zero_grad()
        loss.backward()
        optimizer.step()
        losses.append(loss.item())
    first, last = np.mean(losses[:5]), np.mean(losses[-5:])
    assert last < 0.3 * first, losses


def test_select_action_after_reset_executes_one_chunk_then_replans(depth_box):
    policy = make_dp3()
    obs = depth_box.observation(2)
    noise = torch.randn(2, policy.config.horizon, ACTION_DIM)
    policy.reset()
    chunk = policy.predict_action_chunk(obs, noise=noise)
    assert chunk.shape == (2, 4, ACTION_DIM)

    policy.reset()
    actions = [policy.select_action(obs, noise=noise) for _ in range(4)]
    torch.testing.assert_close(torch.stack(actions, dim=1), chunk)
    # The queue is empty: the next call plans again, now from two different frames.
    other = depth_box.observation(2, seed=5)
    assert not torch.allclose(policy.select_action(other, noise=noise), actions[0])
    with pytest.raises(KeyError, match=r"--env\.depth=true"):
        policy.select_action({"observation.state": other["observation.state"]})


def test_save_load_round_trip_gives_identical_actions(depth_box, tmp_path):
    policy = make_dp3(color=True, use_pc_color=True)
    stats = {
        "observation.state": {"min": -torch.ones(STATE_DIM), "max": torch.ones(STATE_DIM)},
        "action": {"min": torch.zeros(ACTION_DIM), "max": torch.full((ACTION_DIM,), 2.0)},
    }
    pre, post = make_pre_post_processors(policy.config, dataset_stats=stats)
    for part in (policy, pre, post):
        part.save_pretrained(tmp_path)

    config = PreTrainedConfig.from_pretrained(tmp_path)
    assert config.type == "dp3" and config.camera_fovy == 45.0 and config.use_pc_color
    loaded = get_policy_class(config.type).from_pretrained(tmp_path)
    pre2, post2 = make_pre_post_processors(config, pretrained_path=str(tmp_path))

    obs = {**depth_box.observation(1), FRONT: torch.rand(1, 3, SIZE, SIZE)}
    noise = torch.randn(1, config.horizon, ACTION_DIM)
    policy.reset()
    loaded.reset()
    expected = post(policy.select_action(pre(obs), noise=noise))
    torch.testing.assert_close(post2(loaded.select_action(pre2(obs), noise=noise)), expected)


def test_fovy_comes_from_the_converted_dataset(expert_depth_dataset):
    meta = LeRobotDatasetMetadata("local/insert_depth", root=expert_depth_dataset)
    assert meta.depth_keys == [DEPTH]
    policy = make_policy(DP3Config(device="cpu", num_points=32), ds_meta=meta)
    assert policy.config.camera_fovy == 45.0  # meta/rmb.json: front_depth_image_fovy
    with pytest.raises(ValueError, match=r"records 45\.0"):
        make_policy(DP3Config(device="cpu", camera_fovy=62.0), ds_meta=meta)


def test_env_depth_is_the_datasets_depth(expert_depth_dataset):
    """What lerobot-eval feeds the policy equals what lerobot-train fed it (within the codec)."""
    dataset = LeRobotDataset("local/insert_depth", root=expert_depth_dataset)
    first = dataset[0]  # episode 0: world 1, reset with seed 0 (rmb-collect's order)
    env_config = ENV_CONFIGS["rmb_ur5e_insert"](
        cameras=["front"], image_width=SIZE, image_height=SIZE, depth=True
    )
    assert env_config.features_map["images.front_depth"] == DEPTH
    vec = env_config.create_envs(n_envs=1)["rmb_ur5e_insert"][0]
    try:
        raw, _ = vec.reset(seed=0, options={"world_idx": 1})
    finally:
        vec.close()
    env_depth = preprocess_observation(raw)[DEPTH]

    train_depth = first[DEPTH]
    assert env_depth.shape == (1, *train_depth.shape) == (1, 1, SIZE, SIZE)
    assert env_depth.dtype == train_depth.dtype == torch.float32
    assert 500 < train_depth.median() < 3000  # millimetres, both
    # LeRobot's 12-bit log depth codec: steps of ~2 mm at 3.5 m, rounded to the nearest mm.
    assert (env_depth[0] - train_depth).abs().max() <= 2.0


def test_lerobot_train_then_eval_on_an_rmb_env(expert_depth_dataset, train_and_eval_on, tmp_path):
    result = train_and_eval_on(
        expert_depth_dataset,
        "dp3",
        [
            "--policy.num_points=64",
            "--policy.down_dims=[32,64]",
            "--policy.horizon=8",
            "--policy.n_action_steps=4",
        ],
        [
            "--env.cameras=[front]",
            f"--env.image_width={SIZE}",
            f"--env.image_height={SIZE}",
            "--env.depth=true",  # delivers observation.images.front_depth
        ],
    )
    assert result["config"]["type"] == "dp3" and result["config"]["camera_fovy"] == 45.0
    # The dataset records the front camera's pose: trained and evaluated in the world frame.
    assert np.asarray(result["config"]["camera_pose"]).shape == (4, 4)
    assert result["eval"]["overall"]["n_episodes"] == 1
    # lerobot-train called policy.update() after each of its 3 steps: the EMA is trained.
    checkpoint = tmp_path / "train" / "checkpoints" / "last" / "pretrained_model"
    assert int(load_file(checkpoint / "model.safetensors")["ema_updates"]) == 3


# ---------------------------------------------------------------- crop frame and camera pose
# The front camera of the UR5e table (rmb-collect records it as front_depth_image_pose).
FRONT_POSE = [
    [0.0, 0.5**0.5, -(0.5**0.5), 0.5],
    [1.0, 0.0, 0.0, 0.0],
    [0.0, -(0.5**0.5), -(0.5**0.5), 1.5],
    [0.0, 0.0, 0.0, 1.0],
]


def test_crop_frame_auto_follows_the_pose_and_boxes_default_per_frame():
    camera = DP3Config(device="cpu")
    assert (camera.crop_frame, camera.resolved_crop_frame) == ("auto", "camera")
    assert camera.crop_box() == DEFAULT_CROP["camera"] == ((-1.5, -1.5, 0.1), (1.5, 1.5, 1.5))
    world = DP3Config(device="cpu", camera_pose=FRONT_POSE)
    assert world.resolved_crop_frame == "world" and world.crop_box() == DEFAULT_CROP["world"]
    # The world box starts above the UR5e table top: the table surface is dropped.
    assert DEFAULT_CROP["world"][0][2] > RMB_TABLE.table.top_z
    forced = DP3Config(device="cpu", camera_pose=FRONT_POSE, crop_frame="camera")
    assert forced.resolved_crop_frame == "camera"
    own = DP3Config(device="cpu", camera_pose=FRONT_POSE, crop_max=(0.3, 0.4, 1.2))
    assert own.crop_box() == (DEFAULT_CROP["world"][0], (0.3, 0.4, 1.2))


def test_crop_and_pose_checks_name_the_value():
    with pytest.raises(ValueError, match=r"crop_frame.*'table'"):
        DP3Config(crop_frame="table")
    with pytest.raises(ValueError, match=r"camera_pose must be a finite 4x4.*\[1, 2, 3\]"):
        DP3Config(camera_pose=[1, 2, 3])
    skewed = [row[:] for row in FRONT_POSE]
    skewed[0][0] = 2.0
    with pytest.raises(ValueError, match="camera_pose must be a rigid transform"):
        DP3Config(camera_pose=skewed)
    with pytest.raises(ValueError, match=r"crop_min .* must be <= crop_max .*world frame"):
        DP3Config(camera_pose=FRONT_POSE, crop_min=(0.0, 0.0, 2.0))
    with pytest.raises(ValueError, match="crop_max must be 3 finite numbers"):
        DP3Config(crop_max=(1.0, float("nan"), 1.0))


def test_world_crop_without_a_pose_raises_naming_it():
    with pytest.raises(ValueError, match="crop_frame='world' needs camera_pose"):
        make_dp3(crop_frame="world")
    assert make_dp3().point_clouds.frame == "camera"  # auto, no pose: today's camera frame


def test_save_load_keeps_the_pose_and_the_crop_frame(tmp_path):
    policy = make_dp3(camera_pose=FRONT_POSE, crop_frame="world", crop_min=(-0.7, -0.5, 0.83))
    policy.config.save_pretrained(tmp_path)
    config = PreTrainedConfig.from_pretrained(tmp_path)
    assert config.crop_frame == "world" and config.crop_box()[0] == (-0.7, -0.5, 0.83)
    np.testing.assert_allclose(config.camera_pose, FRONT_POSE)
    assert config.crop_max is None  # the frame's default, decided when the cloud is built
    assert DepthPointClouds(config).frame == "world"


@pytest.fixture(scope="module")
def insert_front_frames() -> list[tuple[np.ndarray, dict]]:
    """64x64 front depth (mm) of the Insert env in three worlds, with the episode attributes."""
    import gymnasium as gym

    env = gym.make(ENVS["insert"].gym_id, cameras=("front",), image_size=(64, 64), depth=True)
    frames = []
    try:
        for world in (0, 3, 5):
            obs, _ = env.reset(seed=world, options={"world_idx": world})
            frames.append((obs["depth"]["front"].astype(np.float32), env.unwrapped.rmb_attrs()))
    finally:
        env.close()
    return frames


def test_world_crop_drops_the_table_and_keeps_the_scene(insert_front_frames):
    """Camera-frame crop: most of the 512 points are the table. World-frame crop (the recorded
    pose): next to none are, and the hole/peg above the table and the arm are kept."""
    top = RMB_TABLE.table.top_z
    (hx, hy) = RMB_TABLE.table.half_size
    for depth, attrs in insert_front_frames:
        pose = attrs[K.camera_pose_attr("front")]
        common = {"camera_fovy": attrs[K.fovy_attr("front")], "num_points": 512, "device": "cpu"}
        old = DepthPointClouds(DP3Config(**common))
        new = DepthPointClouds(DP3Config(**common, camera_pose=pose.tolist()))
        old_world = transform_points(old.cloud(depth), matrix=pose)  # to compare in the world
        new_world = new.cloud(depth)
        # ~450 pixels of a 64x64 frame are in the box at reset (repeated to 512).
        assert len(np.unique(new_world, axis=0)) > 400
        near_table = lambda p: np.abs(p[:, 2] - top) < 0.01  # noqa: E731 - the table surface
        assert near_table(old_world).mean() > 0.3 and near_table(new_world).mean() < 0.02
        assert (new_world[:, 2] > top).all()
        over_table = (np.abs(new_world[:, 0]) < hx) & (np.abs(new_world[:, 1]) < hy)
        assert over_table.sum() > 50  # the hole and the peg on the table
        assert (new_world[:, 0] < -0.3).sum() > 100  # the arm, behind the table


def test_make_policy_reads_the_pose_from_the_converted_dataset(expert_depth_dataset, tmp_path):
    meta = LeRobotDatasetMetadata("local/insert_depth", root=expert_depth_dataset)
    rmb = json.loads((expert_depth_dataset / N.RMB_METADATA_PATH).read_text())
    recorded = [ep["attrs"][K.camera_pose_attr("front")] for ep in rmb["episodes"]]
    assert len(recorded) == 2 and recorded[0] == recorded[1]  # nested lists, same in worlds 1, 4
    policy = make_policy(DP3Config(device="cpu", num_points=32), ds_meta=meta)
    assert policy.config.camera_pose == recorded[0]
    assert policy.point_clouds.frame == "world"
    moved = np.asarray(recorded[0])
    moved[2, 3] += 0.1
    with pytest.raises(ValueError, match="but the dataset records"):
        make_policy(DP3Config(device="cpu", camera_pose=moved.tolist()), ds_meta=meta)
    # Old data without the pose: "auto" keeps the camera frame; "world" says what is missing.
    old = tmp_path / "old"
    shutil.copytree(expert_depth_dataset, old)
    for ep in rmb["episodes"]:
        del ep["attrs"][K.camera_pose_attr("front")]
    (old / N.RMB_METADATA_PATH).write_text(json.dumps(rmb))
    old_meta = LeRobotDatasetMetadata("local/insert_depth", root=old)
    policy = make_policy(DP3Config(device="cpu", num_points=32), ds_meta=old_meta)
    assert policy.config.camera_pose is None and policy.point_clouds.frame == "camera"
    with pytest.raises(ValueError, match="needs camera_pose"):
        make_policy(DP3Config(device="cpu", crop_frame="world"), ds_meta=old_meta)

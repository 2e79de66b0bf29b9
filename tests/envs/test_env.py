"""The gymnasium env: API conformance, seeding, worlds, action modes, RMB recording."""

import warnings

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from rmb_lerobot import keys as K
from rmb_lerobot import open_episode
from rmb_lerobot.envs.registry import compose
from rmb_lerobot.envs.tasks.insert import HOLE, InsertTask
from rmb_lerobot.episode import EpisodeWriter
from rmb_lerobot.pose import pose_to_policy


def run(env, actions, seed, options=None):
    obs, _ = env.reset(seed=seed, options=options)
    trace = [obs["agent_pos"].copy()]
    for action in actions:
        obs, *_ = env.step(action)
        trace.append(obs["agent_pos"].copy())
    return np.array(trace), env.sim.data.body(HOLE).xpos.copy()


@pytest.mark.parametrize("mode", ["eef_abs", "eef_rel"])  # joint: every env, test_contract.py
def test_env_checker_passes(mode):
    cameras = ()
    env = compose(InsertTask(), action_mode=mode, cameras=cameras, image_size=(32, 24), depth=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # advice on unbounded/unnormalised boxes
        check_env(env, skip_render_check=False)
    env.close()


def test_contract_attributes(camera_env):
    assert camera_env.metadata["render_fps"] == 31
    assert camera_env.control_dt == pytest.approx(0.032)
    assert camera_env.task_description == InsertTask.description
    assert camera_env.camera_names == ("front", "hand")
    assert camera_env.available_cameras == ("front", "left", "right", "hand")
    obs, info = camera_env.reset(seed=0)
    assert obs["agent_pos"].dtype == np.float32 and obs["agent_pos"].shape == (7,)
    assert info["is_success"] is False
    _, reward, terminated, truncated, info = camera_env.step(camera_env.home_command)
    assert "is_success" in info and reward == 0.0 and not terminated and not truncated


@pytest.mark.parametrize("world_idx", range(6))
def test_each_world_shifts_the_hole(physics_env, world_idx):
    physics_env.reset(seed=0, options={"world_idx": world_idx})
    expected = InsertTask().hole_nominal_pos + InsertTask.world_offsets[world_idx]
    assert physics_env.sim.data.body(HOLE).xpos == pytest.approx(expected)
    assert physics_env.world_idx == world_idx
    assert physics_env.rmb_attrs()[K.ATTR_WORLD_IDX] == world_idx


def test_hole_y_spans_rmb_range():
    ys = InsertTask.world_offsets[:, 1]
    assert ys.min() == pytest.approx(-0.06) and ys.max() == pytest.approx(0.09)


def test_random_shift_is_bounded_planar_and_seeded(physics_env):
    positions = []
    for seed in range(20):
        physics_env.reset(seed=seed, options={"world_idx": 2, "random_shift": 0.01})
        positions.append(physics_env.sim.data.body(HOLE).xpos.copy())
    offsets = np.array(positions) - InsertTask().hole_nominal_pos
    assert np.all(np.abs(offsets[:, :2]) <= 0.01) and np.all(offsets[:, 2] == 0)
    assert np.std(offsets[:, 0]) > 1e-3


def test_world_is_drawn_when_not_given(physics_env):
    worlds = {physics_env.reset(seed=s)[1]["world_idx"] for s in range(30)}
    assert worlds == set(range(6))


def test_bad_reset_options_and_constructor_args_are_named(physics_env):
    with pytest.raises(ValueError, match=r"world_idx must be an integer in 0\.\.5, got 6"):
        physics_env.reset(options={"world_idx": 6})
    with pytest.raises(ValueError, match="unknown reset options"):
        physics_env.reset(options={"world": 1})
    with pytest.raises(ValueError, match="random_shift must be >= 0"):
        physics_env.reset(options={"random_shift": -1})
    with pytest.raises(ValueError, match="action_mode must be one of"):
        compose(InsertTask(), action_mode="torque", cameras=())
    with pytest.raises(ValueError, match="unknown camera 'top'"):
        compose(InsertTask(), cameras=("top",))
    with pytest.raises(ValueError, match=r"action must have shape \(7,\)"):
        physics_env.step(np.zeros(6))


def test_eef_actions_reproduce_the_joint_command():
    env = compose(InsertTask(), action_mode="eef_abs", cameras=())
    env.reset(seed=0)
    pose = env.command_eef_pose
    # eef_abs takes the pose as converted datasets hold it: position + 6-D rotation (9 numbers)
    command = env.command_from_action(np.append(pose_to_policy(pose), 100.0))
    assert command[:6] == pytest.approx(env.home_command[:6], abs=1e-3)
    assert command[6] == 100.0
    with pytest.raises(ValueError, match="degenerate 6-D rotation"):
        env.command_from_action(np.append(pose[:3], [1, 0, 0, 2, 0, 0, 100.0]))
    env.close()
    env = compose(InsertTask(), action_mode="eef_rel", cameras=())
    env.reset(seed=0)
    down = np.array([0, 0, 0.01, 0, 0, 0, 0.0])  # +z of the flange frame points down
    env.step(down)
    moved = env.command_eef_pose
    assert moved[:3] - env.eef_pose(env.home_command)[:3] == pytest.approx([0, 0, -0.01], abs=1e-4)
    env.close()


def test_rmb_step_data_holds_every_recorded_key(physics_env):
    physics_env.reset(seed=0)
    action = physics_env.home_command + 0.01
    step = physics_env.rmb_step_data(action)
    layout = physics_env.robot.layout
    for key in (
        K.MEASURED_JOINT_POS,
        K.COMMAND_JOINT_POS,
        K.MEASURED_JOINT_VEL,
        K.COMMAND_JOINT_VEL,
        K.MEASURED_GRIPPER_JOINT_POS,
        K.COMMAND_GRIPPER_JOINT_POS,
        K.MEASURED_EEF_POSE,
        K.COMMAND_EEF_POSE,
        K.MEASURED_EEF_WRENCH,
    ):
        assert np.shape(step[key]) == (K.spec(key).dim(layout),), key
    assert step[K.COMMAND_JOINT_POS] == pytest.approx(action)
    assert step[K.COMMAND_EEF_POSE] == pytest.approx(physics_env.eef_pose(action))
    assert step[K.TIME] == 0.0 and step[K.REWARD] == 0.0
    physics_env.step(action)
    after = physics_env.rmb_step_data()
    assert after[K.TIME] == pytest.approx(physics_env.control_dt)
    assert after[K.COMMAND_JOINT_POS] == pytest.approx(action)


def test_recorded_episode_reads_back(camera_env, tmp_path):
    camera_env.reset(seed=0, options={"world_idx": 4})
    path = tmp_path / "ep.hdf5"
    with EpisodeWriter(path, camera_env.rmb_attrs(), fk=camera_env.eef_pose) as writer:
        for _ in range(4):
            action = camera_env.home_command
            writer.append(camera_env.rmb_step_data(action))
            camera_env.step(action)
    with open_episode(path) as episode:
        assert episode.attrs[K.ATTR_WORLD_IDX] == 4
        assert episode.attrs[K.fovy_attr("hand")] == pytest.approx(62.0)
        assert episode[K.MEASURED_JOINT_POS].shape == (4, 7)
        assert episode[K.MEASURED_EEF_POSE_REL].shape == (4, 6)
        assert episode["front_rgb_image"].shape == (4, 48, 64, 3)
        assert episode["hand_depth_image"].shape == (4, 48, 64)

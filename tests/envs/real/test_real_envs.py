"""RMB's real envs: their names, a YAML like RMB's, and recorded RMB episodes.

``RealUR5eDemo``, ``RealXarm7Demo`` and ``RealUR5eDualDemo`` resolve to the real backend with
the neutral demo task; a YAML with RMB's keys (``robot_ip``, ``camera_ids``) plus
``driver: sim`` makes a dry-run env on the twins that starts at RMB's real home pose; a
recorded episode holds every key RMB records and reads back.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import yaml

import rmb_lerobot  # noqa: F401 - registers the gymnasium ids
from rmb_lerobot import keys as K
from rmb_lerobot.envs.real.config import load_real_config, make_real_env
from rmb_lerobot.envs.real.options import RealOptions
from rmb_lerobot.envs.real.record import record_episode
from rmb_lerobot.envs.real.task import UR5E_DUAL_LEFT_REAL_HOME, UR5E_REAL_HOME, XARM7_REAL_HOME
from rmb_lerobot.envs.registry import ENVS, REAL_ENVS, entry_for
from rmb_lerobot.envs.robots import UR5E, UR5E_DUAL
from rmb_lerobot.episode import open_episode

FAST = {"image_size": (32, 24), "settle_s": 0.05, "reset_scale": 1.0}


@pytest.mark.parametrize(
    ("name", "robot"),
    [("RealUR5eDemo", "ur5e"), ("RealXarm7Demo", "xarm7"), ("RealUR5eDualDemo", "ur5e_dual")],
)
def test_rmb_real_env_names(name, robot):
    entry = entry_for(name)
    assert entry.simulator == "real" and entry.robot == robot and entry.fps == 50
    assert entry.env_attr == f"{name}Env" and entry.env_attr in entry.robot_record.rmb_envs
    assert entry_for(entry.env_attr) is entry_for(entry.gym_id) is entry
    assert entry.gym_id in gym.registry
    assert entry.name in REAL_ENVS and entry.name not in ENVS  # never in the sim-env sweeps


def test_a_yaml_like_rmbs_makes_a_dry_run_env(tmp_path):
    config = tmp_path / "RealUR5eDemoEnv.yaml"
    config.write_text(
        yaml.safe_dump(
            {
                "robot_ip": "127.0.0.1",
                "camera_ids": {"front": "000000000001", "hand": "000000000002"},
                "driver": "sim",
                **{k: list(v) if isinstance(v, tuple) else v for k, v in FAST.items()},
            }
        )
    )
    assert load_real_config(config)["camera_ids"]["hand"] == "000000000002"
    env = make_real_env("RealUR5eDemo", config)
    try:
        assert env.available_cameras == ("front", "hand") and env.use_depth
        obs, _ = env.reset(seed=0)
        np.testing.assert_allclose(obs["agent_pos"][:6], UR5E_REAL_HOME, atol=0.05)
        assert obs["pixels"]["front"].shape == (24, 32, 3) and "hand" in obs["depth"]
    finally:
        env.close()


def test_the_yaml_needs_a_real_address_for_sdk_and_rmbs_keys_per_robot():
    with pytest.raises(ValueError, match="needs robot_ip"):
        RealOptions(driver="sdk").hosts_for(UR5E)
    with pytest.raises(ValueError, match="robot_ip_left and robot_ip_right"):
        RealOptions(robot_ip="127.0.0.1").hosts_for(UR5E_DUAL)
    assert RealOptions().hosts_for(UR5E_DUAL) == ("127.0.0.1", "127.0.0.1")  # sim: loopback
    sdk = RealOptions(driver="sdk", robot_ip="127.0.0.1", camera_ids={"front": "123"})
    ((name, camera),) = sdk.camera_configs_for(UR5E).items()  # made, never opened
    assert name == "front" and camera.type == "intelrealsense"
    assert (camera.serial_number_or_name, camera.use_depth) == ("123", True)
    assert (camera.width, camera.height, camera.fps) == (640, 480, 30)  # RMB's


def test_a_recorded_episode_holds_every_rmb_key(tmp_path):
    env = make_real_env("RealXarm7Demo", {"driver": "sim", **FAST})
    try:
        home = env.home_command
        np.testing.assert_allclose(home[:7], XARM7_REAL_HOME)
        wave = [home + np.r_[0.1 * np.sin(0.2 * k), np.zeros(7)] for k in range(15)]
        stream = iter(wave)
        path = record_episode(env, lambda obs: next(stream), tmp_path / "demo.rmb", steps=15)
    finally:
        env.close()
    with open_episode(path) as episode:
        assert episode.attrs[K.ATTR_ENV] == "RealXarm7DemoEnv"
        assert list(episode.attrs[K.ATTR_CAMERA_NAMES]) == ["front", "hand"]
        assert episode.attrs[K.fovy_attr("hand")] == pytest.approx(62.0)
        for key in (
            K.MEASURED_JOINT_POS,
            K.COMMAND_JOINT_POS,
            K.MEASURED_JOINT_VEL,
            K.MEASURED_GRIPPER_JOINT_POS,
            K.COMMAND_GRIPPER_JOINT_POS,
            K.MEASURED_EEF_POSE,
            K.COMMAND_EEF_POSE,
            K.MEASURED_EEF_WRENCH,
            K.rgb_image_key("front"),
            K.depth_image_key("hand"),
        ):
            assert episode[key].shape[0] == 15, key
        np.testing.assert_allclose(episode[K.COMMAND_JOINT_POS], np.stack(wave))
        # Stamped in wall-clock time at the control rate: strictly increasing, and paced on
        # the whole (one gap can be short when the deadline-paced loop catches up a stall).
        gaps = np.diff(episode[K.TIME])
        assert np.all(gaps > 0)
        assert np.median(gaps) > 0.01


def test_the_dual_env_records_both_arms():
    env = make_real_env("RealUR5eDualDemo", {"driver": "sim", **FAST})
    try:
        assert env.available_cameras == ("front", "left_hand", "right_hand")
        env.reset(seed=0)
        env.step(env.home_command)
        step = env.rmb_step_data()
        assert step[K.MEASURED_EEF_POSE].shape == (14,) and step[K.MEASURED_EEF_WRENCH].shape == (
            12,
        )
        # RMB's RealUR5eDualDemoEnv pose: the left arm mirrored, the right at the single home.
        joints = step[K.MEASURED_JOINT_POS]
        np.testing.assert_allclose(joints[0:6], UR5E_DUAL_LEFT_REAL_HOME, atol=0.05)
        np.testing.assert_allclose(joints[7:13], UR5E_REAL_HOME, atol=0.05)
    finally:
        env.close()

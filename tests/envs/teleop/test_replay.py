"""Replay: a recorded episode's command re-commanded step by step reproduces the episode."""

from __future__ import annotations

import numpy as np
import pytest

from rmb_lerobot import keys as K
from rmb_lerobot.envs.robots import UR5E, UR5E_DUAL
from rmb_lerobot.envs.teleop.keys import NoKeySource
from rmb_lerobot.envs.teleop.replay import ReplayDevice
from rmb_lerobot.envs.teleop.session import TeleopConfig, TeleopSession
from rmb_lerobot.episode import open_episode
from rmb_lerobot.errors import RmbFormatError

# A replay starts from the same world and home pose and sends the same commands, so the
# measured joints follow the recording; allow for contact and solver differences.
MEASURED_TOL = 1e-3  # rad (and gripper units / 255)


def steps_of(path) -> int:
    with open_episode(path) as episode:
        return len(episode)


def test_replaying_an_episode_reproduces_its_commands(cable_env, recorded_episode, tmp_path):
    device = ReplayDevice(recorded_episode, UR5E)
    device.connect()
    assert len(device) == steps_of(recorded_episode) and device.world_idx == 1
    session = TeleopSession(
        cable_env,
        device,
        NoKeySource(),
        TeleopConfig(out=tmp_path, replay=True, auto_replay=True, save_replay=True, realtime=False),
        log=lambda message: None,
    )
    result = session.run()
    [path] = result.saved
    with open_episode(recorded_episode) as log, open_episode(path) as replay:
        assert replay.attrs["world_idx"] == 1 and len(replay) == len(log)
        for key in (K.COMMAND_JOINT_POS, K.COMMAND_EEF_POSE, K.COMMAND_GRIPPER_JOINT_POS):
            np.testing.assert_allclose(replay[key][:], log[key][:], atol=1e-9, err_msg=key)
        measured, logged = replay[K.MEASURED_JOINT_POS][:], log[K.MEASURED_JOINT_POS][:]
        np.testing.assert_allclose(measured[:, :6], logged[:, :6], atol=MEASURED_TOL)
        np.testing.assert_allclose(measured[:, 6], logged[:, 6], atol=255 * MEASURED_TOL)


def test_relative_keys_start_from_the_first_absolute_value(recorded_episode):
    absolute = ReplayDevice(recorded_episode, UR5E)
    relative = ReplayDevice(recorded_episode, UR5E, key=K.COMMAND_JOINT_POS_REL)
    absolute.connect()
    relative.connect()
    np.testing.assert_allclose(relative.commands, absolute.commands, atol=1e-9)
    first = relative.read().arms[0]
    np.testing.assert_allclose(first.joints, absolute.commands[0, :6])
    assert first.gripper == pytest.approx(0.0)  # the log starts open (0 of 0..255)


def test_replay_ends_and_restarts(recorded_episode):
    device = ReplayDevice(recorded_episode, UR5E)
    device.connect()
    for _ in range(steps_of(recorded_episode)):
        assert device.read().arms
    assert device.done and device.read().arms == {}  # the robot holds
    device.restart()
    assert not device.done


def test_a_log_of_another_robot_is_refused(recorded_episode):
    with pytest.raises(RmbFormatError, match=r"needs \(T, 14\).*another robot") as error:
        ReplayDevice(recorded_episode, UR5E_DUAL).connect()
    assert "command_joint_pos" in str(error.value)
    with pytest.raises(ValueError, match="cannot replay key 'command_eef_pose'"):
        ReplayDevice(recorded_episode, UR5E, key=K.COMMAND_EEF_POSE)

"""The device factory behind ``rmb-teleop --input-device``."""

from __future__ import annotations

import pytest

from rmb_lerobot.envs.robots import PANDA, UR5E, UR5E_DUAL
from rmb_lerobot.envs.teleop.devices import make_device, spacemouse_paths
from rmb_lerobot.envs.teleop.keyboard import KeyboardDevice
from rmb_lerobot.envs.teleop.replay import ReplayDevice


def test_the_keyboard_fits_the_robot():
    dual = make_device("keyboard", UR5E_DUAL)
    assert isinstance(dual, KeyboardDevice) and dual.num_arms == 2 and not dual.has_base
    assert dual.gripper_steps == [50.0, 50.0]  # RMB's step for the 0..255 Robotiq
    low, high = PANDA.arms[0].gripper.command_range
    assert make_device("keyboard", PANDA).gripper_steps == [pytest.approx(50 / 255 * (high - low))]


def test_replay_needs_a_log(recorded_episode):
    assert isinstance(make_device("replay", UR5E, replay_log=recorded_episode), ReplayDevice)
    with pytest.raises(ValueError, match="needs --replay-log"):
        make_device("replay", UR5E)


def test_rmbs_spacemouse_yaml_gives_one_path_per_arm(tmp_path):
    config = tmp_path / "SpaceMouseDual.yaml"
    config.write_text(
        "1: {device_params: {path: /dev/hidraw4}}\n0: {device_params: {path: /dev/hidraw3}}\n"
    )
    assert spacemouse_paths(config) == ("/dev/hidraw3", "/dev/hidraw4")
    device = make_device("spacemouse", UR5E_DUAL, config=config)  # not opened until connect()
    assert device.name == "spacemouse" and device.config.paths == ("/dev/hidraw3", "/dev/hidraw4")
    config.write_text("0: {device_params: {}}\n")
    with pytest.raises(ValueError, match=r"arm 0 has no device_params\.path"):
        spacemouse_paths(config)


def test_unknown_devices_and_gello_without_its_config_are_refused():
    with pytest.raises(ValueError, match="unknown input device 'vive'"):
        make_device("vive", UR5E)
    with pytest.raises(ValueError, match="gello needs --input-device-config"):
        make_device("gello", UR5E)

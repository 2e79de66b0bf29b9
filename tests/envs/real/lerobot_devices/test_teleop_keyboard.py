"""``rmb_keyboard``: RMB's key bindings as end-effector velocity actions, and what it does
without a terminal or a display. (The terminal itself is driven through a pty in
``test_keyboard_cli.py``, with LeRobot's unmodified CLIs.)"""

from __future__ import annotations

import pytest
from lerobot.teleoperators import TeleoperatorConfig, make_teleoperator_from_config

import lerobot_env_rmb  # noqa: F401  (registers the types, as LeRobot's plugin loader does)
from rmb_lerobot.envs.real.lerobot_devices import RmbKeyboard, RmbKeyboardConfig, RmbUR5e
from rmb_lerobot.envs.real.lerobot_devices.config import RmbUR5eConfig
from rmb_lerobot.envs.real.lerobot_devices.features import EE_VELOCITY_KEYS
from rmb_lerobot.envs.teleop import keys as key_sources

FPS = 30.0


def keyboard(tmp_path, **options) -> RmbKeyboard:
    return RmbKeyboard(RmbKeyboardConfig(calibration_dir=tmp_path, fps=FPS, **options))


def test_registered_and_emitting_the_ee_robots_action_keys(tmp_path):
    assert "rmb_keyboard" in TeleoperatorConfig.get_known_choices()
    teleop = make_teleoperator_from_config(RmbKeyboardConfig(calibration_dir=tmp_path))
    assert type(teleop) is RmbKeyboard
    robot = RmbUR5e(RmbUR5eConfig(calibration_dir=tmp_path, action_space="ee_velocity"))
    # lerobot-record stores the teleoperator's action under the robot's action names.
    assert list(teleop.action_features) == list(robot.action_features)
    assert list(teleop.action_for([])) == list(robot.action_features)


def test_one_press_is_one_rmb_step_in_one_loop_period(tmp_path):
    teleop = keyboard(tmp_path)
    idle = teleop.action_for([])
    assert all(idle[k] == 0.0 for k in EE_VELOCITY_KEYS) and idle["gripper.pos"] == 0.0
    # W: +1 cm in x within one period of the loop -> 0.01 * fps m/s.
    assert teleop.action_for(["w"])["ee_x.vel"] == pytest.approx(0.01 * FPS)
    both = teleop.action_for(["w", "w", "e", "u"])  # presses of one step add up
    assert both["ee_x.vel"] == pytest.approx(0.02 * FPS)
    assert both["ee_z.vel"] == pytest.approx(-0.01 * FPS)
    assert both["ee_yaw.vel"] == pytest.approx(0.1 * FPS)  # RMB's yaw step is 2 x 0.05 rad
    assert teleop.action_for(["j"])["ee_roll.vel"] == pytest.approx(-0.05 * FPS)
    # The next step is still again: a terminal reports presses, not held keys.
    assert teleop.action_for([])["ee_x.vel"] == 0.0


def test_the_gripper_command_is_tracked_and_kept_in_range(tmp_path):
    teleop = keyboard(tmp_path)
    assert teleop.action_for(["z", "z"])["gripper.pos"] == pytest.approx(100.0)
    assert teleop.action_for([])["gripper.pos"] == pytest.approx(100.0)  # held
    assert teleop.action_for(["z"] * 9)["gripper.pos"] == pytest.approx(255.0)
    assert teleop.action_for(["x"] * 20)["gripper.pos"] == pytest.approx(0.0)
    assert keyboard(tmp_path, gripper_start=400.0).action_for([])["gripper.pos"] == 255.0


def test_dual_arms_switch_with_tab(tmp_path):
    teleop = keyboard(tmp_path, robot="rmb_ur5e_dual")
    first = teleop.action_for(["w"])
    assert first["left_ee_x.vel"] > 0 and first["right_ee_x.vel"] == 0.0
    second = teleop.action_for(["tab", "a"])
    assert second["right_ee_y.vel"] > 0 and second["left_ee_y.vel"] == 0.0
    assert len(first) == 2 * (len(EE_VELOCITY_KEYS) + 1)


def test_without_terminal_or_display_connect_says_what_is_missing(tmp_path, monkeypatch):
    monkeypatch.setattr(key_sources, "stdin_is_terminal", lambda: False)
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    teleop = keyboard(tmp_path)
    with pytest.raises(ConnectionError, match="not a terminal and there is no display"):
        teleop.connect()
    assert not teleop.is_connected
    with pytest.raises(ValueError, match="keys must be one of"):
        RmbKeyboardConfig(keys="gamepad")
    with pytest.raises(ValueError, match="fps must be > 0"):
        RmbKeyboardConfig(fps=0)

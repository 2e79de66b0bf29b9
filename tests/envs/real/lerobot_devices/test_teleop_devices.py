"""The LeRobot teleoperators ``rmb_gello`` and ``rmb_spacemouse`` in process, on the UR5e twin.

Built through LeRobot's own factory (``make_teleoperator_from_config``), as
``lerobot-teleoperate`` builds them; the GELLO is a fake servo chain on a pty read by the
real dynamixel-sdk, the SpaceMouse a fake ``pyspacemouse`` module. Each loop step is what the
stock loop does: ``robot.get_observation()``, ``teleop.get_action()``,
``robot.send_action(action)``.
"""

from __future__ import annotations

import math
import sys
import time

import numpy as np
import pytest
from lerobot.robots import make_robot_from_config
from lerobot.teleoperators import TeleoperatorConfig, make_teleoperator_from_config

import lerobot_env_rmb  # noqa: F401  (registers the types, as LeRobot's plugin loader does)
from rmb_lerobot.envs.real.lerobot_devices import RmbUR5eConfig
from rmb_lerobot.envs.real.lerobot_devices.config_teleop_devices import (
    RmbGelloConfig,
    RmbSpacemouseConfig,
)
from rmb_lerobot.envs.real.lerobot_devices.features import action_keys, home_vector
from rmb_lerobot.envs.real.lerobot_devices.teleop_devices import RmbGello, RmbSpacemouse
from rmb_lerobot.envs.teleop.fakes.dynamixel import FakeDynamixelChain
from rmb_lerobot.envs.teleop.fakes.spacemouse import FakePySpaceMouse, FakeState

HOME = home_vector("rmb_ur5e")[:6]
OFFSETS = [math.pi, 1.5 * math.pi, math.pi, -0.5 * math.pi, math.pi, 2 * math.pi]
SIGNS = [1, 1, -1, 1, 1, 1]
GRIPPER = [7, 202.04, 160.24]
PERIOD_S = 1 / 30
# These tests are about the teleoperators: a loop step stalled by a loaded machine must not
# trip the safety layer's watchdog (its own tests cover it).
WATCHDOG_S = 5.0


def gello_raw(q: np.ndarray, gripper_deg: float = GRIPPER[1]) -> dict[int, int]:
    """Servo counts for arm joints ``q`` (rad) and the gripper servo at ``gripper_deg``."""
    rad = np.asarray(q) * SIGNS + OFFSETS
    raw = {i + 1: round(r / math.pi * 2048) for i, r in enumerate(rad)}
    return raw | {GRIPPER[0]: round(math.radians(gripper_deg) / math.pi * 2048)}


def gello_config(chain: FakeDynamixelChain, tmp_path) -> RmbGelloConfig:
    return RmbGelloConfig(
        port=chain.path, joint_offsets=OFFSETS, joint_signs=SIGNS, gripper=GRIPPER,
        calibration_dir=tmp_path,
    )  # fmt: skip


def step(robot, teleop) -> dict:
    robot.get_observation()
    action = teleop.get_action()
    robot.send_action(action)
    time.sleep(PERIOD_S)
    return action


def measured(robot) -> np.ndarray:
    obs = robot.get_observation()
    return np.array([obs[k] for k in action_keys("rmb_ur5e")])


def test_types_are_found_by_lerobots_lookup_and_emit_the_robots_action_keys(tmp_path):
    known = TeleoperatorConfig.get_known_choices()
    assert known["rmb_gello"] is RmbGelloConfig and known["rmb_spacemouse"] is RmbSpacemouseConfig
    gello = make_teleoperator_from_config(
        RmbGelloConfig(port="/dev/ttyUSB0", joint_offsets=OFFSETS, calibration_dir=tmp_path)
    )
    mouse = make_teleoperator_from_config(RmbSpacemouseConfig(calibration_dir=tmp_path))
    assert isinstance(gello, RmbGello) and isinstance(mouse, RmbSpacemouse)
    # What lerobot-record needs: the teleop emits every action key of the robot it drives.
    joint_robot = make_robot_from_config(RmbUR5eConfig(calibration_dir=tmp_path))
    ee_robot = make_robot_from_config(
        RmbUR5eConfig(calibration_dir=tmp_path, action_space="ee_velocity")
    )
    assert list(gello.action_features) == list(joint_robot.action_features)
    assert list(mouse.action_features) == list(ee_robot.action_features)
    assert list(mouse.action_features) == list(action_keys("rmb_ur5e", "ee_velocity"))
    xarm = RmbGelloConfig(robot="rmb_xarm7", port="/dev/ttyUSB0", joint_offsets=[0.0] * 7)
    assert list(RmbGello(xarm).action_features) == list(action_keys("rmb_xarm7"))


def test_configs_refuse_what_cannot_work():
    with pytest.raises(ValueError, match="serial port"):
        RmbGelloConfig(joint_offsets=OFFSETS)
    with pytest.raises(ValueError, match="joint_offsets"):
        RmbGelloConfig(port="/dev/ttyUSB0")
    with pytest.raises(ValueError, match="one SpaceMouse each"):
        RmbSpacemouseConfig(robot="rmb_ur5e_dual")  # two arms, no device paths
    with pytest.raises(ValueError, match=r"gripper is \[servo ID, open deg, closed deg\]"):
        RmbGelloConfig(port="/dev/ttyUSB0", joint_offsets=OFFSETS, gripper=[7, 200.0])
    with pytest.raises(ValueError, match="start_joints has 2 values"):
        RmbGello(RmbGelloConfig(port="/dev/ttyUSB0", joint_offsets=OFFSETS, start_joints=[0, 0]))


def test_gello_holds_the_robot_until_ready_then_blends_into_the_leader(tmp_path):
    far = HOME + np.radians([40, 0, 0, 0, 0, 0])  # 40 deg off on the base joint
    with FakeDynamixelChain(gello_raw(far)) as chain:
        teleop = make_teleoperator_from_config(gello_config(chain, tmp_path))
        robot = make_robot_from_config(
            RmbUR5eConfig(calibration_dir=tmp_path, watchdog_timeout_s=WATCHDOG_S)
        )
        teleop.connect()
        robot.connect()
        try:
            held = [step(robot, teleop) for _ in range(5)]
            assert not teleop.ready
            for action in held:  # the robot is held where it started
                np.testing.assert_allclose(list(action.values()), home_vector("rmb_ur5e"))
            leader = HOME + np.radians([12, -8, 6, 10, -5, 15])
            chain.set_positions(gello_raw(leader, gripper_deg=181.14))  # gripper half closed
            actions = [step(robot, teleop) for _ in range(60)]
            assert teleop.ready
            joints = np.array([list(a.values())[:6] for a in actions])
            # The blend starts at the robot's pose and approaches the leader without overshoot.
            np.testing.assert_allclose(joints[0], HOME, atol=1e-9)
            gaps = np.max(np.abs(joints - joints[-1]), axis=1)
            assert np.all(np.diff(gaps) <= 1e-9) and gaps[50] < 1e-9
            np.testing.assert_allclose(joints[-1], leader, atol=2e-3)  # to one servo count
            assert actions[-1]["gripper.pos"] == pytest.approx(127.5, abs=1.0)
            time.sleep(0.5)
            np.testing.assert_allclose(measured(robot)[:6], leader, atol=0.02)
        finally:
            robot.disconnect()
            teleop.disconnect()
    assert chain.received[0x82] >= 60


@pytest.fixture
def fake_mouse(monkeypatch):
    def install(states) -> FakePySpaceMouse:
        fake = FakePySpaceMouse({"/dev/hidraw0": states})
        monkeypatch.setitem(sys.modules, "pyspacemouse", fake)
        return fake

    return install


def test_spacemouse_twist_is_rmbs_delta_over_the_command_duration(fake_mouse, tmp_path):
    fake_mouse([FakeState(x=1.0, yaw=-0.5, buttons=[1, 0])])
    config = RmbSpacemouseConfig(calibration_dir=tmp_path, command_duration_s=0.02)
    teleop = make_teleoperator_from_config(config)
    teleop.connect()
    actions = [teleop.get_action() for _ in range(60)]
    teleop.disconnect()
    twist = [actions[0][k] for k in action_keys("rmb_ur5e", "ee_velocity")[:6]]
    # 1 cm along +y and 2 x 5 mrad x 0.5 of yaw per step, over 0.02 s.
    np.testing.assert_allclose(twist, [0, 0.5, 0, 0, 0, 0.25], atol=1e-12)
    gripper = [a["gripper.pos"] for a in actions]
    assert gripper[:3] == [5.0, 10.0, 15.0] and gripper[-1] == 255.0  # clipped at closed


def test_spacemouse_moves_the_twins_end_effector_through_the_ee_option(fake_mouse, tmp_path):
    pushes = 10
    fake_mouse([FakeState(x=1.0)] * (10 * pushes) + [FakeState()])  # 10 reads per step
    teleop = make_teleoperator_from_config(
        RmbSpacemouseConfig(calibration_dir=tmp_path, pos_scale=2e-3, command_duration_s=PERIOD_S)
    )
    robot = make_robot_from_config(
        RmbUR5eConfig(
            calibration_dir=tmp_path,
            action_space="ee_velocity",
            command_duration_s=PERIOD_S,
            watchdog_timeout_s=WATCHDOG_S,
        )
    )
    teleop.connect()
    robot.connect()
    try:
        kinematics = robot.ee_target.kinematics
        start = kinematics.fk(measured(robot)[:6])
        for _ in range(pushes + 5):
            action = step(robot, teleop)
        assert action["ee_y.vel"] == 0.0  # the script ran out: the cap is released
        target = robot.ee_target.pose
        np.testing.assert_allclose(target[:3] - start[:3], [0, pushes * 2e-3, 0], atol=1e-4)
        time.sleep(0.5)
        reached = kinematics.fk(measured(robot)[:6])
        np.testing.assert_allclose(reached[:3] - start[:3], [0, pushes * 2e-3, 0], atol=3e-3)
    finally:
        robot.disconnect()
        teleop.disconnect()

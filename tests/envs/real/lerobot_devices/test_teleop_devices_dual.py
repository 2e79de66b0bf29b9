"""``rmb_spacemouse`` / ``rmb_gello`` on the dual UR5e (one device per arm, the robot's
``left_`` / ``right_`` keys), the SpaceMouse's gripper start, and the rate check that names
``--fps`` when the loop polls a teleoperator at another period than it assumes."""

from __future__ import annotations

import logging
import math
import sys
import time

import numpy as np
import pytest
from lerobot.robots import make_robot_from_config
from lerobot.teleoperators import make_teleoperator_from_config

import lerobot_env_rmb  # noqa: F401  (registers the types, as LeRobot's plugin loader does)
from rmb_lerobot.envs.real.lerobot_devices import RmbUR5eDualConfig
from rmb_lerobot.envs.real.lerobot_devices.config import RmbArmConfig
from rmb_lerobot.envs.real.lerobot_devices.config_teleop_devices import (
    RmbGelloConfig,
    RmbSpacemouseConfig,
)
from rmb_lerobot.envs.real.lerobot_devices.features import action_keys, home_vector
from rmb_lerobot.envs.real.lerobot_devices.teleop_base import RateCheck
from rmb_lerobot.envs.real.lerobot_devices.teleop_devices import RmbGello, RmbSpacemouse
from rmb_lerobot.envs.teleop.fakes.spacemouse import FakePySpaceMouse, FakeState

HOME = home_vector("rmb_ur5e")[:6]
OFFSETS = [math.pi, 1.5 * math.pi, math.pi, -0.5 * math.pi, math.pi, 2 * math.pi]
SIGNS = [1, 1, -1, 1, 1, 1]
GRIPPER = [7, 202.04, 160.24]
PERIOD_S = 1 / 30
WATCHDOG_S = 5.0  # a stalled step on a loaded machine must not trip the watchdog here


def ee_dual(tmp_path) -> RmbUR5eDualConfig:
    arm = {"action_space": "ee_velocity", "command_duration_s": PERIOD_S}
    return RmbUR5eDualConfig(
        calibration_dir=tmp_path,
        left_arm_config=RmbArmConfig(**arm, watchdog_timeout_s=WATCHDOG_S),
        right_arm_config=RmbArmConfig(**arm, watchdog_timeout_s=WATCHDOG_S),
    )


@pytest.fixture
def two_mice(monkeypatch):
    """Left mouse pushed right (HID +x), right mouse pushed up (HID -z), 10 steps each."""
    steps = 10
    fake = FakePySpaceMouse(
        {
            "/dev/hidraw3": [FakeState(x=1.0)] * (10 * steps) + [FakeState()],
            "/dev/hidraw4": [FakeState(z=-1.0, buttons=[1, 0])] * (10 * steps) + [FakeState()],
        }
    )
    monkeypatch.setitem(sys.modules, "pyspacemouse", fake)
    return fake


def test_two_spacemice_emit_the_dual_robots_prefixed_ee_keys(two_mice, tmp_path):
    config = RmbSpacemouseConfig(
        robot="rmb_ur5e_dual", paths=["/dev/hidraw3", "/dev/hidraw4"], calibration_dir=tmp_path
    )
    teleop = make_teleoperator_from_config(config)
    assert isinstance(teleop, RmbSpacemouse)
    robot = make_robot_from_config(ee_dual(tmp_path))
    assert list(teleop.action_features) == list(robot.action_features)
    assert list(teleop.action_features) == list(action_keys("rmb_ur5e_dual", "ee_velocity"))
    teleop.connect()
    try:
        action = teleop.get_action()
    finally:
        teleop.disconnect()
    assert [d.path for d in two_mice.opened] == ["/dev/hidraw3", "/dev/hidraw4"]
    # RMB's 1 cm per step at full deflection over the 1/30 s command duration.
    assert action["left_ee_y.vel"] == pytest.approx(0.01 * 30)
    assert action["left_ee_z.vel"] == 0.0 and action["right_ee_y.vel"] == 0.0
    assert action["right_ee_z.vel"] == pytest.approx(0.01 * 30)
    assert action["left_gripper.pos"] == 0.0 and action["right_gripper.pos"] == 5.0


def test_two_spacemice_move_both_arms_of_the_dual_twin(two_mice, tmp_path):
    yaml = tmp_path / "SpaceMouseDual.yaml"
    yaml.write_text(
        "0:\n  device_params:\n    path: /dev/hidraw3\n"
        "1:\n  device_params:\n    path: /dev/hidraw4\n"
    )
    teleop = make_teleoperator_from_config(
        RmbSpacemouseConfig(
            robot="rmb_ur5e_dual",
            rmb_config=str(yaml),
            pos_scale=2e-3,
            command_duration_s=PERIOD_S,
            calibration_dir=tmp_path,
        )
    )
    robot = make_robot_from_config(ee_dual(tmp_path))
    teleop.connect()
    robot.connect()
    try:
        arms = (robot.left_arm, robot.right_arm)
        starts = [arm.ee_target.kinematics.fk(arm.real.read_joints()[:-1]) for arm in arms]
        for _ in range(15):
            robot.get_observation()
            robot.send_action(teleop.get_action())
            time.sleep(PERIOD_S)
        targets = [arm.ee_target.pose for arm in arms]
    finally:
        robot.disconnect()
        teleop.disconnect()
    # Twists are in each arm's base frame: the left target moved +y, the right one +z, 2 cm.
    np.testing.assert_allclose(targets[0][:3] - starts[0][:3], [0, 0.02, 0], atol=1e-4)
    np.testing.assert_allclose(targets[1][:3] - starts[1][:3], [0, 0, 0.02], atol=1e-4)


def test_spacemouse_configs_for_the_dual_robot_need_a_device_per_arm(tmp_path):
    with pytest.raises(ValueError, match=r"one SpaceMouse each: give --teleop\.paths"):
        RmbSpacemouseConfig(robot="rmb_ur5e_dual")
    with pytest.raises(ValueError, match="has 2 arm"):
        RmbSpacemouseConfig(robot="rmb_ur5e_dual", paths=["/dev/hidraw3"])
    with pytest.raises(ValueError, match="robot must be one of"):
        RmbSpacemouseConfig(robot="rmb_g1")
    one = tmp_path / "SpaceMouse.yaml"
    one.write_text("0:\n  device_params:\n    path: /dev/hidraw3\n")
    with pytest.raises(ValueError, match="lists 1 device"):
        RmbSpacemouse(RmbSpacemouseConfig(robot="rmb_ur5e_dual", rmb_config=str(one)))


def test_spacemouse_gripper_starts_at_gripper_start(monkeypatch, tmp_path):
    monkeypatch.setitem(sys.modules, "pyspacemouse", FakePySpaceMouse({"/dev/hidraw0": []}))
    teleop = RmbSpacemouse(RmbSpacemouseConfig(gripper_start=120.0, calibration_dir=tmp_path))
    teleop.connect()
    assert teleop.get_action()["gripper.pos"] == 120.0
    teleop.disconnect()
    clipped = RmbSpacemouse(RmbSpacemouseConfig(gripper_start=999.0, calibration_dir=tmp_path))
    clipped.connect()
    assert clipped.get_action()["gripper.pos"] == 255.0  # the record's closed end
    clipped.disconnect()


# ---------------------------------------------------------------------------- GELLO pair
pytest.importorskip("dynamixel_sdk", reason="extra gello (in `make setup`'s EXTRAS)")

from rmb_lerobot.envs.teleop.fakes.dynamixel import FakeDynamixelChain  # noqa: E402


def gello_raw(q: np.ndarray, gripper_deg: float = GRIPPER[1]) -> dict[int, int]:
    rad = np.asarray(q) * SIGNS + OFFSETS
    raw = {i + 1: round(r / math.pi * 2048) for i, r in enumerate(rad)}
    return raw | {GRIPPER[0]: round(math.radians(gripper_deg) / math.pi * 2048)}


def dual_yaml(tmp_path, left: str, right: str):
    arm = (
        "  config:\n    joint_ids: [1, 2, 3, 4, 5, 6]\n"
        f"    joint_signs: {SIGNS}\n    joint_offsets: {OFFSETS}\n"
        f"    gripper_config: {GRIPPER}\n"
    )
    path = tmp_path / "Gello_RealUR5eDual.yaml"
    path.write_text(f"0:\n  port: {left}\n{arm}1:\n  port: {right}\n{arm}")
    return str(path)


def test_a_gello_pair_holds_both_arms_until_both_are_ready_then_drives_each(tmp_path):
    left_q = HOME + np.radians([10, -5, 5, 0, 0, 10])
    right_far = HOME + np.radians([0, 0, 0, 40, 0, 0])
    right_q = HOME + np.radians([-10, 5, 0, 5, 5, 0])
    with (
        FakeDynamixelChain(gello_raw(left_q, gripper_deg=160.24)) as left,
        FakeDynamixelChain(gello_raw(right_far)) as right,
    ):
        config = RmbGelloConfig(
            robot="rmb_ur5e_dual",
            rmb_config=dual_yaml(tmp_path, left.path, right.path),
            calibration_dir=tmp_path,
        )
        teleop = make_teleoperator_from_config(config)
        assert isinstance(teleop, RmbGello)
        dual = make_robot_from_config(RmbUR5eDualConfig(calibration_dir=tmp_path))
        assert list(teleop.action_features) == list(dual.action_features)
        teleop.connect()
        try:
            held = [teleop.get_action() for _ in range(3)]
            assert not teleop.ready  # the right GELLO is 40 deg off: both arms hold
            for action in held:
                np.testing.assert_allclose(list(action.values()), home_vector("rmb_ur5e_dual"))
            right.set_positions(gello_raw(right_q))
            actions = [teleop.get_action() for _ in range(60)]
        finally:
            teleop.disconnect()
    assert teleop.ready
    keys = action_keys("rmb_ur5e_dual")
    last = np.array([actions[-1][k] for k in keys])
    np.testing.assert_allclose(last[:6], left_q, atol=2e-3)
    np.testing.assert_allclose(last[7:13], right_q, atol=2e-3)
    assert last[6] == pytest.approx(255.0, abs=1.0) and last[13] == pytest.approx(0.0, abs=1.0)
    # The joints blend from where the arms stand (the grippers follow their GELLOs at once).
    first = np.array([actions[0][k] for k in keys])
    home = home_vector("rmb_ur5e_dual")
    np.testing.assert_allclose(np.delete(first, [6, 13]), np.delete(home, [6, 13]), atol=1e-9)


def test_gello_configs_for_the_dual_robot_need_rmbs_two_arm_yaml(tmp_path):
    with pytest.raises(ValueError, match=r"Gello_RealUR5eDual\.yaml"):
        RmbGelloConfig(robot="rmb_ur5e_dual", port="/dev/ttyUSB0", joint_offsets=OFFSETS)
    single = tmp_path / "one.yaml"
    single.write_text(
        "0:\n  port: /dev/ttyUSB0\n  config:\n    joint_ids: [1, 2, 3, 4, 5, 6]\n"
        f"    joint_signs: {SIGNS}\n    joint_offsets: {OFFSETS}\n"
    )
    with pytest.raises(ValueError, match="has 1 arm"):
        RmbGello(RmbGelloConfig(robot="rmb_ur5e_dual", rmb_config=str(single)))
    with pytest.raises(ValueError, match="start_joints has 6 values, rmb_ur5e_dual has 12"):
        RmbGello(
            RmbGelloConfig(
                robot="rmb_ur5e_dual",
                rmb_config=dual_yaml(tmp_path, "/dev/ttyUSB0", "/dev/ttyUSB1"),
                start_joints=list(HOME),
            )
        )


# ---------------------------------------------------------------------------- rate check
class FakeClock:
    def __init__(self, period_s: float):
        self.now, self.period_s = 0.0, period_s

    def __call__(self) -> float:
        self.now += self.period_s
        return self.now


@pytest.mark.parametrize("loop_hz", [15.0, 60.0])
def test_a_loop_at_another_rate_than_assumed_is_warned_about_once(loop_hz, caplog):
    check = RateCheck(
        "rmb_spacemouse", 1 / 30, "set --fps", window=30, clock=FakeClock(1 / loop_hz)
    )
    with caplog.at_level(logging.WARNING):
        messages = [check.tick() for _ in range(100)]
    [warning] = [m for m in messages if m is not None]
    assert f"called every {1e3 / loop_hz:.0f} ms" in warning and "assume 33 ms" in warning
    assert f"{loop_hz / 30:.2f} x RMB's step" in warning and warning.endswith("set --fps")
    assert caplog.text.count("rmb_spacemouse: called every") == 1


def test_the_assumed_rate_and_a_pause_now_and_then_pass(caplog):
    clock = FakeClock(1 / 30)
    check = RateCheck("rmb_keyboard", 1 / 30, "set --fps", window=30, clock=clock)
    with caplog.at_level(logging.WARNING):
        for i in range(200):
            if i % 40 == 0:
                clock.now += 2.0  # lerobot-record saving an episode
            assert check.tick() is None
    assert caplog.text == ""

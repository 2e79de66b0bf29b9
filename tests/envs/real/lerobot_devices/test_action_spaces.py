"""The real-arm robots' two action spaces against the UR5e twin, in process.

``joint`` (default): a stream whose first action is far from where the arm stands is reached
by the safety layer's reset move first, so a script or a replayed episode that starts at home
drives an arm standing elsewhere (``ramp_first_action``). ``ee_velocity``: a twist moves the
robot's own end-effector target, started at the measured pose, and the arm follows it through
the same safety layer.
"""

from __future__ import annotations

import logging
import time

import numpy as np
import pytest

from rmb_lerobot.envs.real.errors import JumpTooLarge, NonFiniteCommand
from rmb_lerobot.envs.real.lerobot_devices import (
    RmbScripted,
    RmbScriptedConfig,
    RmbUR5e,
    RmbUR5eConfig,
    RmbUR5eDual,
    RmbUR5eDualConfig,
)
from rmb_lerobot.envs.real.lerobot_devices.config import RmbArmConfig
from rmb_lerobot.envs.real.lerobot_devices.features import EE_VELOCITY_KEYS
from rmb_lerobot.envs.robots import UR5E

JOINT_KEYS = [f"{j}.pos" for j in UR5E.arms[0].joints] + ["gripper.pos"]
EE_KEYS = [*EE_VELOCITY_KEYS, "gripper.pos"]
HOME = np.asarray(UR5E.arms[0].home, dtype=np.float64)
# Away from home: the wrist turned 100° (beyond the 90° jump rule), the base 30°.
AWAY = HOME + np.deg2rad([30.0, 0.0, 0.0, 0.0, 0.0, 100.0])
DT = 1 / 30


def connected(tmp_path, **options) -> RmbUR5e:
    robot = RmbUR5e(RmbUR5eConfig(calibration_dir=tmp_path, **options))
    robot.connect()
    return robot


def put_twin_at(robot: RmbUR5e, q: np.ndarray) -> None:
    """Move the twin by itself (as a person jogging the arm would), not through the plugin."""
    sim = robot.real.twins[0].sim
    assert sim.move_to(q, 2.0)
    assert sim.wait(lambda: sim.at_rest() and np.allclose(sim.read().joint_pos, q, atol=2e-3), 15)


def measured_arm(robot) -> np.ndarray:
    return robot.real.read_joints()[:-1]


@pytest.fixture
def away(tmp_path):
    robot = connected(tmp_path)
    put_twin_at(robot, AWAY)
    yield robot
    if robot.is_connected:
        robot.disconnect()


def test_a_script_from_home_drives_an_arm_standing_elsewhere(away, tmp_path):
    script = RmbScripted(RmbScriptedConfig(calibration_dir=tmp_path, motion="hold"))
    script.connect()
    first = script.get_action()
    sent = away.send_action(first)
    # The first action went out as a reset move at RMB's reset speed (0.3 v_lim), then a step.
    v_reset = 0.3 * np.deg2rad(191.0)
    assert away.real.last_move_duration == pytest.approx(np.deg2rad(100.0) / v_reset, rel=0.05)
    assert list(sent) == JOINT_KEYS
    for _ in range(10):
        sent = away.send_action(script.get_action())
        time.sleep(DT)
    assert np.allclose(list(sent.values())[:-1], HOME, atol=1e-6)  # nothing clamped any more
    sim = away.real.twins[0].sim
    assert sim.wait(lambda: np.allclose(sim.read().joint_pos, HOME, atol=0.02), 15)
    script.disconnect()


def test_without_the_ramp_the_first_action_is_refused_as_a_jump(tmp_path):
    robot = connected(tmp_path, ramp_first_action=False)
    try:
        put_twin_at(robot, AWAY)
        with pytest.raises(JumpTooLarge, match="wrist_3_joint"):
            robot.send_action(dict(zip(JOINT_KEYS, [*HOME, 0.0], strict=True)))
        assert np.allclose(measured_arm(robot), AWAY, atol=2e-3)
    finally:
        robot.disconnect()


def test_a_nearby_first_action_is_sent_as_a_step(tmp_path):
    robot = connected(tmp_path)
    try:
        action = dict(zip(JOINT_KEYS, [*(HOME + 0.001), 0.0], strict=True))
        robot.send_action(action)
        assert robot.real.last_move_duration == 0.0  # no reset move
    finally:
        robot.disconnect()


@pytest.fixture
def ee_robot(tmp_path):
    robot = connected(tmp_path, action_space="ee_velocity")
    yield robot
    if robot.is_connected:
        robot.disconnect()


def test_ee_velocity_features(tmp_path):
    robot = RmbUR5e(RmbUR5eConfig(calibration_dir=tmp_path, action_space="ee_velocity"))
    assert list(robot.action_features) == EE_KEYS
    assert list(robot.observation_features) == JOINT_KEYS  # the observation is unchanged
    dual = RmbUR5eDual(
        RmbUR5eDualConfig(
            calibration_dir=tmp_path, right_arm_config=RmbArmConfig(action_space="ee_velocity")
        )
    )
    assert list(dual.action_features) == [f"left_{k}" for k in JOINT_KEYS] + [
        f"right_{k}" for k in EE_KEYS
    ]
    with pytest.raises(ValueError, match="action_space must be one of"):
        RmbUR5eConfig(action_space="cartesian")


@pytest.mark.parametrize("direction", [(1, 0, 0), (0, 0, -1)])
def test_a_twist_moves_the_tcp_that_way(ee_robot, direction):
    kinematics = ee_robot.ee_target.kinematics
    start = kinematics.fk(measured_arm(ee_robot))
    speed, steps = 0.1, 20
    twist = dict(zip(EE_KEYS, [*(speed * np.asarray(direction)), 0, 0, 0, 0.0], strict=True))
    for _ in range(steps):
        sent = ee_robot.send_action(twist)
        time.sleep(DT)
    assert list(sent) == EE_KEYS
    # What was sent realises the twist asked for (nothing clamped at this speed).
    assert [sent[k] for k in EE_VELOCITY_KEYS] == pytest.approx(
        [*(speed * np.asarray(direction)), 0, 0, 0], abs=1e-3
    )
    sim = ee_robot.real.twins[0].sim
    assert sim.wait(sim.at_rest, 15)
    end = kinematics.fk(measured_arm(ee_robot))
    moved = end[:3] - start[:3]
    expected = speed * steps * DT * np.asarray(direction)  # 6.7 cm
    assert moved == pytest.approx(expected, abs=0.01)
    assert float(np.dot(moved, direction)) > 0.8 * np.linalg.norm(expected)


def test_ee_mode_refuses_bad_actions_and_takes_joint_ones(ee_robot):
    with pytest.raises(KeyError, match=r"ee_yaw\.vel"):
        ee_robot.send_action({"ee_x.vel": 0.0})
    twist = dict.fromkeys(EE_KEYS, 0.0)
    ee_robot.send_action(twist)
    with pytest.raises(NonFiniteCommand, match=r"ee_y\.vel"):
        ee_robot.send_action({**twist, "ee_y.vel": float("nan")})
    assert not ee_robot.streaming  # the arm was stopped
    # lerobot-rollout returns the arm to its start with the observation's .pos keys.
    obs = ee_robot.get_observation()
    sent = ee_robot.send_action(obs)
    assert list(sent) == JOINT_KEYS
    assert [sent[k] for k in JOINT_KEYS[:-1]] == pytest.approx([obs[k] for k in JOINT_KEYS[:-1]])
    # The next twist starts from the measured pose again.
    ee_robot.send_action(twist)
    assert ee_robot.ee_target.pose[:3] == pytest.approx(
        ee_robot.ee_target.kinematics.fk(measured_arm(ee_robot))[:3], abs=0.01
    )


def test_dual_arms_ramp_together_to_a_first_action_from_home(tmp_path, caplog):
    dual = RmbUR5eDual(RmbUR5eDualConfig(calibration_dir=tmp_path))
    dual.connect()
    try:
        put_twin_at(dual.right_arm, AWAY)  # the left arm stands at home
        script = RmbScripted(
            RmbScriptedConfig(robot="rmb_ur5e_dual", motion="hold", calibration_dir=tmp_path)
        )
        script.connect()
        with caplog.at_level(logging.WARNING):
            dual.send_action(script.get_action())
        assert "reset speed" in caplog.text
        assert "resuming" not in caplog.text  # the waiting arm's watchdog did not trip
        assert dual.left_arm.real.last_move_duration == 0.0  # at home already: no reset move
        assert dual.right_arm.real.last_move_duration > 1.0
        for _ in range(5):
            sent = dual.send_action(script.get_action())
            time.sleep(DT)
        assert [sent[f"right_{k}"] for k in JOINT_KEYS[:-1]] == pytest.approx(HOME)
        script.disconnect()
    finally:
        dual.disconnect()

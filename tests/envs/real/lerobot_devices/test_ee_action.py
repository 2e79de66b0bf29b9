"""The end-effector target behind ``--robot.action_space=ee_velocity``: twist maths, IK
tracking, and what happens out of reach or when the arm drifts from its target.

No twin here: the arm's MuJoCo kinematics only (the robots' tests drive the twins)."""

from __future__ import annotations

import numpy as np
import pytest

from rmb_lerobot.envs.real.lerobot_devices.ee_action import (
    DRIFT_POSITION_M,
    EeTarget,
    apply_twist,
    build_arm_kinematics,
    pose_distance,
    pose_twist,
)
from rmb_lerobot.envs.robots import UR5E, XARM7


@pytest.fixture(scope="module")
def ur5e_kinematics():
    return build_arm_kinematics(UR5E)


def random_pose(rng: np.random.Generator) -> np.ndarray:
    quat = rng.normal(size=4)
    return np.concatenate([rng.uniform(-0.5, 0.5, 3), quat / np.linalg.norm(quat)])


@pytest.mark.parametrize("seed", range(5))
def test_pose_twist_inverts_apply_twist(seed):
    rng = np.random.default_rng(seed)
    pose = random_pose(rng)
    twist = np.concatenate([rng.uniform(-0.5, 0.5, 3), rng.uniform(-1.0, 1.0, 3)])
    moved = apply_twist(pose, twist, 1 / 30)
    assert np.allclose(pose_twist(pose, moved, 1 / 30), twist, atol=1e-9)
    dist, _ = pose_distance(pose, moved)
    assert dist == pytest.approx(np.linalg.norm(twist[:3]) / 30)
    # The turn is applied in the base frame: R(ω dt) @ R, RMB's teleop rule.
    yaw_only = apply_twist(pose, np.array([0, 0, 0, 0, 0, 3.0]), 0.1)
    assert np.allclose(yaw_only[:3], pose[:3])
    assert pose_distance(pose, yaw_only)[1] == pytest.approx(0.3)


def test_a_twist_moves_the_solved_pose_by_velocity_times_duration(ur5e_kinematics):
    target = EeTarget(ur5e_kinematics)
    q = np.asarray(UR5E.arms[0].home, dtype=np.float64)
    start = target.sync(q)
    dt = 1 / 30
    for _ in range(15):  # 15 steps of 0.3 m/s along +x: 0.15 m
        step = target.step(np.array([0.3, 0, 0, 0, 0, 0]), dt, q)
        assert step.reached and not step.resynced
        q = step.joint_pos  # the arm follows perfectly
    reached = ur5e_kinematics.fk(q)
    assert reached[:3] - start[:3] == pytest.approx([0.15, 0.0, 0.0], abs=1e-3)
    assert pose_distance(reached, start)[1] < 1e-2  # orientation held
    # A zero twist holds the joints.
    assert np.allclose(target.step(np.zeros(6), dt, q).joint_pos, q, atol=1e-6)


def test_out_of_reach_the_target_stops_at_the_arm_and_comes_straight_back():
    kinematics = build_arm_kinematics(XARM7)
    target = EeTarget(kinematics)
    q = np.asarray(XARM7.arms[0].home, dtype=np.float64)
    target.sync(q)
    outward = np.array([1.0, 0, 0, 0, 0, 0])
    for _ in range(60):  # 2 m along +x: far beyond an xArm7's reach
        step = target.step(outward, 1 / 30, q)
        q = step.joint_pos
    assert not step.reached
    # The target never wound up beyond what the joints reach...
    assert pose_distance(step.target_pose, kinematics.fk(q))[0] < 1e-6
    # ...so reversing moves the arm back at once.
    back = target.step(-outward, 1 / 30, q)
    assert kinematics.fk(back.joint_pos)[0] < kinematics.fk(q)[0] - 0.01


def test_target_resyncs_when_the_arm_is_elsewhere_or_clipped(ur5e_kinematics):
    target = EeTarget(ur5e_kinematics)
    home = np.asarray(UR5E.arms[0].home, dtype=np.float64)
    target.sync(home)
    step = target.step(np.zeros(6), 1 / 30, home)
    assert step.resynced == ""
    # The arm was pushed away (a protective stop, a collision): steer from where it stands.
    pushed = home + np.array([0.3, 0, 0, 0, 0, 0])
    assert pose_distance(ur5e_kinematics.fk(pushed), step.target_pose)[0] > DRIFT_POSITION_M
    step = target.step(np.zeros(6), 1 / 30, pushed)
    assert "from its target" in step.resynced
    assert np.allclose(step.joint_pos, pushed, atol=1e-3)
    # The safety layer clamped the sent joints: the target follows what was sent.
    sent = pushed + 0.01
    target.sent(sent, clipped=True)
    assert np.allclose(target.pose, ur5e_kinematics.fk(sent))
    with pytest.raises(ValueError, match="6 finite"):
        target.step(np.array([np.nan, 0, 0, 0, 0, 0]), 1 / 30, pushed)

"""FK / IK of RMB's Sawyer on a private pybullet client, as the env and the experts use them.

Poses are RMB's ``(x, y, z, qw, qx, qy, qz)`` of ``right_l6`` in the robot's root frame.
"""

from __future__ import annotations

import numpy as np
import pybullet as p
import pytest
from scipy.spatial.transform import Rotation

from rmb_lerobot.envs.pybullet import sawyer
from rmb_lerobot.envs.pybullet.kinematics import (
    RMB_TACTO_RECORD_FRAME,
    SawyerKinematics,
    pos_rot_from_pose,
    quat_xyzw_to_wxyz,
    to_rmb_record_frame,
)

# RMB: robo_manip_baselines/envs/assets/tacto/robots/sawyer/sawyer_wsg50.urdf, <origin> of
# right_j0 .. right_j6 (lines 156, 223, 250, 277, 304, 344, 385); every axis is z.
RMB_ARM_ORIGINS = [
    ((0, 0, 0.08), (0, 0, 0)),
    ((0.081, 0.05, 0.237), (-1.5708, 1.5708, 0)),
    ((0, -0.14, 0.1425), (1.5708, 0, 0)),
    ((0, -0.042, 0.26), (-1.5708, 0, 0)),
    ((0, -0.125, -0.1265), (1.5708, 0, 0)),
    ((0, 0.031, 0.275), (-1.5708, 0, 0)),
    ((0, -0.11, 0.1053), (-1.5708, -0.17453, 3.1416)),
]
RMB_HOME = [0, -1.24, -0.58, 2.18, 0.27, 0.7, 1]  # RMB: envs/tacto/TactoSawyerGraspEnv.py:16-28


def transform(xyz, rpy=(0, 0, 0)) -> np.ndarray:
    """4x4 transform of a URDF <origin> (rpy = fixed-axis x, y, z)."""
    out = np.eye(4)
    out[:3, :3] = Rotation.from_euler("xyz", rpy).as_matrix()
    out[:3, 3] = xyz
    return out


def chain_to_eef(q) -> np.ndarray:
    """right_l6 in the root frame, composed joint by joint."""
    pose = np.eye(4)
    for (xyz, rpy), angle in zip(RMB_ARM_ORIGINS, q, strict=True):
        pose = pose @ transform(xyz, rpy) @ transform((0, 0, 0), (0, 0, angle))
    return pose


def as_matrix(pose) -> np.ndarray:
    pos, rot = pos_rot_from_pose(pose)
    out = np.eye(4)
    out[:3, :3], out[:3, 3] = rot, pos
    return out


def rotation_angle(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.linalg.norm(Rotation.from_matrix(a @ b.T).as_rotvec()))


@pytest.fixture(scope="module")
def kin():
    with SawyerKinematics() as kinematics:
        yield kinematics


def test_fk_at_home_matches_rmbs_joint_chain(kin):
    pose = kin.fk(RMB_HOME)
    assert pose.shape == (7,)
    assert pose[3] >= 0  # w first, RMB's order
    np.testing.assert_allclose(as_matrix(pose), chain_to_eef(RMB_HOME), atol=1e-6)


def test_fk_ignores_the_gripper_value_rmb_appends(kin):
    np.testing.assert_array_equal(kin.fk([*RMB_HOME, 0.02]), kin.fk(RMB_HOME))
    with pytest.raises(ValueError, match="at least 7"):
        kin.fk(RMB_HOME[:6])


def test_fk_agrees_with_a_simulated_robot_through_world_to_root(kin):
    client = p.connect(p.DIRECT)
    try:
        robot = sawyer.load_sawyer_wsg50(client)
        q = np.array([0.3, -0.9, 0.4, 1.5, -0.6, 0.9, -1.2])
        sawyer.reset_joints(client, robot, q, 0.02)
        state = p.getLinkState(
            robot.body_id, robot.eef_link, computeForwardKinematics=True, physicsClientId=client
        )
        rot = np.array(p.getMatrixFromQuaternion(state[5])).reshape(3, 3)
        from_sim = kin.world_to_root(state[4], rot)
        np.testing.assert_allclose(from_sim[:3], kin.fk(q)[:3], atol=1e-6)
        # pybullet's (x, y, z, w) becomes RMB's (w, x, y, z) (same rotation up to sign).
        quat = quat_xyzw_to_wxyz(state[5])
        assert abs(quat @ kin.fk(q)[3:]) == pytest.approx(1.0, abs=1e-6)
        # And back: root_to_world gives the simulated link frame.
        pos, rot_back = kin.root_to_world(kin.fk(q))
        np.testing.assert_allclose(pos, state[4], atol=1e-6)
        np.testing.assert_allclose(rot_back, rot, atol=1e-6)
    finally:
        p.disconnect(client)


def test_jacobian_is_the_derivative_of_fk(kin):
    q = np.array([0.3, -0.9, 0.4, 1.5, -0.6, 0.9, -1.2])
    eps = 1e-4  # pybullet's link poses are float32-precise: a larger step than usual
    numeric = np.zeros((6, 7))
    for i in range(7):
        step = np.zeros(7)
        step[i] = eps
        plus, minus = as_matrix(kin.fk(q + step)), as_matrix(kin.fk(q - step))
        numeric[:3, i] = (plus[:3, 3] - minus[:3, 3]) / (2 * eps)
        turn = Rotation.from_matrix(plus[:3, :3] @ minus[:3, :3].T).as_rotvec()
        numeric[3:, i] = turn / (2 * eps)
    np.testing.assert_allclose(kin.jacobian(q), numeric, atol=1e-3)


def test_ik_round_trips_random_configurations(kin):
    rng = np.random.default_rng(0)
    span = kin.upper - kin.lower
    for _ in range(8):
        q = kin.lower + span * rng.uniform(0.15, 0.85, size=7)
        target = kin.fk(q)
        q_init = np.clip(q + rng.uniform(-0.3, 0.3, size=7), kin.lower, kin.upper)
        solution = kin.ik(target, q_init)
        reached = kin.fk(solution)
        assert np.linalg.norm(reached[:3] - target[:3]) < 1e-3  # 1 mm
        angle = rotation_angle(as_matrix(reached)[:3, :3], as_matrix(target)[:3, :3])
        assert np.degrees(angle) < 1.0  # 1 deg


def test_ik_moves_the_gripper_down_from_home(kin):
    # What Insert's pre-motion does (OperationTactoSawyerInsert.py): eef straight down 0.08 m.
    target = kin.fk(RMB_HOME)
    target[2] -= 0.08
    result = kin.solve_ik(target, RMB_HOME)
    assert result.converged
    assert result.pos_error < 1e-4 and result.rot_error < 1e-3


def test_ik_of_an_unreachable_target_returns_finite_joints_within_limits(kin):
    far = np.array([3.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0])  # 3 m away: the arm reaches ~1.3 m
    result = kin.solve_ik(far, RMB_HOME)
    assert not result.converged
    assert np.all(np.isfinite(result.qpos))
    assert np.all(result.qpos >= kin.lower) and np.all(result.qpos <= kin.upper)
    # It stretches towards the target: the closest reachable point is ~1.7 m short of it.
    assert result.pos_error == pytest.approx(np.linalg.norm(far[:3] - kin.fk(result.qpos)[:3]))
    assert result.pos_error < np.linalg.norm(far[:3] - kin.fk(RMB_HOME)[:3])
    np.testing.assert_array_equal(kin.ik(far, RMB_HOME), result.qpos)


def test_rmb_record_frame_reproduces_rmbs_eef_pose(kin):
    # RMB's measured_eef_pose of the TACTO envs (TactoSawyerEnvBase.py:193-205,
    # common/body/ArmManager.py:68-72, common/utils/MathUtils.py:37-39): Pinocchio's chain with
    # its first joint moved by arm_root_pose = pybullet's getLinkState(right_l0)[0:2] at zero
    # joints (the link's centre of mass and an (x, y, z, w) quaternion), read as (w, x, y, z).
    client = p.connect(p.DIRECT)
    try:
        robot = sawyer.load_sawyer_wsg50(client)
        link_l0 = sawyer.link_indices_by_name(robot.body_id, client)["right_l0"]
        com_pos, quat_xyzw = p.getLinkState(robot.body_id, link_l0, physicsClientId=client)[:2]
    finally:
        p.disconnect(client)
    w, x, y, z = quat_xyzw  # RMB's misreading
    arm_root = transform(com_pos)
    arm_root[:3, :3] = Rotation.from_quat([x, y, z, w]).as_matrix()
    expected = arm_root @ chain_to_eef(RMB_HOME)  # oMi[7] with jointPlacements[1] premultiplied
    np.testing.assert_allclose(
        as_matrix(to_rmb_record_frame(kin.fk(RMB_HOME))), expected, atol=1e-6
    )
    np.testing.assert_allclose(RMB_TACTO_RECORD_FRAME[:3], com_pos, atol=1e-6)


def test_kinematics_never_touch_a_simulation(kin):
    client = p.connect(p.DIRECT)
    try:
        robot = sawyer.load_sawyer_wsg50(client)
        sawyer.reset_joints(client, robot, RMB_HOME, 0.02)
        before = p.getJointStates(robot.body_id, robot.controlled_joints, physicsClientId=client)
        kin.ik(kin.fk(np.zeros(7)), RMB_HOME)
        after = p.getJointStates(robot.body_id, robot.controlled_joints, physicsClientId=client)
        assert [s[0] for s in after] == [s[0] for s in before]
    finally:
        p.disconnect(client)

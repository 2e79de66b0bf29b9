"""Pose maths against hand-computed cases and RMB's conventions."""

import numpy as np
import pytest

from rmb_lerobot import pose

IDENTITY = np.array([0, 0, 0, 1, 0, 0, 0], dtype=float)


def quat_about_z(angle):
    return np.array([np.cos(angle / 2), 0, 0, np.sin(angle / 2)])


def test_quaternion_is_scalar_first():
    rot = pose.quat_to_rotmat(quat_about_z(np.pi / 2))
    np.testing.assert_allclose(rot, [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-12)
    np.testing.assert_allclose(pose.rotmat_to_quat(rot), quat_about_z(np.pi / 2), atol=1e-12)


def test_rotmat_to_quat_returns_nonnegative_w():
    q = -quat_about_z(0.3)  # same rotation, other sign
    assert pose.rotmat_to_quat(pose.quat_to_rotmat(q))[0] > 0


def test_relative_pose_is_prev_inverse_times_current_in_rpy():
    prev = np.concatenate([[1.0, 0, 0], quat_about_z(np.pi / 2)])
    cur = np.concatenate([[1.0, 1.0, 0], quat_about_z(np.pi / 2 + 0.1)])
    rel = pose.relative_pose(prev, cur)
    # In the previous frame (rotated 90 deg about z) the world +y step is the local +x step.
    np.testing.assert_allclose(rel, [1, 0, 0, 0, 0, 0.1], atol=1e-12)
    np.testing.assert_allclose(pose.apply_relative_pose(prev, rel), cur, atol=1e-12)


def test_rpy_convention_is_pinocchios_zyx():
    roll, pitch, yaw = 0.1, -0.2, 0.3
    rel = pose.rel_pose_to_matrix([0, 0, 0, roll, pitch, yaw])[:3, :3]
    rx = np.array([[1, 0, 0], [0, np.cos(roll), -np.sin(roll)], [0, np.sin(roll), np.cos(roll)]])
    ry = np.array(
        [[np.cos(pitch), 0, np.sin(pitch)], [0, 1, 0], [-np.sin(pitch), 0, np.cos(pitch)]]
    )
    rz = np.array([[np.cos(yaw), -np.sin(yaw), 0], [np.sin(yaw), np.cos(yaw), 0], [0, 0, 1]])
    np.testing.assert_allclose(rel, rz @ ry @ rx, atol=1e-12)


def test_relative_pose_sequence_starts_at_zero_like_rmb():
    poses = np.stack([IDENTITY, np.concatenate([[0, 0, 0.5], IDENTITY[3:]])])
    rel = pose.relative_pose_sequence(poses)
    np.testing.assert_allclose(rel, [[0] * 6, [0, 0, 0.5, 0, 0, 0]], atol=1e-12)


def test_six_d_rotation_is_the_first_two_rows_and_round_trips():
    rot = pose.quat_to_rotmat(quat_about_z(np.pi / 2))
    np.testing.assert_allclose(pose.rotmat_to_6d(rot), [0, -1, 0, 1, 0, 0], atol=1e-12)
    rng = np.random.default_rng(0)
    quats = rng.normal(size=(20, 4))
    quats /= np.linalg.norm(quats, axis=1, keepdims=True)
    poses = np.concatenate([rng.normal(size=(20, 3)), quats], axis=1)
    policy = pose.pose_to_policy(poses)
    assert policy.shape == (20, 9)
    back = pose.policy_to_pose(policy)
    same = np.abs(np.sum(back[:, 3:] * quats, axis=1))  # q and -q are one rotation
    np.testing.assert_allclose(same, 1, atol=1e-9)
    np.testing.assert_allclose(back[:, :3], poses[:, :3])


def test_rot6d_projects_noisy_network_output_onto_a_rotation():
    noisy = np.array([1.1, 0.1, 0.0, 0.05, 0.9, 0.02])
    rot = pose.rot6d_to_rotmat(noisy)
    np.testing.assert_allclose(rot @ rot.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(rot) == pytest.approx(1.0)


def test_wrong_shapes_are_named():
    with pytest.raises(ValueError, match="pose must have last dimension 7"):
        pose.pose_to_matrix(np.zeros(6))
    with pytest.raises(ValueError, match=r"rotation matrix must have shape \(\.\.\., 3, 3\)"):
        pose.rotmat_to_quat(np.zeros((2, 3)))

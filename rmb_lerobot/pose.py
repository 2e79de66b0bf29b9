"""Pose maths in RMB's conventions, vectorised over leading dimensions.

RMB stores an absolute pose as ``(tx, ty, tz, qw, qx, qy, qz)`` (scalar-first quaternion), a
relative pose as ``(tx, ty, tz, roll, pitch, yaw)`` of ``prev^-1 * current`` with pinocchio's
roll-pitch-yaw convention (``R = Rz(yaw) @ Ry(pitch) @ Rx(roll)``), and shows policies an
absolute pose as position + 6-D rotation (the first two rows of the rotation matrix, Zhou et al.
2019), nine numbers. Rotations go through :mod:`scipy.spatial.transform` rather than
hand-written conversions.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

POSE_DIM = 7
REL_POSE_DIM = 6
POLICY_POSE_DIM = 9
# scipy's lowercase (extrinsic) "xyz" Euler angles are pinocchio's rpy: R = Rz(y) Ry(p) Rx(r).
_RPY = "xyz"


def _check_last_dim(array: np.ndarray, dim: int, what: str) -> np.ndarray:
    array = np.asarray(array, dtype=np.float64)
    if array.ndim == 0 or array.shape[-1] != dim:
        raise ValueError(f"{what} must have last dimension {dim}, got shape {array.shape}")
    return array


def _rotation(quat_wxyz: np.ndarray) -> Rotation:
    flat = quat_wxyz.reshape(-1, 4)
    return Rotation.from_quat(flat, scalar_first=True)


def quat_to_rotmat(quat_wxyz: np.ndarray) -> np.ndarray:
    """Unit quaternion(s) ``(..., 4)`` as (w, x, y, z) -> rotation matrices ``(..., 3, 3)``."""
    quat = _check_last_dim(quat_wxyz, 4, "quaternion")
    return _rotation(quat).as_matrix().reshape(*quat.shape[:-1], 3, 3)


def rotmat_to_quat(rotmat: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(..., 3, 3)`` -> quaternions (w, x, y, z) with ``w >= 0``."""
    rot = np.asarray(rotmat, dtype=np.float64)
    if rot.shape[-2:] != (3, 3):
        raise ValueError(f"rotation matrix must have shape (..., 3, 3), got {rot.shape}")
    quat = Rotation.from_matrix(rot.reshape(-1, 3, 3)).as_quat(canonical=True, scalar_first=True)
    return quat.reshape(*rot.shape[:-2], 4)


def pose_to_matrix(pose: np.ndarray) -> np.ndarray:
    """Pose(s) ``(..., 7)`` -> homogeneous transforms ``(..., 4, 4)``."""
    pose = _check_last_dim(pose, POSE_DIM, "pose")
    out = np.zeros((*pose.shape[:-1], 4, 4))
    out[..., :3, :3] = quat_to_rotmat(pose[..., 3:7])
    out[..., :3, 3] = pose[..., :3]
    out[..., 3, 3] = 1.0
    return out


def matrix_to_pose(matrix: np.ndarray) -> np.ndarray:
    """Homogeneous transforms ``(..., 4, 4)`` -> poses ``(..., 7)``."""
    matrix = np.asarray(matrix, dtype=np.float64)
    return np.concatenate([matrix[..., :3, 3], rotmat_to_quat(matrix[..., :3, :3])], axis=-1)


def relative_pose(prev_pose: np.ndarray, current_pose: np.ndarray) -> np.ndarray:
    """``prev^-1 * current`` as ``(tx, ty, tz, roll, pitch, yaw)``: RMB's ``*_eef_pose_rel``."""
    prev = pose_to_matrix(prev_pose)
    cur = pose_to_matrix(current_pose)
    return matrix_to_rel_pose(np.linalg.inv(prev) @ cur)


def matrix_to_rel_pose(matrix: np.ndarray) -> np.ndarray:
    """Homogeneous transforms ``(..., 4, 4)`` -> ``(tx, ty, tz, roll, pitch, yaw)``."""
    matrix = np.asarray(matrix, dtype=np.float64)
    rpy = Rotation.from_matrix(matrix[..., :3, :3].reshape(-1, 3, 3)).as_euler(_RPY)
    return np.concatenate([matrix[..., :3, 3], rpy.reshape(*matrix.shape[:-2], 3)], axis=-1)


def rel_pose_to_matrix(rel_pose: np.ndarray) -> np.ndarray:
    """``(tx, ty, tz, roll, pitch, yaw)`` -> homogeneous transforms ``(..., 4, 4)``."""
    rel = _check_last_dim(rel_pose, REL_POSE_DIM, "relative pose")
    out = np.zeros((*rel.shape[:-1], 4, 4))
    rot = Rotation.from_euler(_RPY, rel[..., 3:6].reshape(-1, 3)).as_matrix()
    out[..., :3, :3] = rot.reshape(*rel.shape[:-1], 3, 3)
    out[..., :3, 3] = rel[..., :3]
    out[..., 3, 3] = 1.0
    return out


def apply_relative_pose(prev_pose: np.ndarray, rel_pose: np.ndarray) -> np.ndarray:
    """Inverse of :func:`relative_pose`: ``prev * rel`` as a pose ``(..., 7)``."""
    return matrix_to_pose(pose_to_matrix(prev_pose) @ rel_pose_to_matrix(rel_pose))


def relative_pose_sequence(poses: np.ndarray) -> np.ndarray:
    """Per-step relative poses of a ``(T, 7)`` sequence; the first step is zero (as RMB records)."""
    poses = _check_last_dim(poses, POSE_DIM, "pose sequence")
    out = np.zeros((*poses.shape[:-1], REL_POSE_DIM))
    if poses.shape[0] > 1:
        out[1:] = relative_pose(poses[:-1], poses[1:])
    return out


def rotmat_to_6d(rotmat: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(..., 3, 3)`` -> 6-D representation: the first two rows, flattened."""
    rot = np.asarray(rotmat, dtype=np.float64)
    return rot[..., :2, :].reshape(*rot.shape[:-2], 6)


def rot6d_to_rotmat(rot6d: np.ndarray) -> np.ndarray:
    """6-D representation ``(..., 6)`` -> the nearest rotation matrix (Gram-Schmidt on the rows).

    Network outputs are not orthonormal; this projects them back onto SO(3).
    """
    r = _check_last_dim(rot6d, 6, "6-D rotation")
    a, b = r[..., 0:3], r[..., 3:6]
    row0 = a / np.linalg.norm(a, axis=-1, keepdims=True)
    b = b - np.sum(row0 * b, axis=-1, keepdims=True) * row0
    row1 = b / np.linalg.norm(b, axis=-1, keepdims=True)
    row2 = np.cross(row0, row1)
    return np.stack([row0, row1, row2], axis=-2)


def pose_to_policy(pose: np.ndarray) -> np.ndarray:
    """Pose ``(..., 7)`` -> the 9 numbers policies see: position + 6-D rotation."""
    pose = _check_last_dim(pose, POSE_DIM, "pose")
    return np.concatenate([pose[..., :3], rotmat_to_6d(quat_to_rotmat(pose[..., 3:7]))], axis=-1)


def policy_to_pose(policy_pose: np.ndarray) -> np.ndarray:
    """Inverse of :func:`pose_to_policy` (re-orthonormalising the rotation)."""
    p = _check_last_dim(policy_pose, POLICY_POSE_DIM, "policy pose")
    return np.concatenate([p[..., :3], rotmat_to_quat(rot6d_to_rotmat(p[..., 3:9]))], axis=-1)

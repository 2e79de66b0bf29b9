"""Forward and inverse kinematics from the compiled MuJoCo model.

Poses are RMB's ``(tx, ty, tz, qw, qx, qy, qz)`` in the robot's root frame. Both FK and IK work
on a private :class:`mujoco.MjData`, so calling them never disturbs the simulation state. The IK
is damped least squares on ``mj_jacSite`` (position + orientation), clipping to joint limits at
every iteration; it is what the end-effector action modes and the scripted experts use.
"""

from __future__ import annotations

from typing import Protocol

import mujoco
import numpy as np

from rmb_lerobot.envs.ik import IkResult, solve_dls


class ArmNames(Protocol):
    """The MuJoCo names kinematics needs of one arm (an ``ArmModel`` of
    :mod:`rmb_lerobot.envs.mujoco.models.common`, or a ``RobotSpec``)."""

    arm_joints: tuple[str, ...]
    root_body: str
    eef_site: str


def _quat_of(xmat: np.ndarray) -> np.ndarray:
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, np.ascontiguousarray(xmat, dtype=np.float64).reshape(9))
    return quat


def _rotvec(quat: np.ndarray) -> np.ndarray:
    vel = np.empty(3)
    mujoco.mju_quat2Vel(vel, quat, 1.0)
    return vel


class ArmKinematics:
    """FK/IK of one robot's arm inside a compiled scene model."""

    def __init__(self, model: mujoco.MjModel, robot: ArmNames):
        self.model = model
        self.robot = robot
        self._data = mujoco.MjData(model)
        joint_ids = [model.joint(name).id for name in robot.arm_joints]
        self.qpos_index = np.array([model.jnt_qposadr[j] for j in joint_ids])
        self.dof_index = np.array([model.jnt_dofadr[j] for j in joint_ids])
        limited = model.jnt_limited[joint_ids].astype(bool)
        ranges = model.jnt_range[joint_ids]
        self.lower = np.where(limited, ranges[:, 0], -np.inf)
        self.upper = np.where(limited, ranges[:, 1], np.inf)
        mujoco.mj_kinematics(model, self._data)
        root = self._data.body(robot.root_body)
        self._root_pos = root.xpos.copy()
        self._root_mat = root.xmat.reshape(3, 3).copy()

    # ----------------------------------------------------------------- frames
    def _site_id(self, site: str | None) -> int:
        name = self.robot.eef_site if site is None else site
        site_id = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_SITE, name)
        if site_id < 0:
            raise ValueError(f"no site named {name!r} in the model")
        return site_id

    def world_to_root(self, pos: np.ndarray, mat: np.ndarray) -> np.ndarray:
        """World position + rotation matrix -> RMB pose in the root frame."""
        local_pos = self._root_mat.T @ (np.asarray(pos) - self._root_pos)
        local_mat = self._root_mat.T @ np.asarray(mat).reshape(3, 3)
        return np.concatenate([local_pos, _quat_of(local_mat)])

    def root_to_world(self, pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """RMB pose in the root frame -> world position and unit quaternion."""
        pose = np.asarray(pose, dtype=np.float64)
        if pose.shape != (7,):
            raise ValueError(f"pose must have shape (7,), got {pose.shape}")
        quat = pose[3:] / np.linalg.norm(pose[3:])
        root_quat = _quat_of(self._root_mat)
        world_quat = np.empty(4)
        mujoco.mju_mulQuat(world_quat, root_quat, quat)
        return self._root_pos + self._root_mat @ pose[:3], world_quat

    def site_pose(self, data: mujoco.MjData, site: str | None = None) -> np.ndarray:
        """Pose of a site (default: the eef site) in the root frame, from ``data``'s kinematics."""
        site_id = self._site_id(site)
        return self.world_to_root(data.site_xpos[site_id], data.site_xmat[site_id])

    # ----------------------------------------------------------------- FK / IK
    def _set_arm(self, q: np.ndarray) -> None:
        self._data.qpos[self.qpos_index] = q
        mujoco.mj_kinematics(self.model, self._data)

    def fk(self, q_arm: np.ndarray, site: str | None = None) -> np.ndarray:
        """Pose of a site (default: the eef site) for arm joint angles ``q_arm``.

        Extra trailing entries (the gripper value RMB appends) are ignored, so this is directly
        usable as the ``fk`` callable of :class:`rmb_lerobot.EpisodeWriter`.
        """
        q = np.asarray(q_arm, dtype=np.float64)
        n = len(self.qpos_index)
        if q.shape[-1] < n:
            raise ValueError(f"expected at least {n} joint values, got shape {q.shape}")
        self._set_arm(q[:n])
        return self.site_pose(self._data, site)

    __call__ = fk

    def ik(
        self,
        target_pose: np.ndarray,
        q_init: np.ndarray,
        site: str | None = None,
        *,
        max_iters: int = 100,
        pos_tol: float = 1e-4,
        rot_tol: float = 1e-3,
        damping: float = 1e-2,
        max_step: float = 0.3,
    ) -> IkResult:
        """Arm joints that put ``site`` at ``target_pose`` (root frame), starting from ``q_init``.

        Damped least squares: ``dq = J^T (J J^T + damping^2 I)^-1 e`` with ``e`` the 6-D
        position/rotation error in the world frame; steps are capped at ``max_step`` rad and the
        solution is clipped to the joint limits. Returns the best iterate even when it does not
        converge (an unreachable target gives the closest reachable pose).
        """
        site_id = self._site_id(site)
        target_pos, target_quat = self.root_to_world(target_pose)
        jacp = np.zeros((3, self.model.nv))
        jacr = np.zeros((3, self.model.nv))
        site_quat = np.empty(4)
        err_quat = np.empty(4)

        def error(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            self._set_arm(q)
            mujoco.mju_mat2Quat(site_quat, self._data.site_xmat[site_id])
            mujoco.mju_negQuat(site_quat, site_quat)
            mujoco.mju_mulQuat(err_quat, target_quat, site_quat)
            return target_pos - self._data.site_xpos[site_id], _rotvec(err_quat)

        def jacobian(q: np.ndarray) -> np.ndarray:  # at the state error(q) set
            mujoco.mj_comPos(self.model, self._data)
            mujoco.mj_jacSite(self.model, self._data, jacp, jacr, site_id)
            return np.vstack([jacp[:, self.dof_index], jacr[:, self.dof_index]])

        q_init = np.asarray(q_init, dtype=np.float64)[: len(self.qpos_index)]
        return solve_dls(
            error,
            jacobian,
            q_init,
            self.lower,
            self.upper,
            max_iters=max_iters,
            pos_tol=pos_tol,
            rot_tol=rot_tol,
            damping=damping,
            max_step=max_step,
        )

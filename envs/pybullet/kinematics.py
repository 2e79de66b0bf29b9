"""Forward and inverse kinematics of RMB's Sawyer arm, on a private pybullet client.

Poses are RMB's ``(x, y, z, qw, qx, qy, qz)`` (pybullet's quaternions are ``(x, y, z, w)``: this
module converts at its boundary) of the eef link (:data:`~rmb_lerobot.envs.pybullet.sawyer.
EEF_LINK_NAME`, ``right_l6``, RMB's Pinocchio joint 7) in the **robot's root frame**: the frame of
the URDF's root link ``base``, unrotated, at :data:`~rmb_lerobot.envs.pybullet.sawyer.
ROOT_POSITION` (0.1, 0, 0.03) in RMB's TACTO worlds (see :func:`~rmb_lerobot.envs.pybullet.sawyer.
load_sawyer_wsg50` for why not (0, 0, 0.1)), so ``root = world - ROOT_POSITION``. This is the
project's convention for every backend (an arm's root frame).

RMB itself builds its eef pose with Pinocchio from ``common/robots/sawyer/sawyer.urdf`` after
moving the first joint by ``arm_root_pose = get_link_pose("right_j0")``
(``RMB: envs/tacto/TactoSawyerEnvBase.py:193-205``, ``common/body/ArmManager.py:68-72``). That pose
is pybullet's ``getLinkState`` of ``right_l0`` at zero joints: the link's centre of mass (not its
frame), with the ``(x, y, z, w)`` quaternion read as ``(w, x, y, z)``; so RMB's recorded
``measured_eef_pose`` of the TACTO envs is ``T_rmb @ pose_in_root`` with the constant transform
:data:`RMB_TACTO_RECORD_FRAME` (a translation and a half turn about z), which
:func:`to_rmb_record_frame` applies.

The kinematics run on a pybullet ``DIRECT`` client of their own that holds only the robot (base
at the origin), so calling them never disturbs a simulation.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pybullet as p
from scipy.spatial.transform import Rotation

from rmb_lerobot.envs.ik import IkResult, solve_dls
from rmb_lerobot.envs.pybullet.sawyer import (
    ARM_JOINT_NAMES,
    BASE_INERTIAL_XYZ,
    EEF_LINK_NAME,
    ROOT_POSITION,
    joint_indices_by_name,
    link_indices_by_name,
    load_sawyer_wsg50,
)

#: The transform RMB's TACTO envs apply to root-frame eef poses before recording them, as a pose
#: (x, y, z, qw, qx, qy, qz): the zero-joint world position of ``right_l0``'s centre of mass
#: (ROOT_POSITION + (0, 0, 0.08) + RMB's inertial origin (0.024366, 0.010969, 0.14363)) and
#: pybullet's identity quaternion (0, 0, 0, 1) read as (w, x, y, z), a half turn about z.
RMB_TACTO_RECORD_FRAME: tuple[float, ...] = (0.124366, 0.010969, 0.25363, 0.0, 0.0, 0.0, 1.0)


def quat_wxyz_to_xyzw(quat: Sequence[float]) -> np.ndarray:
    """RMB's ``(w, x, y, z)`` quaternion in pybullet's / scipy's ``(x, y, z, w)`` order."""
    w, x, y, z = quat
    return np.array([x, y, z, w], dtype=np.float64)


def quat_xyzw_to_wxyz(quat: Sequence[float]) -> np.ndarray:
    """Pybullet's / scipy's ``(x, y, z, w)`` quaternion in RMB's ``(w, x, y, z)`` order."""
    x, y, z, w = quat
    return np.array([w, x, y, z], dtype=np.float64)


def pose_from_pos_rot(pos: Sequence[float], rot: np.ndarray) -> np.ndarray:
    """Position (3,) and rotation matrix (3, 3) -> RMB pose (7,), ``qw >= 0``."""
    quat = quat_xyzw_to_wxyz(Rotation.from_matrix(np.asarray(rot, dtype=np.float64)).as_quat())
    if quat[0] < 0:
        quat = -quat
    return np.concatenate([np.asarray(pos, dtype=np.float64), quat])


def pos_rot_from_pose(pose: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """RMB pose (7,) -> position (3,) and rotation matrix (3, 3) (the quaternion is normalised).

    Raises:
        ValueError: If ``pose`` is not 7 numbers or its quaternion is zero.
    """
    pose = np.asarray(pose, dtype=np.float64)
    if pose.shape != (7,):
        raise ValueError(f"pose must have shape (7,), got {pose.shape}")
    if not np.linalg.norm(pose[3:]) > 0:
        raise ValueError("pose quaternion must be non-zero")
    return pose[:3].copy(), Rotation.from_quat(quat_wxyz_to_xyzw(pose[3:])).as_matrix()


def to_rmb_record_frame(pose_in_root: Sequence[float]) -> np.ndarray:
    """A root-frame eef pose as RMB's TACTO envs record it (``measured_eef_pose``).

    Use it to compare with (or produce) RMB's recorded values; everything else in this project
    works in the root frame.
    """
    frame_pos, frame_rot = pos_rot_from_pose(RMB_TACTO_RECORD_FRAME)
    pos, rot = pos_rot_from_pose(pose_in_root)
    return pose_from_pos_rot(frame_pos + frame_rot @ pos, frame_rot @ rot)


class SawyerKinematics:
    """FK and damped-least-squares IK of the Sawyer arm (7 joints, eef ``right_l6``).

    Example::

        kin = SawyerKinematics()
        pose = kin.fk(HOME_ARM_QPOS)            # (7,) in the root frame
        q = kin.ik(pose, q_init=HOME_ARM_QPOS)  # back to joints
        kin.close()
    """

    def __init__(
        self,
        *,
        eef_link: str = EEF_LINK_NAME,
        root_position: Sequence[float] = ROOT_POSITION,
        urdf_directory: Path | None = None,
    ) -> None:
        """Load the robot into a private ``p.DIRECT`` client.

        Args:
            eef_link: The link whose frame FK reports and IK places.
            root_position: World position of the robot's root frame in the simulation this
                instance serves (``SawyerHandles.root_position``; used by
                :meth:`world_to_root` / :meth:`root_to_world` only).
            urdf_directory: Where to write the generated URDF (a temp cache by default).

        Raises:
            KeyError: If ``eef_link`` is not a link of the model.
        """
        self.root_position = np.asarray(root_position, dtype=np.float64)
        self._client = p.connect(p.DIRECT)
        try:
            # Base centre of mass at BASE_INERTIAL_XYZ: the root frame is this client's world.
            handles = load_sawyer_wsg50(
                self._client, directory=urdf_directory, base_position=BASE_INERTIAL_XYZ
            )
            self._body = handles.body_id
            self._eef = link_indices_by_name(self._body, self._client)[eef_link]
        except BaseException:
            p.disconnect(self._client)
            raise
        self.lower = handles.arm_lower.copy()
        self.upper = handles.arm_upper.copy()
        joints = joint_indices_by_name(self._body, self._client)
        self._arm = [joints[name] for name in ARM_JOINT_NAMES]
        self._dofs = [
            i
            for i in range(p.getNumJoints(self._body, physicsClientId=self._client))
            if p.getJointInfo(self._body, i, physicsClientId=self._client)[2] != p.JOINT_FIXED
        ]
        self._arm_columns = [self._dofs.index(j) for j in self._arm]

    # ----------------------------------------------------------------- lifecycle
    def close(self) -> None:
        """Disconnect the private client (idempotent)."""
        if self._client is not None and p.isConnected(self._client):
            p.disconnect(self._client)
        self._client = None

    def __enter__(self) -> SawyerKinematics:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ----------------------------------------------------------------- frames
    def world_to_root(self, pos: Sequence[float], rot: np.ndarray) -> np.ndarray:
        """A world position (3,) and rotation matrix (3, 3) as an RMB pose in the root frame."""
        return pose_from_pos_rot(np.asarray(pos, dtype=np.float64) - self.root_position, rot)

    def root_to_world(self, pose: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
        """An RMB pose in the root frame as a world position (3,) and rotation matrix (3, 3)."""
        pos, rot = pos_rot_from_pose(pose)
        return pos + self.root_position, rot

    # ----------------------------------------------------------------- FK
    def _arm_qpos(self, q: Sequence[float]) -> np.ndarray:
        q = np.asarray(q, dtype=np.float64).reshape(-1)
        if q.shape[0] < len(self._arm):
            raise ValueError(f"expected at least {len(self._arm)} joint values, got {q.shape[0]}")
        return q[: len(self._arm)]

    def _set_arm(self, q: np.ndarray) -> None:
        for index, value in zip(self._arm, q, strict=True):
            p.resetJointState(self._body, index, float(value), physicsClientId=self._client)

    def _eef_pos_rot(self) -> tuple[np.ndarray, np.ndarray]:
        state = p.getLinkState(
            self._body, self._eef, computeForwardKinematics=True, physicsClientId=self._client
        )
        rot = np.array(p.getMatrixFromQuaternion(state[5])).reshape(3, 3)
        return np.array(state[4]), rot

    def fk(self, q_arm: Sequence[float]) -> np.ndarray:
        """Eef pose (7,) in the root frame for the arm joint angles ``q_arm``.

        Args:
            q_arm: The 7 arm joint angles; extra trailing entries (the gripper value RMB appends
                to its joint vectors) are ignored.

        Returns:
            ``(x, y, z, qw, qx, qy, qz)`` with ``qw >= 0``.

        Raises:
            ValueError: If fewer than 7 values are given.
        """
        self._set_arm(self._arm_qpos(q_arm))
        return pose_from_pos_rot(*self._eef_pos_rot())

    __call__ = fk

    # ----------------------------------------------------------------- IK
    def jacobian(self, q_arm: Sequence[float]) -> np.ndarray:
        """Geometric Jacobian (6, 7) of the eef frame origin: linear over angular velocity, both
        in the root frame, at the arm joints ``q_arm`` (extra entries ignored).

        pybullet's ``calculateJacobian`` takes its point relative to the URDF link frame's origin
        (in the inertial frame's axes; bullet3 issue #4668, checked against finite differences of
        :meth:`fk` in the tests), so the link origin is the point (0, 0, 0).
        """
        q = self._arm_qpos(q_arm)
        positions = [
            p.getJointState(self._body, j, physicsClientId=self._client)[0] for j in self._dofs
        ]
        for column, value in zip(self._arm_columns, q, strict=True):
            positions[column] = float(value)
        zeros = [0.0] * len(self._dofs)
        linear, angular = p.calculateJacobian(
            self._body,
            self._eef,
            [0.0, 0.0, 0.0],
            positions,
            zeros,
            zeros,
            physicsClientId=self._client,
        )
        jac = np.vstack([np.array(linear), np.array(angular)])
        return jac[:, self._arm_columns]

    def solve_ik(
        self,
        target_pose: Sequence[float],
        q_init: Sequence[float],
        *,
        max_iters: int = 200,
        pos_tol: float = 1e-4,
        rot_tol: float = 1e-3,
        damping: float = 1e-2,
        max_step: float = 0.2,
    ) -> IkResult:
        """Arm joints placing the eef at ``target_pose`` (root frame), with diagnostics.

        Damped least squares ``dq = J^T (J J^T + damping^2 I)^-1 e``: ``e`` is the position error
        and the rotation vector of ``R_target R^T`` (both in the root frame), steps are capped at
        ``max_step`` rad and every iterate is clipped to the joint limits. The best iterate
        (position error + 0.1 m/rad x rotation error) is returned even when the target is out of
        reach, so the answer is always finite and within limits.

        Args:
            target_pose: ``(x, y, z, qw, qx, qy, qz)`` in the root frame.
            q_init: Starting joints (7; extra entries ignored), e.g. the current ones.
            max_iters: Iteration bound.
            pos_tol: Position tolerance (m) for convergence.
            rot_tol: Rotation tolerance (rad) for convergence.
            damping: Damping factor of the least squares.
            max_step: Largest joint change per iteration (rad).

        Returns:
            The solution and its remaining error.

        Raises:
            ValueError: If ``target_pose`` is not a 7-vector with a non-zero quaternion.
        """
        target_pos, target_rot = pos_rot_from_pose(target_pose)

        def error(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            self._set_arm(q)
            pos, rot = self._eef_pos_rot()
            return target_pos - pos, Rotation.from_matrix(target_rot @ rot.T).as_rotvec()

        return solve_dls(
            error,
            self.jacobian,
            self._arm_qpos(q_init),
            self.lower,
            self.upper,
            max_iters=max_iters,
            pos_tol=pos_tol,
            rot_tol=rot_tol,
            damping=damping,
            max_step=max_step,
        )

    def ik(self, target_pose: Sequence[float], q_init: Sequence[float]) -> np.ndarray:
        """Arm joints (7,) placing the eef at ``target_pose`` (root frame), from ``q_init``.

        The closest reachable solution (within joint limits) when the target is out of reach;
        :meth:`solve_ik` also says how close it got.
        """
        return self.solve_ik(target_pose, q_init).qpos

"""The end-effector velocity action of the real-arm plugins (``--robot.action_space=ee_velocity``).

LeRobot's stock loops hand a teleoperator no robot state (``lerobot-record`` stores the
teleoperator's action as it is and gives it no feedback), so a Cartesian device cannot track
an absolute pose target that starts where the arm stands. The robot can: :class:`EeTarget`
is the robot's own end-effector target. It starts at the *measured* pose (forward kinematics
of the measured joints), moves by each action's velocity held for one command duration, is
solved by the same damped-least-squares IK as the simulated envs' end-effector modes
(:class:`~rmb_lerobot.envs.mujoco.kinematics.ArmKinematics` on the robot record's MuJoCo
model), and snaps back to what was actually sent or measured whenever the two part ways (an
unreachable target, a clamp by the safety layer, an arm that lagged or was stopped). The
resulting joint target then passes the safety layer like any joint action.

Keys (all ``float``, :data:`~.features.EE_VELOCITY_KEYS`): ``ee_x.vel``, ``ee_y.vel``,
``ee_z.vel`` (m/s) and ``ee_roll.vel``, ``ee_pitch.vel``, ``ee_yaw.vel`` (rad/s) in the arm's
base frame (the robot record's root frame, the frame of RMB's ``measured_eef_pose``), then
``gripper.pos`` (the absolute gripper command, 0 open .. 255 closed). The angular part turns
the target in the base frame by the roll-pitch-yaw ``ω · dt`` (``R ← R(ω dt) · R``, RMB's
teleop rule). They end in ``.vel`` as LeKiwi's base velocities do, so ``lerobot-rollout``
passes them to and from a policy.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from scipy.spatial.transform import Rotation

from rmb_lerobot.pose import quat_to_rotmat, rotmat_to_quat

if TYPE_CHECKING:
    from rmb_lerobot.envs.mujoco.kinematics import ArmKinematics
    from rmb_lerobot.envs.robots import Robot

log = logging.getLogger(__name__)

_RPY = "xyz"  # scipy's extrinsic xyz = RMB's (pinocchio's) roll-pitch-yaw, as rmb_lerobot.pose

DRIFT_POSITION_M = 0.05
"""Target re-synced to the measured pose when their positions are further apart (m)."""
DRIFT_ROTATION_RAD = 0.3
"""... or their orientations differ by more than this (rad)."""
IK_POSITION_TOL_M = 1e-3
"""An IK answer further than this from the target (m) is taken as "out of reach"."""
IK_ROTATION_TOL_RAD = 1e-2
"""... or further than this in orientation (rad)."""


@dataclass(frozen=True)
class EeStep:
    """One end-effector action turned into a joint target.

    Attributes:
        joint_pos: Arm joint target (rad) for the safety layer.
        target_pose: The end-effector target it was solved for, ``(x, y, z, qw, qx, qy, qz)``
            in the base frame (already pulled back to the IK's answer when out of reach).
        resynced: Why the target was re-synced to the measured pose first (``""``: it was not).
        reached: Whether the IK reached the requested pose (within the tolerances above).
    """

    joint_pos: np.ndarray
    target_pose: np.ndarray
    resynced: str
    reached: bool


def build_arm_kinematics(record: Robot) -> ArmKinematics:
    """FK/IK of a single-arm record on its MuJoCo model (what the twins and sim envs load).

    Args:
        record: A single-arm robot record (``ur5e``, ``xarm7``).

    Returns:
        The arm's kinematics (poses in its root frame).
    """
    from rmb_lerobot.envs.mujoco.kinematics import ArmKinematics
    from rmb_lerobot.envs.mujoco.robots import build_robot_model

    built = build_robot_model(record)
    (arm,) = built.arms
    return ArmKinematics(built.spec.compile(), arm)


def apply_twist(pose: np.ndarray, twist: np.ndarray, dt: float) -> np.ndarray:
    """Move a pose by a base-frame twist held for ``dt`` seconds.

    Args:
        pose: ``(x, y, z, qw, qx, qy, qz)``.
        twist: ``(vx, vy, vz, ωroll, ωpitch, ωyaw)`` in m/s and rad/s.
        dt: Seconds the twist is held.

    Returns:
        The new pose: position ``+ v dt``, rotation ``R(ω dt) · R`` (roll-pitch-yaw).
    """
    twist = np.asarray(twist, dtype=np.float64)
    out = np.asarray(pose, dtype=np.float64).copy()
    out[:3] += twist[:3] * dt
    turn = Rotation.from_euler(_RPY, twist[3:] * dt).as_matrix()
    out[3:] = rotmat_to_quat(turn @ quat_to_rotmat(out[3:]))
    return out


def pose_twist(before: np.ndarray, after: np.ndarray, dt: float) -> np.ndarray:
    """The base-frame twist that takes ``before`` to ``after`` in ``dt`` seconds
    (the inverse of :func:`apply_twist`).

    Args:
        before: ``(x, y, z, qw, qx, qy, qz)``.
        after: The same.
        dt: Seconds (> 0).

    Returns:
        ``(vx, vy, vz, ωroll, ωpitch, ωyaw)``.
    """
    turn = quat_to_rotmat(after[3:]) @ quat_to_rotmat(before[3:]).T
    rpy = Rotation.from_matrix(turn).as_euler(_RPY)
    return np.concatenate([np.asarray(after[:3]) - before[:3], rpy]) / dt


def pose_distance(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    """Position (m) and rotation angle (rad) between two poses.

    Args:
        a: ``(x, y, z, qw, qx, qy, qz)``.
        b: The same.

    Returns:
        ``(|pa - pb|, angle of Ra^T Rb)``.
    """
    rel = quat_to_rotmat(a[3:]).T @ quat_to_rotmat(b[3:])
    return float(np.linalg.norm(a[:3] - b[:3])), float(Rotation.from_matrix(rel).magnitude())


class EeTarget:
    """The end-effector target one arm tracks in ``ee_velocity`` mode.

    Args:
        kinematics: FK/IK of the arm (:func:`build_arm_kinematics`).
        name: The robot's name for log messages.
    """

    def __init__(self, kinematics: ArmKinematics, name: str = "arm"):
        self.kinematics = kinematics
        self.name = name
        self.pose: np.ndarray | None = None
        self._seed: np.ndarray | None = None

    def reset(self) -> None:
        """Forget the target: the next :meth:`step` starts from the measured pose."""
        self.pose = None
        self._seed = None

    def sync(self, measured_q: np.ndarray) -> np.ndarray:
        """Put the target where the arm stands.

        Args:
            measured_q: Measured arm joints (rad).

        Returns:
            The measured pose, now the target.
        """
        q = np.asarray(measured_q, dtype=np.float64)
        self.pose = self.kinematics.fk(q)
        self._seed = q.copy()
        return self.pose.copy()

    def step(self, twist: np.ndarray, dt: float, measured_q: np.ndarray) -> EeStep:
        """Move the target by ``twist`` for ``dt`` seconds and solve it for the arm's joints.

        The target is first re-synced to the measured pose when there is none yet, or when the
        arm stands further than :data:`DRIFT_POSITION_M` / :data:`DRIFT_ROTATION_RAD` from it
        (it lagged, was blocked or stopped): an operator then steers from where the arm
        really is, instead of the arm lunging after a target that ran away.

        Args:
            twist: ``(vx, vy, vz, ωroll, ωpitch, ωyaw)`` (m/s, rad/s), finite.
            dt: Seconds the twist is held (the command duration).
            measured_q: Measured arm joints (rad).

        Returns:
            The joint target and the pose it was solved for.

        Raises:
            ValueError: ``twist`` is not 6 finite numbers.
        """
        twist = np.asarray(twist, dtype=np.float64)
        if twist.shape != (6,) or not np.all(np.isfinite(twist)):
            raise ValueError(f"{self.name}: twist must be 6 finite numbers, got {twist}")
        measured_q = np.asarray(measured_q, dtype=np.float64)
        resynced = ""
        if self.pose is None or self._seed is None:
            resynced = "start"
        else:
            dist, angle = pose_distance(self.kinematics.fk(measured_q), self.pose)
            if dist > DRIFT_POSITION_M or angle > DRIFT_ROTATION_RAD:
                resynced = f"the arm is {dist:.3f} m / {angle:.2f} rad from its target"
                log.warning("%s: %s; target re-synced to the measured pose", self.name, resynced)
        if resynced:
            self.sync(measured_q)
        assert self.pose is not None and self._seed is not None
        wanted = apply_twist(self.pose, twist, dt)
        result = self.kinematics.ik(wanted, self._seed)
        reached_pose = self.kinematics.fk(result.qpos)
        dist, angle = pose_distance(reached_pose, wanted)
        reached = dist <= IK_POSITION_TOL_M and angle <= IK_ROTATION_TOL_RAD
        # Out of reach (or at a joint limit): hold the target at what the joints can do, so it
        # never winds up beyond the workspace and comes back in as soon as the twist reverses.
        self.pose = wanted if reached else reached_pose
        self._seed = result.qpos.copy()
        return EeStep(result.qpos.copy(), self.pose.copy(), resynced, reached)

    def sent(self, joint_pos: np.ndarray, clipped: bool) -> None:
        """Tell the target what the safety layer actually sent.

        Args:
            joint_pos: The arm joint target sent (rad).
            clipped: Whether the layer changed it (joint bounds, velocity clamp).
        """
        q = np.asarray(joint_pos, dtype=np.float64)
        self._seed = q.copy()
        if clipped:  # the arm goes where the layer sent it, not where the target asked
            self.pose = self.kinematics.fk(q)

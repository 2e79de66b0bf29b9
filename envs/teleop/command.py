"""Device readings -> the env's joint command: one end-effector target per arm, solved by IK.

A Cartesian device (keyboard, SpaceMouse) reports pose *deltas* in the world frame; as in
RMB's ``TeleopBase``, they accumulate into a target pose per arm (``p += dpos``,
``R = R(drpy) @ R``, ``R(drpy)`` = Rz(yaw) Ry(pitch) Rx(roll), pinocchio's ``rpyToMatrix``) and
the target is solved with the env's own inverse kinematics (the backend's damped least
squares, :mod:`rmb_lerobot.envs.ik`), starting from the arm's last command. Targets live in
each arm's root frame, where the env's IK takes them; deltas are rotated into it, so W moves
every arm towards world +x whichever way its base is turned (the UR5e's is turned by pi).

A joint-space device (GELLO, a replayed log) gives joint targets and a gripper closure in
[0, 1], which pass through (the target pose follows them, so devices can be swapped).
"""

from __future__ import annotations

import logging

import numpy as np
from scipy.spatial.transform import Rotation

from rmb_lerobot.envs.base import RmbEnv
from rmb_lerobot.envs.teleop.device import CartesianDelta, DeviceReading, JointTarget
from rmb_lerobot.pose import quat_to_rotmat, rotmat_to_quat

logger = logging.getLogger(__name__)


class CommandTracker:
    """The joint command a stream of device readings means for one env.

    Args:
        env: The env whose robot is driven (its IK, forward kinematics, arm frames and
            gripper ranges are used).
    """

    def __init__(self, env: RmbEnv):
        self.env = env
        self.slices = env.robot.joint_slices()
        self.grippers = [arm.gripper for arm in env.robot.arms]
        # Rotation of each arm's root frame relative to the world (root-from-world).
        self.root_from_world = [
            quat_to_rotmat(env.sim.world_to_root(i, np.zeros(3), np.eye(3))[3:])
            for i in range(len(self.slices))
        ]
        self._base_warned = False
        self.sync()

    def sync(self) -> None:
        """Take the env's current command as the command, and its eef poses as the targets
        (after a reset, and whenever a device starts driving)."""
        self.command = self.env.command
        self.targets = [
            (pose[:3].copy(), quat_to_rotmat(pose[3:]))
            for pose in (
                self.env.sim.fk(i, self.command[arm]) for i, (arm, _) in enumerate(self.slices)
            )
        ]

    def target_pose(self, arm: int) -> np.ndarray:
        """Arm ``arm``'s target (7,) in its root frame: ``(x, y, z, qw, qx, qy, qz)``."""
        pos, rot = self.targets[arm]
        return np.concatenate([pos, rotmat_to_quat(rot)])

    def update(self, reading: DeviceReading) -> np.ndarray:
        """Apply one reading and return the new joint command (arms it omits hold).

        Raises:
            ValueError: The reading names an arm the robot does not have.
        """
        command = self.command.copy()
        for arm, value in reading.arms.items():
            if not 0 <= arm < len(self.slices):
                raise ValueError(
                    f"device command for arm {arm}; {self.env.robot.name} has arms "
                    f"0..{len(self.slices) - 1}"
                )
            if isinstance(value, CartesianDelta):
                self._apply_delta(arm, value, command)
            elif isinstance(value, JointTarget):
                self._apply_joints(arm, value, command)
            else:
                raise TypeError(f"unknown arm command {type(value).__name__} for arm {arm}")
        if reading.base is not None and np.any(reading.base) and not self._base_warned:
            logger.warning("%s has no mobile base: base commands ignored", self.env.robot.name)
            self._base_warned = True
        self.command = command
        return command.copy()

    def _apply_delta(self, arm: int, delta: CartesianDelta, command: np.ndarray) -> None:
        joints, grip = self.slices[arm]
        pos, rot = self.targets[arm]
        to_root = self.root_from_world[arm]
        if np.any(delta.dpos) or np.any(delta.drpy):
            world_rot = Rotation.from_euler("xyz", np.asarray(delta.drpy)).as_matrix()
            pos = pos + to_root @ np.asarray(delta.dpos, dtype=np.float64)
            rot = to_root @ world_rot @ to_root.T @ rot
            self.targets[arm] = (pos, rot)
            target = np.concatenate([pos, rotmat_to_quat(rot)])
            command[joints] = self.env.sim.ik(arm, target, command[joints])
        if delta.dgripper:
            gripper = self.grippers[arm]
            low, high = gripper.command_range
            towards_closed = np.sign(gripper.closed - gripper.open)
            command[grip] = np.clip(command[grip] + towards_closed * delta.dgripper, low, high)

    def _apply_joints(self, arm: int, target: JointTarget, command: np.ndarray) -> None:
        joints, grip = self.slices[arm]
        if len(target.joints) != len(self.env.robot.arms[arm].joints):
            raise ValueError(
                f"joint target for arm {arm} has {len(target.joints)} joints; "
                f"{self.env.robot.arms[arm].name} has {len(self.env.robot.arms[arm].joints)}"
            )
        command[joints] = target.joints
        gripper = self.grippers[arm]
        low, high = gripper.command_range
        closure = np.clip(target.gripper, 0.0, 1.0)
        command[grip] = np.clip(gripper.open + closure * (gripper.closed - gripper.open), low, high)
        pose = self.env.sim.fk(arm, command[joints])
        self.targets[arm] = (pose[:3].copy(), quat_to_rotmat(pose[3:]))


def gripper_closure(value: float, open_value: float, closed_value: float) -> float:
    """A gripper command as a closure in [0, 1] (0 open, 1 closed), the inverse of the map
    :class:`CommandTracker` applies to a :class:`JointTarget`."""
    return float((value - open_value) / (closed_value - open_value))

"""Action modes: what an action vector means, as small objects (size, bounds, to-command).

Every mode turns an action into a *command*: the joint vector RMB records (per arm its joint
targets, then its gripper command; :meth:`~rmb_lerobot.envs.robots.Robot.joint_slices`).

- ``joint``: the command itself (absolute joint targets + gripper values);
- ``eef_abs``: per arm the absolute end-effector pose in its root frame as the 9 numbers
  policies use (position + 6-D rotation, what a dataset converted with ``command_eef_pose`` as
  action holds), then one gripper value per arm;
- ``eef_rel``: per arm RMB's relative eef pose (6: translation + rotation vector) applied to
  the previous command's pose, then one gripper value per arm.

A robot on a mobile base (:attr:`~rmb_lerobot.envs.robots.Robot.base`) has its base velocity
``(vx, vy, wz)`` (base frame) as the last three numbers of every mode's action and of the
command (:attr:`~rmb_lerobot.envs.robots.Robot.base_slice`), bounded by the base's limits; a
fixed robot's actions and commands are the arm parts only.

The eef modes ask an inverse kinematics function for the joints (the backend's, see
:class:`CommandState`). The order of the eef modes' numbers (all poses, then all grippers) is
RMB's key order: ``command_eef_pose`` then ``command_gripper_joint_pos``. Nothing here depends
on a simulator.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import ClassVar

import gymnasium as gym
import numpy as np

from rmb_lerobot.envs.robots import Robot
from rmb_lerobot.pose import POLICY_POSE_DIM, REL_POSE_DIM, apply_relative_pose, policy_to_pose

# Per-step bounds of the eef action spaces (root frame, metres / radians).
EEF_POS_BOUND = 1.5
EEF_REL_POS_BOUND = 0.2
EEF_REL_ROT_BOUND = np.pi
# Joint-mode bound of joints without limits (continuous joints), rad.
UNLIMITED_JOINT_BOUND = 2 * np.pi

IkSolver = Callable[[int, np.ndarray, np.ndarray], np.ndarray]
"""``ik(arm_index, target_pose (7,), q_init) -> arm joint angles``."""


@dataclass(frozen=True)
class CommandState:
    """What an action is applied to: the current command, its eef pose per arm, and IK."""

    command: np.ndarray  # joint vector of the last command
    eef_poses: tuple[np.ndarray, ...]  # per arm, its pose (7,) in its root frame
    ik: IkSolver


class ActionMode(ABC):
    """One action mode for one robot: its gymnasium space and its action-to-command map.

    ``joint_limits``: per arm, ``(lower, upper)`` of its arm joints (``-inf``/``inf`` where a
    joint has none), as the backend's model gives them.
    """

    name: ClassVar[str]

    def __init__(self, robot: Robot, joint_limits: Sequence[tuple[np.ndarray, np.ndarray]]):
        if len(joint_limits) != len(robot.arms):
            raise ValueError(f"{len(robot.arms)} arms but {len(joint_limits)} joint limits")
        self.robot = robot
        self.slices = robot.joint_slices()
        self.gripper_ranges = tuple(arm.gripper.command_range for arm in robot.arms)
        lower, upper = self._bounds(joint_limits)
        if robot.base is not None:
            base_low, base_high = robot.base.velocity_bounds
            lower, upper = np.append(lower, base_low), np.append(upper, base_high)
        self.space = gym.spaces.Box(
            lower.astype(np.float32), upper.astype(np.float32), dtype=np.float32
        )

    @property
    def size(self) -> int:
        return int(self.space.shape[0])

    @property
    def arm_size(self) -> int:
        """Numbers of the arm parts (the action without the base velocity)."""
        return self.size - self.robot.layout.mobile_dim

    @abstractmethod
    def _bounds(
        self, joint_limits: Sequence[tuple[np.ndarray, np.ndarray]]
    ) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds of the arm parts of the action (float64; the space stores
        float32); the base velocity's bounds are appended from the record."""

    @abstractmethod
    def _command(self, action: np.ndarray, state: CommandState) -> np.ndarray:
        """The joint vector of the arm parts of a checked float64 action."""

    def to_command(self, action: np.ndarray, state: CommandState) -> np.ndarray:
        """The command an action means: the joint vector (gripper values clipped to their
        range), then the base velocity clipped to the base's bounds when there is a base.

        Raises:
            ValueError: the action has the wrong shape or non-finite values.
        """
        action = np.asarray(action, dtype=np.float64)
        if action.shape != self.space.shape:
            raise ValueError(
                f"{self.name!r} action must have shape {self.space.shape}, got {action.shape}"
            )
        if not np.all(np.isfinite(action)):
            raise ValueError(f"action has non-finite values: {action}")
        joints = self._command(action[: self.arm_size], state)
        if self.robot.base is None:
            return joints
        low, high = self.robot.base.velocity_bounds
        return np.concatenate([joints, np.clip(action[self.arm_size :], low, high)])

    def _gripper_bounds(self) -> tuple[list[float], list[float]]:
        return [lo for lo, _ in self.gripper_ranges], [hi for _, hi in self.gripper_ranges]

    def _grippers(self, values: np.ndarray) -> list[np.float64]:
        return [np.clip(v, lo, hi) for v, (lo, hi) in zip(values, self.gripper_ranges, strict=True)]


class JointMode(ActionMode):
    """Absolute joint targets and gripper commands: the command vector itself."""

    name = "joint"

    def _bounds(self, joint_limits):
        lows, highs = [], []
        for (lower, upper), (g_lo, g_hi) in zip(joint_limits, self.gripper_ranges, strict=True):
            lows.append(np.append(lower, g_lo))
            highs.append(np.append(upper, g_hi))
        lower, upper = np.concatenate(lows), np.concatenate(highs)
        lower = np.where(np.isfinite(lower), lower, -UNLIMITED_JOINT_BOUND)
        upper = np.where(np.isfinite(upper), upper, UNLIMITED_JOINT_BOUND)
        return lower, upper

    def _command(self, action, state):
        command = np.empty_like(action)
        low, high = self.space.low, self.space.high
        for (arm, grip), (g_lo, g_hi) in zip(self.slices, self.gripper_ranges, strict=True):
            command[arm] = np.clip(action[arm], low[arm], high[arm])
            command[grip] = np.clip(action[grip], g_lo, g_hi)
        return command


class _EefMode(ActionMode):
    """Per arm a pose part of ``pose_dim`` numbers, then one gripper value per arm."""

    pose_dim: ClassVar[int]

    @abstractmethod
    def _pose_bounds(self) -> tuple[list[float], list[float]]:
        """Bounds of one arm's pose part."""

    @abstractmethod
    def _target(self, part: np.ndarray, current_pose: np.ndarray) -> np.ndarray:
        """The target eef pose (7,) of one arm's pose part."""

    def _bounds(self, joint_limits):
        lower, upper = self._pose_bounds()
        g_lo, g_hi = self._gripper_bounds()
        n = len(self.robot.arms)
        return np.array([*lower * n, *g_lo]), np.array([*upper * n, *g_hi])

    def _command(self, action, state):
        n = len(self.robot.arms)
        grippers = self._grippers(action[self.pose_dim * n : self.pose_dim * n + n])
        command = np.empty(self.robot.layout.num_joints)
        for i, (arm, grip) in enumerate(self.slices):
            part = action[self.pose_dim * i : self.pose_dim * (i + 1)]
            target = self._target(part, state.eef_poses[i])
            command[arm] = state.ik(i, target, state.command[arm])
            command[grip] = grippers[i]
        return command


class EefAbsMode(_EefMode):
    """Absolute eef poses (position + 6-D rotation) in each arm's root frame."""

    name = "eef_abs"
    pose_dim = POLICY_POSE_DIM

    def _pose_bounds(self):
        return [-EEF_POS_BOUND] * 3 + [-1.0] * 6, [EEF_POS_BOUND] * 3 + [1.0] * 6

    def _target(self, part, current_pose):
        rot6d = part[3:POLICY_POSE_DIM].reshape(2, 3)
        if np.linalg.norm(np.cross(*rot6d)) < 1e-6:
            raise ValueError(f"eef_abs action has a degenerate 6-D rotation: {part}")
        return policy_to_pose(part.astype(np.float64))


class EefRelMode(_EefMode):
    """RMB's relative eef poses, applied to the previous command's poses."""

    name = "eef_rel"
    pose_dim = REL_POSE_DIM

    def _pose_bounds(self):
        return (
            [-EEF_REL_POS_BOUND] * 3 + [-EEF_REL_ROT_BOUND] * 3,
            [EEF_REL_POS_BOUND] * 3 + [EEF_REL_ROT_BOUND] * 3,
        )

    def _target(self, part, current_pose):
        return apply_relative_pose(current_pose, part)


ACTION_MODE_CLASSES: dict[str, type[ActionMode]] = {
    cls.name: cls for cls in (JointMode, EefAbsMode, EefRelMode)
}
ACTION_MODES = tuple(ACTION_MODE_CLASSES)


def make_action_mode(
    name: str, robot: Robot, joint_limits: Sequence[tuple[np.ndarray, np.ndarray]]
) -> ActionMode:
    if name not in ACTION_MODE_CLASSES:
        raise ValueError(f"action_mode must be one of {ACTION_MODES}, got {name!r}")
    return ACTION_MODE_CLASSES[name](robot, joint_limits)

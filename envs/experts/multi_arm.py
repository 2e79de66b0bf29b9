"""Scripted experts for robots with several arms, built from one single-arm expert per arm.

A :class:`~rmb_lerobot.envs.experts.base.ScriptedExpert` tracks one arm's waypoints and emits
that arm's action only. For a two-arm robot the action holds every arm (``envs/actions.py``):

- ``joint``: per arm its joint targets, then its gripper command (the command vector);
- ``eef_abs`` / ``eef_rel``: per arm its pose part (9 or 6 numbers), then all grippers.

So a multi-arm expert lets each arm's expert (mixing in :class:`ArmTargets`, with its own
``arm_index``) produce a *target*: the eef pose in that arm's root frame and a gripper command,
after the same tracking, integral correction and tool-offset logic the single-arm experts use.
:class:`MultiArmExpert` coordinates them (:meth:`MultiArmExpert.coordinate`, once a step) and
assembles the targets into one action in the env's mode, in the order the action modes read
them. Nothing here is task-specific, and ``base.py`` needs no change.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from rmb_lerobot.envs.base import RmbEnv
from rmb_lerobot.envs.experts.base import ScriptedExpert
from rmb_lerobot.keys import MOBILE_OMNI_VEL_DIM
from rmb_lerobot.pose import POSE_DIM, pose_to_policy, relative_pose


class ArmTargets:
    """Mixin for a :class:`ScriptedExpert` that drives one arm of several (list it first among
    the bases): :meth:`arm_target` returns this step's target instead of an action."""

    def _action(self, pose: np.ndarray, gripper: float) -> np.ndarray:
        return np.append(pose, gripper)

    def arm_target(self) -> tuple[np.ndarray, float]:
        """Eef pose target (7,) in the arm's root frame and the gripper command; advances the
        arm's phase as :meth:`ScriptedExpert.select_action` does."""
        target = self.select_action()  # type: ignore[attr-defined]
        return target[:POSE_DIM], float(target[POSE_DIM])


class MultiArmExpert:
    """One expert per arm (``arms[i]`` drives the robot's arm ``i``), coordinated.

    Subclasses build the per-arm experts, may hand work between them in :meth:`coordinate`,
    and extend :meth:`on_reset`. Called like any policy: ``action = expert(observation)``;
    call :meth:`reset` after every ``env.reset``.
    """

    def __init__(self, env: Any, arms: Sequence[ScriptedExpert]):
        self.env: RmbEnv = env.unwrapped
        self.sim = self.env.sim
        robot = self.env.robot
        if len(arms) != len(robot.arms):
            raise ValueError(f"robot {robot.name!r} has {len(robot.arms)} arms, got {len(arms)}")
        for i, arm in enumerate(arms):
            if arm.arm_index != i or not isinstance(arm, ArmTargets):
                raise ValueError(
                    f"arms[{i}] must be an ArmTargets expert with arm_index {i}, got "
                    f"{type(arm).__name__} with arm_index {arm.arm_index}"
                )
        self.arms = tuple(arms)
        self._slices = robot.joint_slices()
        self._q = [self.env.home_command[joints].copy() for joints, _ in self._slices]

    def on_reset(self) -> None:
        """Coordination state reset (after every arm's :meth:`ScriptedExpert.reset`)."""

    def coordinate(self) -> None:
        """Called once a step before the arms' targets: hand over work between arms."""

    def base_velocity(self) -> np.ndarray:
        """The base velocity ``(vx, vy, wz)`` (base frame) to command with this step's arm
        targets, for a robot on a mobile base (appended to the action); default: stand still."""
        return np.zeros(MOBILE_OMNI_VEL_DIM)

    def reset(self) -> None:
        for arm in self.arms:
            arm.reset()
        self._q = [self.env.command[joints].copy() for joints, _ in self._slices]
        self.on_reset()

    def __call__(self, observation: Any = None) -> np.ndarray:
        return self.select_action(observation)

    def select_action(self, observation: Any = None) -> np.ndarray:
        """Next action in the env's action mode (the observation itself is not needed)."""
        self.coordinate()
        return self.assemble([arm.arm_target() for arm in self.arms])  # type: ignore[attr-defined]

    def assemble(self, targets: Sequence[tuple[np.ndarray, float]]) -> np.ndarray:
        """The action of per-arm ``(pose in the arm's root frame (7,), gripper)`` targets."""
        poses = [np.asarray(pose, dtype=np.float64) for pose, _ in targets]
        grippers = [float(gripper) for _, gripper in targets]
        mode = self.env.action_mode
        if mode == "joint":
            parts = []
            for i, (pose, gripper) in enumerate(zip(poses, grippers, strict=True)):
                self._q[i] = self.sim.ik(i, pose, self._q[i])
                parts.append(np.append(self._q[i], gripper))
            action = np.concatenate(parts)
        elif mode == "eef_abs":
            action = np.concatenate([*map(pose_to_policy, poses), grippers])
        else:  # eef_rel: relative to the last command's eef pose of each arm
            current = self.env.command_eef_pose.reshape(len(poses), POSE_DIM)
            rel = [relative_pose(c, p) for c, p in zip(current, poses, strict=True)]
            action = np.concatenate([*rel, grippers])
        if self.env.robot.base is not None:
            action = np.concatenate([action, self.base_velocity()])
        return action.astype(np.float32)

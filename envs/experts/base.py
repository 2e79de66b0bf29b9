"""Scripted experts: privileged policies that drive the tool along task waypoints.

An expert is called like any policy, ``action = expert(observation)``, and emits actions in the
env's action mode, so its rollouts can be recorded or evaluated like a learned policy. It reads
object poses from the simulator (privileged information a learned policy does not get).

Control: a reference point moves towards the current waypoint at bounded speed; an integral
term on the measured tool position cancels the steady-state sag of RMB's position-controlled
joints (no gravity compensation, as in RMB); IK turns the corrected tool pose into joint
targets.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any

import numpy as np
from rmb_lerobot.envs.base import RmbEnv
from scipy.spatial.transform import Rotation

from rmb_lerobot.pose import pose_to_policy, relative_pose


def top_down_rotation(across: np.ndarray, current: Rotation) -> Rotation:
    """Gripper pointing down with the fingers (the eef x axis) closing along the horizontal
    direction ``across``; of the two such orientations, the one nearer the ``current`` hand."""
    across = np.array([across[0], across[1], 0.0])
    across /= np.linalg.norm(across)
    if across @ current.apply([1.0, 0.0, 0.0]) < 0:
        across = -across
    down = np.array([0.0, 0.0, -1.0])
    return Rotation.from_matrix(np.column_stack([across, np.cross(down, across), down]))


@dataclass(frozen=True)
class Waypoint:
    """Where the tool point should go (world frame), the eef orientation, the gripper command."""

    pos: np.ndarray
    rot: Rotation
    gripper: float


class ScriptedExpert(ABC):
    """Base of the per-task experts: waypoint tracking with integral correction and IK.

    Subclasses define the tool point (:meth:`tool_offset` in the eef frame and its measured
    world position :meth:`measured_tool`) and the current :meth:`waypoint` (a small state
    machine over the task's phases). Call :meth:`reset` after every ``env.reset``.
    """

    def __init__(
        self,
        env: Any,
        *,
        max_speed: float = 0.15,
        max_angular_speed: float = 1.0,
        integral_gain: float = 0.3,
        max_correction: float = 0.05,
    ):
        self.env: RmbEnv = env.unwrapped
        self.kin = self.env.kinematics
        self.dt = self.env.control_dt
        self.max_step = max_speed * self.dt
        self.max_angle_step = max_angular_speed * self.dt
        self.integral_gain = integral_gain
        self.max_correction = max_correction
        self._ref_pos = np.zeros(3)
        self._ref_rot = Rotation.identity()
        self._correction = np.zeros(3)
        self._q = self.env.home_command[:-1].copy()

    # ------------------------------------------------------------------ task hooks
    @abstractmethod
    def tool_offset(self) -> np.ndarray:
        """Tool point in the eef-site frame (3,)."""

    @abstractmethod
    def measured_tool(self) -> np.ndarray:
        """Measured world position of the tool point (3,)."""

    @abstractmethod
    def waypoint(self) -> Waypoint:
        """The current target; may advance the expert's phase."""

    def on_reset(self) -> None:  # noqa: B027 - optional hook
        """Task-specific reset (called once the env state is known)."""

    # ------------------------------------------------------------------ helpers
    def eef_world(self) -> tuple[np.ndarray, Rotation]:
        """Measured eef-site position and orientation in the world frame."""
        site = self.env.data.site(self.env.robot.eef_site)
        return site.xpos.copy(), Rotation.from_matrix(site.xmat.reshape(3, 3))

    def reached(self, target: np.ndarray, tol: float, xy_only: bool = False) -> bool:
        """Whether both the reference and the measured tool are within ``tol`` of ``target``."""
        dims = slice(0, 2) if xy_only else slice(0, 3)
        ref_err = np.linalg.norm(self._ref_pos[dims] - target[dims])
        meas_err = np.linalg.norm(self.measured_tool()[dims] - target[dims])
        return bool(ref_err < tol and meas_err < tol)

    # ------------------------------------------------------------------ policy API
    def reset(self) -> None:
        self.on_reset()
        _, rot = self.eef_world()
        self._ref_pos = self.measured_tool()
        self._ref_rot = rot
        self._correction = np.zeros(3)
        self._q = self.env.command[:-1].copy()

    def __call__(self, observation: Any = None) -> np.ndarray:
        return self.select_action(observation)

    def select_action(self, observation: Any = None) -> np.ndarray:
        """Next action in the env's action mode (the observation itself is not needed)."""
        wp = self.waypoint()
        delta = wp.pos - self._ref_pos
        dist = np.linalg.norm(delta)
        self._ref_pos = self._ref_pos + (
            delta if dist <= self.max_step else delta * (self.max_step / dist)
        )
        rot_err = (wp.rot * self._ref_rot.inv()).as_rotvec()
        angle = np.linalg.norm(rot_err)
        if angle > self.max_angle_step:
            rot_err *= self.max_angle_step / angle
        self._ref_rot = Rotation.from_rotvec(rot_err) * self._ref_rot

        self._correction += self.integral_gain * (self._ref_pos - self.measured_tool())
        norm = np.linalg.norm(self._correction)
        if norm > self.max_correction:
            self._correction *= self.max_correction / norm
        eef_pos = self._ref_pos + self._correction - self._ref_rot.apply(self.tool_offset())
        pose = self.kin.world_to_root(eef_pos, self._ref_rot.as_matrix())
        return self._action(pose, wp.gripper)

    def _action(self, pose: np.ndarray, gripper: float) -> np.ndarray:
        mode = self.env.action_mode
        if mode == "joint":
            self._q = self.kin.ik(pose, self._q).qpos
            action = np.append(self._q, gripper)
        elif mode == "eef_abs":
            action = np.append(pose_to_policy(pose), gripper)
        else:
            action = np.append(relative_pose(self.env.command_eef_pose, pose), gripper)
        return action.astype(np.float32)

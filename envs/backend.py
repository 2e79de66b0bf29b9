"""The backend interface: what the env core needs from a simulator (or a real robot).

A backend owns the world of one env: it builds the scene (robot, workspace, the task's props),
resets it, applies joint commands, advances one control period, reads joint positions,
velocities and wrenches, renders cameras (RGB + depth + fovy), does forward and inverse
kinematics of each arm, and reports poses of named things for tasks' success tests and the
scripted experts. :class:`rmb_lerobot.envs.base.RmbEnv` (the env core) does everything else
(gymnasium API, reset options, action modes, observations, RMB recording) the same for every
backend. :class:`rmb_lerobot.envs.mujoco.backend.MujocoBackend` is the first implementation.

Joint vectors are RMB's (per arm: arm joints, then the gripper value in command units;
:meth:`~rmb_lerobot.envs.robots.Robot.joint_slices`). Poses are RMB's ``(x, y, z, qw, qx, qy,
qz)`` in an arm's root frame unless a method says world frame.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from rmb_lerobot.envs.robots import Robot
from rmb_lerobot.envs.workspace import Workspace

if TYPE_CHECKING:
    from rmb_lerobot.envs.tasks.base import Task


class SceneState(ABC):
    """Read-only, simulator-neutral view of the world: what success tests and experts read.

    Names are those the task gave its objects when it built them.
    """

    @abstractmethod
    def body_pose(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """World position (3,) and rotation matrix (3, 3) of a body (copies)."""

    @abstractmethod
    def geom_pose(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """World position (3,) and rotation matrix (3, 3) of a collision/visual shape."""

    @abstractmethod
    def site_pose(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """World position (3,) and rotation matrix (3, 3) of a frame marker (site)."""

    @abstractmethod
    def joint_position(self, name: str) -> np.ndarray:
        """Position coordinates of a (prop's) joint: (1,) for a hinge or slide."""

    @abstractmethod
    def joint_velocity(self, name: str) -> np.ndarray:
        """Velocity coordinates of a (prop's) joint: (6,) for a free joint (linear velocity in
        the world frame, then angular velocity)."""

    @abstractmethod
    def body_positions(self, names: Sequence[str]) -> np.ndarray:
        """World positions (n, 3) of several bodies (e.g. granular particles)."""

    @abstractmethod
    def points(self, name: str) -> np.ndarray:
        """World positions (n, 3) of a deformable object's points (cable, cloth, ring)."""


class Backend(SceneState):
    """One simulated or real world behind the env core.

    Attributes every backend sets: ``robot`` (the record), ``workspace``, ``task``,
    ``cameras`` (every camera it can render, RMB names), ``control_dt`` (seconds per step).
    """

    robot: Robot
    workspace: Workspace
    task: Task
    cameras: tuple[str, ...]
    control_dt: float

    # ---------------------------------------------------------------- episode
    @abstractmethod
    def reset(self, world_offset: np.ndarray, home: np.ndarray) -> None:
        """Start an episode: the task's objects shifted by ``world_offset`` (world frame),
        the robot at joint vector ``home`` and commanded to stay there."""

    @abstractmethod
    def apply_command(self, command: np.ndarray) -> None:
        """Command joint targets (a joint vector); takes effect in :meth:`step`."""

    @abstractmethod
    def step(self) -> None:
        """Advance one control period (``control_dt``)."""

    @property
    @abstractmethod
    def time(self) -> float:
        """Seconds since the episode started."""

    # ---------------------------------------------------------------- measurements
    @abstractmethod
    def joint_limits(self) -> tuple[tuple[np.ndarray, np.ndarray], ...]:
        """Per arm ``(lower, upper)`` of its arm joints (``-inf``/``inf`` where unlimited)."""

    @abstractmethod
    def measured_joint_pos(self) -> np.ndarray:
        """Measured joint vector (grippers in command units, as RMB records them)."""

    @abstractmethod
    def measured_joint_vel(self) -> np.ndarray:
        """Measured joint velocities, 0 for the grippers (RMB records none)."""

    @abstractmethod
    def measured_wrench(self) -> np.ndarray:
        """Per arm the wrist force/torque (fx, fy, fz, nx, ny, nz) in the sensor frame."""

    def tactile(self) -> dict[str, np.ndarray]:
        """Tactile grids by RMB key (e.g. ``left_tactile_sensor``: ``(5, 8)`` normal forces in
        N); empty unless the backend was built with tactile sensing."""
        return {}

    # ---------------------------------------------------------------- cameras
    @abstractmethod
    def render(
        self, cameras: Sequence[str], *, rgb: bool = True, depth: bool = False
    ) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
        """``(rgb, depth)`` by camera: ``uint8 (H, W, 3)`` and ``float32 (H, W)`` metres."""

    @abstractmethod
    def fovy(self, camera: str) -> float:
        """Vertical field of view of a camera in degrees (RMB's only stored intrinsic)."""

    def camera_pose(self, camera: str) -> np.ndarray | None:
        """4x4 world-from-camera pose (metres, OpenCV axes: x right, y down, z forward) of a
        camera fixed to the world; None for a camera that moves (on the robot) or when the
        backend cannot tell."""
        return None

    # ---------------------------------------------------------------- kinematics
    @abstractmethod
    def fk(self, arm: int, q_arm: np.ndarray) -> np.ndarray:
        """Eef pose (7,) of arm ``arm`` at joint angles ``q_arm`` (extra entries ignored)."""

    @abstractmethod
    def ik(self, arm: int, target: np.ndarray, q_init: np.ndarray) -> np.ndarray:
        """Arm joint angles that put the eef of arm ``arm`` at ``target`` (7,), from
        ``q_init``; the closest reachable solution when ``target`` is out of reach."""

    @abstractmethod
    def world_to_root(self, arm: int, pos: np.ndarray, rot: np.ndarray) -> np.ndarray:
        """A world position (3,) and rotation matrix (3, 3) as a pose in the arm's root frame."""

    def close(self) -> None:
        """Free rendering contexts, connections."""

"""The backend interface: what the env core needs from a simulator (or a real robot).

A backend owns the world of one env: it builds the scene (robot, workspace, the task's props),
resets it, applies joint commands, advances one control period, reads joint positions,
velocities and wrenches, renders cameras (RGB + depth + fovy), does forward and inverse
kinematics of each arm, and, where it can, offers a scene view
(:class:`~rmb_lerobot.envs.scene.SceneState`: poses of named things for tasks' success tests
and the scripted experts). :class:`rmb_lerobot.envs.base.RmbEnv` (the env core) does everything else
(gymnasium API, reset options, action modes, observations, RMB recording) the same for every
backend. :class:`rmb_lerobot.envs.mujoco.backend.MujocoBackend` and
:class:`rmb_lerobot.envs.pybullet.backend.PybulletBackend` implement it; the registry
(:mod:`rmb_lerobot.envs.registry`) names each env's backend and builds it.

Joint vectors are RMB's (per arm: arm joints, then the gripper value in command units;
:meth:`~rmb_lerobot.envs.robots.Robot.joint_slices`). Poses are RMB's ``(x, y, z, qw, qx, qy,
qz)`` in an arm's root frame unless a method says world frame.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from rmb_lerobot.envs.robots import Robot
from rmb_lerobot.envs.scene import SceneState
from rmb_lerobot.envs.workspace import Workspace

if TYPE_CHECKING:
    from rmb_lerobot.envs.tasks.base import Task


class Backend(ABC):
    """One simulated or real world behind the env core: robot I/O, cameras, timing, and an
    optional scene view.

    Attributes every backend sets: ``robot`` (the record), ``workspace``, ``task``,
    ``cameras`` (every camera it can render, RMB names), ``image_size`` (``(width, height)``
    of rendered images), ``control_dt`` (seconds per step: the env's frame rate follows it).
    """

    simulator: ClassVar[str]  # key of rmb_lerobot.envs.simulators.SIMULATORS
    robot: Robot
    workspace: Workspace
    task: Task
    cameras: tuple[str, ...]
    image_size: tuple[int, int]
    control_dt: float
    tactile_sensors: tuple[str, ...] = ()  # RMB's rgb_tactile_names (fingertip images)

    @property
    def scene(self) -> SceneState | None:
        """The world as success tests and scripted experts read it; None where nothing can be
        read (a real arm: no success test, no privileged expert)."""
        return None

    # ---------------------------------------------------------------- episode
    def seed(self, rng: np.random.Generator) -> None:  # noqa: B027 - optional hook
        """Called with the env's generator before every :meth:`reset`: a backend that draws
        random numbers (sensor noise) seeds its own generator from it; others ignore it."""

    @abstractmethod
    def reset(self, world_offset: np.ndarray, home: np.ndarray) -> None:
        """Start an episode: the task's objects shifted by ``world_offset`` (world frame),
        the robot at joint vector ``home`` and commanded to stay there (``home`` is a
        command: for a robot on a mobile base it ends with a zero base velocity)."""

    @abstractmethod
    def apply_command(self, command: np.ndarray) -> None:
        """Command joint targets (a joint vector; for a robot on a mobile base followed by
        the base velocity ``(vx, vy, wz)`` in the base frame); takes effect in :meth:`step`."""

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

    def measured_base_velocity(self) -> np.ndarray:
        """The mobile base's velocity ``(vx, vy, wz)`` in its own frame (RMB's
        ``measured_mobile_omni_vel``); asked only of backends whose robot has a base.

        Raises:
            NotImplementedError: this backend drives no mobile base.
        """
        raise NotImplementedError(
            f"{type(self).__name__} drives no mobile base, but robot {self.robot.name!r} has one"
        )

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

    def image_shape(self, camera: str) -> tuple[int, int]:
        """``(height, width)`` of a camera's or tactile sensor's images."""
        width, height = self.image_size
        return height, width

    def render_tactile(self, sensors: Sequence[str]) -> dict[str, np.ndarray]:
        """RGB images ``uint8 (H, W, 3)`` of fingertip tactile sensors (:attr:`tactile_sensors`).

        Raises:
            ValueError: a name that is not one of this backend's tactile sensors.
        """
        unknown = [s for s in sensors if s not in self.tactile_sensors]
        if unknown:
            raise ValueError(
                f"unknown tactile sensors {unknown}; available: {list(self.tactile_sensors)}"
            )
        return {}

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

    def close(self) -> None:  # noqa: B027 - optional: not every backend holds resources
        """Free rendering contexts, connections."""

"""The smallest complete backend: a point arm in plain numpy, for tests and as a template.

A point arm's three joints are its tip's position (``x, y, z``) in the arm's root frame; a
one-joint gripper follows. :class:`PointArmBackend` implements every method of
:class:`~rmb_lerobot.envs.backend.Backend` without a simulator (joints reach their command in
one step, images are blank), and :class:`PointScene` answers a task's questions from the point
poses the backend lists (:meth:`PointArmBackend.poses`). A test world subclasses them to add what
it is about (a camera that paints the joints, a mobile base, a box the gripper carries): the
env core, the recorder, the converters and the experts run on it unchanged, which is how the
core is shown not to assume MuJoCo. Nothing here imports a simulator.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar

import numpy as np

from rmb_lerobot.envs.backend import Backend
from rmb_lerobot.envs.robots import Arm, BodyCamera, Gripper, MobileBase, Pose, Robot
from rmb_lerobot.envs.scene import SceneState
from rmb_lerobot.envs.tasks.base import Task

TIP = "tip"


def point_arm_robot(
    name: str,
    *,
    home: tuple[float, float, float],
    root_frame: str = "base",
    tip: str = TIP,
    base: MobileBase | None = None,
    body_cameras: tuple[BodyCamera, ...] = (),
) -> Robot:
    """A robot of one point arm (joints ``x, y, z``, gripper ``finger`` 0 open .. 1 closed).

    Args:
        name: The robot's name; RMB's spelling is its capitalised form (``point`` ->
            ``Point``, so episodes say ``MujocoPointReachEnv``).
        home: The tip's home position in the root frame.
        root_frame: The frame the joints are positions in.
        tip: The name of the tip (end effector, tool centre point and hand frame at once).
        base: A mobile base the arm stands on, if any.
        body_cameras: Cameras the robot carries off its hand (a head camera).

    Returns:
        The robot record.
    """
    arm = Arm(
        name="arm",
        joints=("x", "y", "z"),
        home=home,
        gripper=Gripper(joints=("finger",), open=0.0, closed=1.0, measured_scale=1.0),
        mount=Pose(),
        root_frame=root_frame,
        eef_frame=tip,
        tcp_frame=tip,
        hand_frame=tip,
    )
    rmb_name = "".join(part.capitalize() for part in name.split("_"))
    return Robot(name=name, rmb_name=rmb_name, arms=(arm,), base=base, body_cameras=body_cameras)


class PointScene(SceneState):
    """Bodies, sites and geoms are the points the backend lists; it has no joints or meshes."""

    def __init__(self, backend: PointArmBackend) -> None:
        self.backend = backend

    def body_pose(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        poses = self.backend.poses()
        if name not in poses:
            raise KeyError(name)
        position, rotation = poses[name]
        return np.array(position, dtype=float), np.array(rotation, dtype=float)

    geom_pose = site_pose = body_pose

    def joint_position(self, name: str) -> np.ndarray:
        raise KeyError(name)

    def joint_velocity(self, name: str) -> np.ndarray:
        raise KeyError(name)

    def body_positions(self, names: Sequence[str]) -> np.ndarray:
        return np.array([self.body_pose(n)[0] for n in names])

    def points(self, name: str) -> np.ndarray:
        raise KeyError(name)


class PointArmBackend(Backend):
    """A point arm whose joints and gripper reach their command in one step.

    Attributes:
        q: The measured joint vector (``x, y, z, finger``).
        target: The last command (joints, then the base velocity when the robot has a base).
        joint_bound: The arm joints' symmetric limit; IK clips to it.
    """

    simulator: ClassVar[str] = "mujoco"  # names only (rmb_env_name); nothing MuJoCo is used
    cameras: tuple[str, ...] = ("front",)
    joint_bound: ClassVar[float] = 1.0
    camera_fovy: ClassVar[float] = 45.0

    def __init__(
        self,
        task: Task,
        robot: Robot,
        *,
        control_dt: float,
        image_size: tuple[int, int] = (8, 6),
    ) -> None:
        self.task, self.robot, self.workspace = task, robot, task.workspace
        self.image_size, self.control_dt = image_size, control_dt
        self.q = np.zeros(4)
        self.target = np.zeros(robot.command_size)
        self.t = 0.0

    @property
    def scene(self) -> SceneState | None:
        return PointScene(self)

    def poses(self) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """World poses (position, rotation matrix) of the points a task may ask for."""
        return {self.robot.arms[0].tcp_frame: (self.q[:3].copy(), np.eye(3))}

    def reset(self, world_offset: np.ndarray, home: np.ndarray) -> None:
        self.q, self.target, self.t = home[:4].copy(), home.copy(), 0.0

    def apply_command(self, command: np.ndarray) -> None:
        self.target = command.copy()

    def step(self) -> None:
        self.q, self.t = self.target[:4].copy(), self.t + self.control_dt

    @property
    def time(self) -> float:
        return self.t

    def joint_limits(self) -> tuple[tuple[np.ndarray, np.ndarray], ...]:
        return ((np.full(3, -self.joint_bound), np.full(3, self.joint_bound)),)

    def measured_joint_pos(self) -> np.ndarray:
        return self.q.copy()

    def measured_joint_vel(self) -> np.ndarray:
        return np.zeros(4)

    def measured_wrench(self) -> np.ndarray:
        return np.zeros(6)

    def render(self, cameras, *, rgb=True, depth=False):
        width, height = self.image_size
        images = {c: np.zeros((height, width, 3), np.uint8) for c in cameras}
        return (images if rgb else {}), {}

    def fovy(self, camera: str) -> float:
        return self.camera_fovy

    def fk(self, arm: int, q_arm: np.ndarray) -> np.ndarray:
        return np.array([*q_arm[:3], 1.0, 0.0, 0.0, 0.0])

    def ik(self, arm: int, target: np.ndarray, q_init: np.ndarray) -> np.ndarray:
        return np.clip(target[:3], -self.joint_bound, self.joint_bound)

    def world_to_root(self, arm: int, pos: np.ndarray, rot: np.ndarray) -> np.ndarray:
        return np.array([*pos, 1.0, 0.0, 0.0, 0.0])

"""The PyBullet backend: RMB's TACTO worlds (Sawyer + WSG50 + DIGIT) behind the env core.

As RMB's ``TactoSawyerEnvBase``: a headless ``p.DIRECT`` client (RMB opens a GUI, which kills a
process without a display) with RMB's physics (0.005 s x 6 substeps = 0.03 s per control step,
200 solver iterations, cone friction), the Sawyer + WSG50 built in code
(:mod:`rmb_lerobot.envs.pybullet.sawyer`) on a floor, position-controlled joints (forces 200 N
arm, 20 N fingers; fingers at ``(-g, +g)``), the wrist wrench from the ``right_hand`` F/T joint,
RMB's "front" camera (RGB + depth linearised as RMB does) and one DIGIT-like RGB image per
fingertip (:mod:`rmb_lerobot.envs.pybullet.tactile`). The task's props come from its PyBullet
scene (:data:`~rmb_lerobot.envs.pybullet.tasks.base.PYBULLET_TASK_SCENES`).

Kinematics: :class:`~rmb_lerobot.envs.pybullet.kinematics.SawyerKinematics` on a private
client (RMB's eef, ``right_l6``, in the robot's root frame, as every backend reports it).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, ClassVar

import numpy as np
import pybullet as p

from rmb_lerobot.envs.backend import Backend
from rmb_lerobot.envs.pybullet.camera import (
    FRONT_CAMERA,
    SPOON_FRONT_CAMERA,
    CameraSpec,
    opencv_pose,
    render,
)
from rmb_lerobot.envs.pybullet.client import PhysicsSettings, connect
from rmb_lerobot.envs.pybullet.kinematics import SawyerKinematics, quat_xyzw_to_wxyz
from rmb_lerobot.envs.pybullet.options import PybulletOptions
from rmb_lerobot.envs.pybullet.sawyer import (
    PAD_CENTRE,
    PAD_NORMAL,
    TOOL_CENTRE_IN_EEF,
    apply_position_targets,
    link_indices_by_name,
    load_sawyer_wsg50,
    reset_joints,
)
from rmb_lerobot.envs.pybullet.tactile import PadSpec, TactilePads
from rmb_lerobot.envs.pybullet.tasks.base import pybullet_scene_for
from rmb_lerobot.envs.robots import Robot
from rmb_lerobot.envs.scene import SceneState
from rmb_lerobot.envs.sensors.digit import DigitConfig
from rmb_lerobot.envs.workspace import Workspace

if TYPE_CHECKING:
    from rmb_lerobot.envs.tasks.base import Task

# RMB's cameras of each TACTO scene, as PyBullet's orbit parameters; the workspace records name
# the same cameras (checked in tests/envs/pybullet/test_backend.py).
CAMERAS: dict[str, tuple[CameraSpec, ...]] = {
    "tacto_floor": (FRONT_CAMERA,),
    "tacto_spoon_floor": (SPOON_FRONT_CAMERA,),
}
"""Workspace name -> its cameras for PyBullet."""

PYBULLET_ROBOTS = ("sawyer",)
"""Robots PyBullet builds (RMB's TACTO envs have one)."""

# Frames the robot record names that are not links: (link, offset in the link frame).
_VIRTUAL_FRAMES = {"tool_centre": ("right_l6", TOOL_CENTRE_IN_EEF)}


class PybulletBackend(Backend):
    """One PyBullet world: the Sawyer, the floor, the task's props, the DIGIT sensors.

    Args:
        task: The neutral task; its PyBullet scene builder comes from
            :data:`~rmb_lerobot.envs.pybullet.tasks.base.PYBULLET_TASK_SCENES`.
        robot: The robot record (the Sawyer).
        workspace: The floor and its cameras (:data:`CAMERAS` has their PyBullet views).
        options: Images and renderer (:class:`PybulletOptions`).

    Raises:
        ValueError: a robot or workspace PyBullet does not build, or a task without a scene.
    """

    simulator: ClassVar[str] = "pybullet"

    def __init__(
        self,
        task: Task,
        robot: Robot,
        workspace: Workspace,
        options: PybulletOptions | None = None,
    ):
        if robot.name not in PYBULLET_ROBOTS:
            raise ValueError(f"PyBullet builds robots {PYBULLET_ROBOTS}, not {robot.name!r}")
        if workspace.name not in CAMERAS:
            raise ValueError(
                f"PyBullet has no scene for workspace {workspace.name!r}; known: {sorted(CAMERAS)}"
            )
        self.options = PybulletOptions() if options is None else options
        self.task, self.robot, self.workspace = task, robot, workspace
        self.task_scene = pybullet_scene_for(task)
        self.image_size = self.options.image_size
        self._cameras = {spec.name: spec for spec in CAMERAS[workspace.name]}
        self.cameras = tuple(self._cameras)
        self.tactile_sensors = robot.tactile_sensors
        self._client = connect(PhysicsSettings(), renderer=self.options.renderer)
        try:
            self._build()
        except BaseException:
            self.close()
            raise

    def _build(self) -> None:
        cid = self._client.client_id
        self.control_dt = self._client.settings.control_dt
        self.ground = p.loadURDF("plane.urdf", physicsClientId=cid)
        self.handles = load_sawyer_wsg50(cid)
        self._links = link_indices_by_name(self.handles.body_id, cid)
        self._bodies: dict[str, int] = {}
        self._tactile_bodies: set[int] = set()
        self.task_scene.build(self)
        self.kinematics = SawyerKinematics(root_position=self.handles.root_position)
        (arm,) = self.robot.arms
        self._grip_signs = np.asarray(arm.gripper.signs)
        width, height = self.options.tactile_size
        pads = [
            PadSpec(link, PAD_CENTRE, PAD_NORMAL, (0.0, 0.0, 1.0))
            for link in self.handles.fingertip_links
        ]
        self._pads = TactilePads(
            cid,
            self.handles.body_id,
            pads,
            self._tactile_bodies,
            DigitConfig(height=height, width=width),
        )
        self._rng = np.random.default_rng(0)
        self._time = 0.0
        self._scene = PybulletScene(self)

    # ---------------------------------------------------------------- scene construction
    @property
    def client_id(self) -> int:
        """PyBullet's ``physicsClientId`` of this world (for task scenes and tests)."""
        return self._client.client_id

    def add_body(self, name: str, body: int, *, tactile: bool = False) -> None:
        """Name a task's body (success tests and experts find it by name); ``tactile``: the
        fingertip sensors see it (RMB's ``rgb_tactiles.add_body``)."""
        if name in self._bodies:
            raise ValueError(f"a body named {name!r} exists already")
        self._bodies[name] = body
        if tactile:
            self._tactile_bodies.add(body)

    def body_id(self, name: str) -> int:
        """The body id of a named task body.

        Raises:
            KeyError: no body of that name (the error names the known ones).
        """
        try:
            return self._bodies[name]
        except KeyError:
            raise KeyError(f"no body named {name!r}; known: {sorted(self._bodies)}") from None

    def reset_body(
        self, name: str, position: Sequence[float], quat_wxyz: Sequence[float] = (1, 0, 0, 0)
    ) -> None:
        """Place a named body at rest (world frame; quaternion ``(w, x, y, z)``)."""
        w, x, y, z = (float(v) for v in quat_wxyz)
        body = self.body_id(name)
        p.resetBasePositionAndOrientation(
            body, list(map(float, position)), [x, y, z, w], physicsClientId=self.client_id
        )
        p.resetBaseVelocity(body, [0, 0, 0], [0, 0, 0], physicsClientId=self.client_id)

    # ---------------------------------------------------------------- episode
    def seed(self, rng: np.random.Generator) -> None:
        """Tactile sensor noise comes from a generator seeded from the env's."""
        self._rng = np.random.default_rng(rng.integers(2**63))

    def reset(self, world_offset: np.ndarray, home: np.ndarray) -> None:
        ((arm, grip),) = self.robot.joint_slices()
        reset_joints(self.client_id, self.handles, home[arm], float(home[grip]))
        self.apply_command(home)
        self.task_scene.apply_world(self, np.asarray(world_offset, dtype=np.float64))
        self._time = 0.0

    def apply_command(self, command: np.ndarray) -> None:
        ((arm, grip),) = self.robot.joint_slices()
        apply_position_targets(self.client_id, self.handles, command[arm], float(command[grip]))

    def step(self) -> None:
        self._client.step_control()
        self._time += self.control_dt

    @property
    def time(self) -> float:
        return self._time

    # ---------------------------------------------------------------- measurements
    def joint_limits(self) -> tuple[tuple[np.ndarray, np.ndarray], ...]:
        return ((self.handles.arm_lower.copy(), self.handles.arm_upper.copy()),)

    def _joint_states(self, joints: Sequence[int]) -> list[tuple]:
        return p.getJointStates(self.handles.body_id, list(joints), physicsClientId=self.client_id)

    def measured_joint_pos(self) -> np.ndarray:
        arm = [s[0] for s in self._joint_states(self.handles.arm_joints)]
        fingers = np.array([s[0] for s in self._joint_states(self.handles.finger_joints)])
        return np.array([*arm, float(np.mean(self._grip_signs * fingers))])

    def measured_joint_vel(self) -> np.ndarray:
        return np.array([*(s[1] for s in self._joint_states(self.handles.arm_joints)), 0.0])

    def measured_wrench(self) -> np.ndarray:
        (state,) = self._joint_states([self.handles.ft_joint])
        return np.asarray(state[2], dtype=np.float64)

    # ---------------------------------------------------------------- cameras
    def _spec(self, camera: str) -> CameraSpec:
        if camera not in self._cameras:
            raise ValueError(f"unknown camera {camera!r}; available: {self.cameras}")
        return self._cameras[camera]

    def render(
        self, cameras: Sequence[str], *, rgb: bool = True, depth: bool = False
    ) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
        width, height = self.image_size
        rgb_out, depth_out = {}, {}
        for camera in cameras:
            image, depth_m = render(
                self._client,
                self._spec(camera),
                width,
                height,
                rgb=rgb,
                depth=depth,
                shadow=self.options.shadows,
            )
            if image is not None:
                rgb_out[camera] = image
            if depth_m is not None:
                depth_out[camera] = depth_m
        return rgb_out, depth_out

    def fovy(self, camera: str) -> float:
        return float(self._spec(camera).fovy)

    def camera_pose(self, camera: str) -> np.ndarray | None:
        return opencv_pose(self._spec(camera))

    def image_shape(self, camera: str) -> tuple[int, int]:
        if camera in self.tactile_sensors:
            width, height = self.options.tactile_size
            return height, width
        return super().image_shape(camera)

    def render_tactile(self, sensors: Sequence[str]) -> dict[str, np.ndarray]:
        super().render_tactile(sensors)  # checks the names
        rng = self._rng if self.options.tactile_noise else None
        images = dict(zip(self.tactile_sensors, self._pads.render(rng), strict=True))
        return {name: images[name] for name in sensors}

    # ---------------------------------------------------------------- kinematics
    def fk(self, arm: int, q_arm: np.ndarray) -> np.ndarray:
        return self.kinematics.fk(q_arm)

    def ik(self, arm: int, target: np.ndarray, q_init: np.ndarray) -> np.ndarray:
        return self.kinematics.ik(target, q_init)

    def world_to_root(self, arm: int, pos: np.ndarray, rot: np.ndarray) -> np.ndarray:
        return self.kinematics.world_to_root(pos, rot)

    # ---------------------------------------------------------------- scene
    @property
    def scene(self) -> SceneState:
        return self._scene

    def link_pose(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """World position and rotation matrix of a robot link frame or virtual frame."""
        if name == self.robot.arms[0].root_frame:  # the base link: no link state
            return np.asarray(self.handles.root_position, dtype=np.float64), np.eye(3)
        link, offset = _VIRTUAL_FRAMES.get(name, (name, (0.0, 0.0, 0.0)))
        if link not in self._links:
            raise KeyError(f"the robot has no link or frame {name!r}")
        state = p.getLinkState(
            self.handles.body_id,
            self._links[link],
            computeForwardKinematics=True,
            physicsClientId=self.client_id,
        )
        rot = np.array(p.getMatrixFromQuaternion(state[5])).reshape(3, 3)
        return np.asarray(state[4]) + rot @ np.asarray(offset), rot

    def close(self) -> None:
        kinematics = getattr(self, "kinematics", None)
        if kinematics is not None:
            kinematics.close()
        self._client.close()


class PybulletScene(SceneState):
    """What success tests and experts read of a PyBullet world: named task bodies (their base
    frames) and the robot's links (as frames, ``site_pose``)."""

    def __init__(self, backend: PybulletBackend) -> None:
        self.backend = backend

    def body_pose(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        position, quat = p.getBasePositionAndOrientation(
            self.backend.body_id(name), physicsClientId=self.backend.client_id
        )
        return np.asarray(position), np.array(p.getMatrixFromQuaternion(quat)).reshape(3, 3)

    def geom_pose(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """A task body's pose (each prop is one rigid body here)."""
        return self.body_pose(name)

    def site_pose(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """A robot link's frame (or the record's ``tool_centre``) in the world."""
        return self.backend.link_pose(name)

    def joint_position(self, name: str) -> np.ndarray:
        """A free body's position and ``(w, x, y, z)`` quaternion (7,), as a free joint's."""
        position, quat = p.getBasePositionAndOrientation(
            self.backend.body_id(name), physicsClientId=self.backend.client_id
        )
        return np.array([*position, *quat_xyzw_to_wxyz(quat)])

    def joint_velocity(self, name: str) -> np.ndarray:
        """A free body's linear (world frame) then angular velocity (6,)."""
        linear, angular = p.getBaseVelocity(
            self.backend.body_id(name), physicsClientId=self.backend.client_id
        )
        return np.array([*linear, *angular])

    def body_positions(self, names: Sequence[str]) -> np.ndarray:
        return np.array([self.body_pose(name)[0] for name in names])

    def points(self, name: str) -> np.ndarray:
        raise ValueError(f"no deformable named {name!r}: the PyBullet scenes have rigid bodies")

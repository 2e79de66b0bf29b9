"""The MuJoCo backend: RMB's MuJoCo worlds behind the simulator-neutral env core.

Builds the scene from records (the robot's MuJoCo model, :mod:`rmb_lerobot.envs.mujoco.robots`;
the workspace, :mod:`rmb_lerobot.envs.mujoco.scene`; the task's props, its MuJoCo scene in
:mod:`rmb_lerobot.envs.mujoco.tasks`), and steps it as RMB does: timestep 0.004 s,
``frame_skip`` 8 (31.25 Hz), position-controlled joints. Forward/inverse kinematics are
:class:`~rmb_lerobot.envs.mujoco.kinematics.ArmKinematics` on the model, one per arm.

MuJoCo-specific on purpose, for the tasks' MuJoCo hooks and tests: :attr:`model`,
:attr:`data`, :attr:`robot_model` (the MuJoCo names of each arm) and :attr:`kinematics`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from rmb_lerobot.envs.backend import Backend
from rmb_lerobot.envs.mujoco.kinematics import ArmKinematics
from rmb_lerobot.envs.mujoco.mobile_base import MobileBaseDrive, pose_in_body
from rmb_lerobot.envs.mujoco.options import MujocoOptions
from rmb_lerobot.envs.mujoco.render import MultiCameraRenderer, mujoco
from rmb_lerobot.envs.mujoco.robots import build_robot_model, check_model
from rmb_lerobot.envs.mujoco.scene import build_scene
from rmb_lerobot.envs.mujoco.tasks.base import mujoco_scene_for
from rmb_lerobot.envs.robots import Robot
from rmb_lerobot.envs.scene import SceneState
from rmb_lerobot.envs.sensors.tactile import TactileGrid, add_pad_sites, pads_for
from rmb_lerobot.envs.workspace import Workspace
from rmb_lerobot.pointcloud import opencv_camera_pose

if TYPE_CHECKING:
    from rmb_lerobot.envs.tasks.base import Task


class MujocoBackend(Backend, SceneState):
    """One MuJoCo world: the robot record's model, the workspace and the task's props.

    Its own scene view (:attr:`scene` is itself): bodies, geoms, sites, joints and flexes by the
    names the task's MuJoCo scene gave them.

    Args:
        task: The neutral task; its MuJoCo scene builder comes from
            :data:`~rmb_lerobot.envs.mujoco.tasks.base.MUJOCO_TASK_SCENES`.
        robot: The robot record (its MuJoCo model comes from
            :data:`~rmb_lerobot.envs.mujoco.robots.MUJOCO_BUILDERS`).
        workspace: The table and fixed cameras of the scene.
        options: How to build, step and render (:class:`MujocoOptions`).
    """

    simulator: ClassVar[str] = "mujoco"

    def __init__(
        self,
        task: Task,
        robot: Robot,
        workspace: Workspace,
        options: MujocoOptions | None = None,
    ):
        options = MujocoOptions() if options is None else options
        self.options = options
        image_size = options.image_size
        self.task = task
        self.robot = robot
        self.workspace = workspace
        self.frame_skip = int(options.frame_skip)
        self.image_size = image_size
        self._render_flags = {
            "shadows": options.shadows,
            "reflections": options.reflections,
            "antialias": options.antialias,
        }
        self.robot_model = build_robot_model(robot, visual_mesh_error=options.visual_mesh_error)
        spec = build_scene(self.robot_model, workspace, max_render_size=image_size)
        pads = pads_for(robot.name) if options.tactile else ()
        add_pad_sites(spec, pads)
        self.task_scene = mujoco_scene_for(task)
        self.task_scene.build(spec, self)
        self.model = spec.compile()
        check_model(robot, self.robot_model, self.model)
        self.data = mujoco.MjData(self.model)
        self._tactile = {pad.key: TactileGrid(self.model, pad.site) for pad in pads}
        self.kinematics = tuple(ArmKinematics(self.model, arm) for arm in self.robot_model.arms)
        self._camera_names = {
            **{c.name: c.name for c in workspace.cameras},
            **self.robot_model.cameras,
        }
        self.cameras = tuple(self._camera_names)
        self.control_dt = self.model.opt.timestep * self.frame_skip

        model, arms = self.model, self.robot_model.arms
        self._arm_qpos = tuple(kin.qpos_index for kin in self.kinematics)
        self._arm_dof = tuple(kin.dof_index for kin in self.kinematics)
        self._arm_act = tuple(
            np.array([model.actuator(a).id for a in m.arm_actuators]) for m in arms
        )
        self._grip_act = tuple(model.actuator(m.gripper_actuator).id for m in arms)
        self._grip_qpos = tuple(
            np.array([model.joint(j).qposadr[0] for j in arm.gripper.joints]) for arm in robot.arms
        )
        self._grip_scale = tuple(arm.gripper.measured_scale for arm in robot.arms)
        self._force_adr = tuple(model.sensor(m.force_sensor).adr[0] for m in arms)
        self._torque_adr = tuple(model.sensor(m.torque_sensor).adr[0] for m in arms)
        self._slices = robot.joint_slices()
        self._base = MobileBaseDrive(model, robot) if robot.base is not None else None
        self._renderer: MultiCameraRenderer | None = None
        self._body_ids: dict[tuple[str, ...], np.ndarray] = {}

    # ---------------------------------------------------------------- episode
    def reset(self, world_offset: np.ndarray, home: np.ndarray) -> None:
        mujoco.mj_resetData(self.model, self.data)
        self.task_scene.apply_world(self, world_offset)
        for qpos, grip_qpos, scale, (arm, g) in zip(
            self._arm_qpos, self._grip_qpos, self._grip_scale, self._slices, strict=True
        ):
            self.data.qpos[qpos] = home[arm]
            # Gripper joints where their measured value (scale * mean) is the start command:
            # the Panda's fingers start open as commanded (RMB's start closed and open in the
            # first steps); the 2F-85's and the xArm gripper's open command is their zero.
            self.data.qpos[grip_qpos] = home[g] / scale
        self.apply_command(home)
        mujoco.mj_kinematics(self.model, self.data)
        self.task_scene.reset_objects(self)
        mujoco.mj_forward(self.model, self.data)

    def apply_command(self, command: np.ndarray) -> None:
        for act, grip, (arm, g) in zip(self._arm_act, self._grip_act, self._slices, strict=True):
            self.data.ctrl[act] = command[arm]
            self.data.ctrl[grip] = command[g]
        if self._base is not None:
            self._base.command(self.data, command[self.robot.base_slice])

    def step(self) -> None:
        mujoco.mj_step(self.model, self.data, nstep=self.frame_skip)

    @property
    def time(self) -> float:
        return float(self.data.time)

    # ---------------------------------------------------------------- measurements
    def joint_limits(self) -> tuple[tuple[np.ndarray, np.ndarray], ...]:
        return tuple((kin.lower, kin.upper) for kin in self.kinematics)

    def _per_arm(self, parts: list[np.ndarray]) -> np.ndarray:
        return parts[0] if len(parts) == 1 else np.concatenate(parts)

    def measured_joint_pos(self) -> np.ndarray:
        qpos = self.data.qpos
        return self._per_arm(
            [
                np.append(qpos[arm], scale * np.mean(qpos[grip]))
                for arm, grip, scale in zip(
                    self._arm_qpos, self._grip_qpos, self._grip_scale, strict=True
                )
            ]
        )

    def measured_joint_vel(self) -> np.ndarray:
        return self._per_arm([np.append(self.data.qvel[dof], 0.0) for dof in self._arm_dof])

    def measured_wrench(self) -> np.ndarray:
        sensordata = self.data.sensordata
        return self._per_arm(
            [
                np.concatenate([sensordata[f : f + 3], sensordata[t : t + 3]])
                for f, t in zip(self._force_adr, self._torque_adr, strict=True)
            ]
        )

    def measured_base_velocity(self) -> np.ndarray:
        if self._base is None:
            return super().measured_base_velocity()
        return self._base.measured(self.data)

    def tactile(self) -> dict[str, np.ndarray]:
        return {key: grid.read(self.data) for key, grid in self._tactile.items()}

    # ---------------------------------------------------------------- cameras
    def _get_renderer(self) -> MultiCameraRenderer:
        if self._renderer is None:
            width, height = self.image_size
            self._renderer = MultiCameraRenderer(self.model, width, height, **self._render_flags)
        return self._renderer

    def _mujoco_camera(self, camera: str) -> str:
        if camera not in self._camera_names:
            raise ValueError(f"unknown camera {camera!r}; available: {self.cameras}")
        return self._camera_names[camera]

    def render(
        self, cameras: Sequence[str], *, rgb: bool = True, depth: bool = False
    ) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
        names = {self._mujoco_camera(c): c for c in cameras}
        rgb_out, depth_out = self._get_renderer().render(
            self.data, list(names), rgb=rgb, depth=depth
        )
        return (
            {names[k]: v for k, v in rgb_out.items()},
            {names[k]: v for k, v in depth_out.items()},
        )

    def fovy(self, camera: str) -> float:
        return float(self.model.camera(self._mujoco_camera(camera)).fovy[0])

    def camera_pose(self, camera: str) -> np.ndarray | None:
        """The pose of a camera that cannot move: fixed mode (no tracking) on a body welded to
        the world (the world body itself or a chain of joint-less, non-mocap bodies)."""
        cam = self.model.camera(self._mujoco_camera(camera))
        if int(cam.mode[0]) != mujoco.mjtCamLight.mjCAMLIGHT_FIXED:
            return None
        body = int(cam.bodyid[0])
        while body != 0:
            if self.model.body_jntnum[body] > 0 or self.model.body_mocapid[body] >= 0:
                return None
            body = int(self.model.body_parentid[body])
        view = self.data.camera(cam.id)
        return opencv_camera_pose(view.xpos, view.xmat)

    # ---------------------------------------------------------------- kinematics
    def fk(self, arm: int, q_arm: np.ndarray) -> np.ndarray:
        return self.kinematics[arm].fk(q_arm)

    def ik(self, arm: int, target: np.ndarray, q_init: np.ndarray) -> np.ndarray:
        return self.kinematics[arm].ik(target, q_init).qpos

    def world_to_root(self, arm: int, pos: np.ndarray, rot: np.ndarray) -> np.ndarray:
        if self._base is None:
            return self.kinematics[arm].world_to_root(pos, rot)
        # On a mobile base the root frame moves: use its current pose, not the model's.
        return pose_in_body(self.data, self.robot.arms[arm].root_frame, pos, rot)

    # ---------------------------------------------------------------- scene state
    @property
    def scene(self) -> SceneState:
        return self

    @staticmethod
    def _pose(view) -> tuple[np.ndarray, np.ndarray]:
        return view.xpos.copy(), view.xmat.reshape(3, 3).copy()

    def body_pose(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        return self._pose(self.data.body(name))

    def geom_pose(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        return self._pose(self.data.geom(name))

    def site_pose(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        return self._pose(self.data.site(name))

    def joint_position(self, name: str) -> np.ndarray:
        return self.data.joint(name).qpos.copy()

    def joint_velocity(self, name: str) -> np.ndarray:
        return self.data.joint(name).qvel.copy()

    def body_positions(self, names: Sequence[str]) -> np.ndarray:
        key = tuple(names)
        if key not in self._body_ids:
            self._body_ids[key] = np.array([self.model.body(name).id for name in key], dtype=int)
        return self.data.xpos[self._body_ids[key]].copy()

    def points(self, name: str) -> np.ndarray:
        """A flex's vertex positions (MuJoCo's deformables: cable, cloth, ring)."""
        flex = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_FLEX, name)
        if flex < 0:
            raise ValueError(f"no deformable (flex) named {name!r} in the model")
        start, count = int(self.model.flex_vertadr[flex]), int(self.model.flex_vertnum[flex])
        return self.data.flexvert_xpos[start : start + count].copy()

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

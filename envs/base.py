"""One gymnasium env for every RMB robot/task combination on MuJoCo.

:class:`RmbEnv` composes a :class:`~rmb_lerobot.envs.mujoco.robot.RobotSpec`, a
:class:`~rmb_lerobot.envs.tasks.base.Task` and the shared scene. Observations follow LeRobot's
env contract (``pixels``, ``agent_pos``, optional ``depth``); everything RMB records (joint,
gripper, end-effector and wrench keys, images) is available to recorders through
:meth:`RmbEnv.rmb_step_data`, which keeps the observation space small.

Control follows RMB: timestep 0.004 s, ``frame_skip`` 8 (31.25 Hz), position-controlled joints.
Action modes: ``joint`` (7 absolute targets: 6 arm joints + gripper 0..255), ``eef_abs``
(absolute eef pose in the robot root frame as the 9 numbers policies use, position + 6-D
rotation, which is what a dataset converted with ``command_eef_pose`` as action holds, + gripper)
and ``eef_rel`` (RMB's relative eef
pose (6) applied to the previous command pose + gripper), the eef modes solved by damped
least-squares IK on the model.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from rmb_lerobot.envs.mujoco.kinematics import ArmKinematics
from rmb_lerobot.envs.mujoco.meshes import DEFAULT_VISUAL_MESH_ERROR
from rmb_lerobot.envs.mujoco.render import MultiCameraRenderer, mujoco
from rmb_lerobot.envs.mujoco.robot import FORCE_SENSOR, TORQUE_SENSOR, UR5E_2F85, RobotSpec
from rmb_lerobot.envs.mujoco.scene import TIMESTEP, build_scene
from rmb_lerobot.envs.tasks.base import Task

from rmb_lerobot import keys as K
from rmb_lerobot.codecs.depth_base import metres_to_mm
from rmb_lerobot.pose import POLICY_POSE_DIM, REL_POSE_DIM, apply_relative_pose, policy_to_pose

ACTION_MODES = ("joint", "eef_abs", "eef_rel")
FRAME_SKIP = 8
DEFAULT_IMAGE_SIZE = (128, 128)
RMB_IMAGE_SIZE = (640, 480)
# Per-step bounds of the eef action spaces (root frame, metres / radians).
EEF_POS_BOUND = 1.5
EEF_REL_POS_BOUND = 0.2
EEF_REL_ROT_BOUND = np.pi


class RmbEnv(gym.Env):
    """RMB task on MuJoCo with a gymnasium API and LeRobot's observation contract.

    Parameters
    ----------
    task:
        The task (props, world variations, success test).
    robot:
        The robot description (default: UR5e + Robotiq 2F-85, as in RMB).
    action_mode:
        ``"joint"`` (default), ``"eef_abs"`` or ``"eef_rel"``.
    cameras:
        Cameras rendered into the observation, any of :attr:`available_cameras`; ``()`` for none
        (fast: physics only). Default: RMB's four.
    image_size:
        ``(width, height)`` of every camera image (RMB records 640x480).
    depth:
        Also render depth: ``observation["depth"]`` (uint16 mm) and float metres for recorders.
    random_shift:
        Default scale (m) of the uniform random object shift added to the world's offset;
        ``reset(options={"random_shift": s})`` overrides it for one episode.
    terminate_on_success:
        End the episode (``terminated``) when the success criterion holds.
    render_camera:
        The camera :meth:`render` shows.
    shadows, reflections:
        MuJoCo's shadow and reflection passes (off: they cost several times a plain render in
        software rendering).
    antialias:
        4x multisampling, as RMB renders (default); ``False`` is about 2x faster at 640x480 in
        software rendering, with aliased edges.
    visual_mesh_error:
        How far (m) the robot's simplified visual meshes may leave the original surface
        (default 0.5 mm: a tenth of the triangles, renders several times faster, looks the same
        at camera resolution); 0 for the original meshes. Collision geometry and physics are
        the same at every setting.
    """

    # RMB reports int(1 / (timestep * frame_skip)) = 31 frames per second.
    metadata: ClassVar[dict[str, Any]] = {
        "render_modes": ["rgb_array"],
        "render_fps": int(1 / (TIMESTEP * FRAME_SKIP)),
    }

    def __init__(
        self,
        task: Task,
        robot: RobotSpec = UR5E_2F85,
        *,
        action_mode: str = "joint",
        cameras: Sequence[str] | None = None,
        image_size: tuple[int, int] = DEFAULT_IMAGE_SIZE,
        depth: bool = False,
        random_shift: float = 0.0,
        terminate_on_success: bool = True,
        render_mode: str | None = "rgb_array",
        render_camera: str = "front",
        frame_skip: int = FRAME_SKIP,
        shadows: bool = False,
        reflections: bool = False,
        antialias: bool = True,
        visual_mesh_error: float = DEFAULT_VISUAL_MESH_ERROR,
    ):
        if action_mode not in ACTION_MODES:
            raise ValueError(f"action_mode must be one of {ACTION_MODES}, got {action_mode!r}")
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        if frame_skip < 1:
            raise ValueError(f"frame_skip must be >= 1, got {frame_skip!r}")
        width, height = (int(v) for v in image_size)
        if width <= 0 or height <= 0:
            raise ValueError(f"image_size must be two positive ints (W, H), got {image_size!r}")
        if random_shift < 0:
            raise ValueError(f"random_shift must be >= 0 metres, got {random_shift!r}")
        self.task = task
        self.robot = robot
        self.action_mode = action_mode
        self.image_size = (width, height)
        self.use_depth = bool(depth)
        self.random_shift = float(random_shift)
        self.terminate_on_success = terminate_on_success
        self.render_mode = render_mode
        self.render_camera = render_camera
        self.frame_skip = int(frame_skip)
        self._render_flags = {
            "shadows": bool(shadows),
            "reflections": bool(reflections),
            "antialias": bool(antialias),
        }

        spec = build_scene(
            robot, max_render_size=(width, height), visual_mesh_error=visual_mesh_error
        )
        task.build(spec, robot)
        self.model = spec.compile()
        self.data = mujoco.MjData(self.model)
        self.kinematics = ArmKinematics(self.model, robot)
        self.available_cameras = tuple(self.model.camera(i).name for i in range(self.model.ncam))
        cameras = self.available_cameras if cameras is None else tuple(cameras)
        for name in (*cameras, *([render_camera] if render_mode else [])):
            if name not in self.available_cameras:
                raise ValueError(f"unknown camera {name!r}; available: {self.available_cameras}")
        self.camera_names = cameras
        self.control_dt = self.model.opt.timestep * self.frame_skip
        self.task_description = task.description
        self._max_episode_steps = task.max_episode_steps

        self._arm_qpos = self.kinematics.qpos_index
        self._arm_dof = self.kinematics.dof_index
        self._arm_act = np.array([self.model.actuator(a).id for a in robot.arm_actuators])
        self._grip_act = self.model.actuator(robot.gripper_actuator).id
        self._grip_range = self.model.actuator_ctrlrange[self._grip_act].copy()
        self._grip_qpos = np.array([self.model.joint(j).qposadr[0] for j in robot.gripper_joints])
        self._force_adr = self.model.sensor(FORCE_SENSOR).adr[0]
        self._torque_adr = self.model.sensor(TORQUE_SENSOR).adr[0]
        home = task.home_arm_qpos if task.home_arm_qpos is not None else robot.home_arm_qpos
        self.home_command = np.array([*home, robot.home_gripper], dtype=np.float64)

        self._renderer: MultiCameraRenderer | None = None
        self.observation_space = self._make_observation_space()
        self.action_space = self._make_action_space()

        self.world_idx = 0
        self.world_offset = np.zeros(3)
        self._command = self.home_command.copy()
        self._prev_command = self.home_command.copy()
        self._command_eef_pose = self.kinematics.fk(self.home_command)
        self._command_cache: tuple[tuple[bytes, bytes], np.ndarray] | None = None
        self._reward = 0.0
        self._success = False
        self._rgb: dict[str, np.ndarray] = {}
        self._depth_m: dict[str, np.ndarray] = {}

    # ------------------------------------------------------------------ spaces
    def _make_observation_space(self) -> gym.spaces.Dict:
        width, height = self.image_size
        n = self.robot.layout.num_joints
        spaces: dict[str, gym.spaces.Space] = {
            "agent_pos": gym.spaces.Box(-np.inf, np.inf, (n,), dtype=np.float32)
        }
        if self.camera_names:
            spaces["pixels"] = gym.spaces.Dict(
                {
                    cam: gym.spaces.Box(0, 255, (height, width, 3), dtype=np.uint8)
                    for cam in self.camera_names
                }
            )
            if self.use_depth:
                spaces["depth"] = gym.spaces.Dict(
                    {
                        cam: gym.spaces.Box(
                            0, np.iinfo(np.uint16).max, (height, width), dtype=np.uint16
                        )
                        for cam in self.camera_names
                    }
                )
        return gym.spaces.Dict(spaces)

    def _make_action_space(self) -> gym.spaces.Box:
        g_lo, g_hi = self._grip_range
        if self.action_mode == "joint":
            lower = np.append(self.kinematics.lower, g_lo)
            upper = np.append(self.kinematics.upper, g_hi)
            lower = np.where(np.isfinite(lower), lower, -2 * np.pi)
            upper = np.where(np.isfinite(upper), upper, 2 * np.pi)
        elif self.action_mode == "eef_abs":
            lower = np.array([*[-EEF_POS_BOUND] * 3, *[-1.0] * 6, g_lo])
            upper = np.array([*[EEF_POS_BOUND] * 3, *[1.0] * 6, g_hi])
        else:
            lower = np.array([*[-EEF_REL_POS_BOUND] * 3, *[-EEF_REL_ROT_BOUND] * 3, g_lo])
            upper = np.array([*[EEF_REL_POS_BOUND] * 3, *[EEF_REL_ROT_BOUND] * 3, g_hi])
        return gym.spaces.Box(lower.astype(np.float32), upper.astype(np.float32), dtype=np.float32)

    # ------------------------------------------------------------------ gymnasium API
    def reset(
        self, *, seed: int | None = None, options: Mapping[str, Any] | None = None
    ) -> tuple[dict[str, Any], dict[str, Any]]:
        """Start an episode. ``options``: ``world_idx`` (0..5; default drawn from the env's
        generator), ``random_shift`` (metres; default the constructor's) and the task's own
        (``Task.reset_options``, e.g. Pick's ``instruction``). Options LeRobot's rollout loop
        adds (``lerobot_*``, e.g. ``lerobot_new_rollout``) are ignored."""
        super().reset(seed=seed)
        options = {k: v for k, v in (options or {}).items() if not k.startswith("lerobot_")}
        known = ("world_idx", "random_shift", *self.task.reset_options)
        unknown = set(options) - set(known)
        if unknown:
            raise ValueError(f"unknown reset options {sorted(unknown)}; use {', '.join(known)}")
        task_options = {k: options[k] for k in self.task.reset_options if k in options}
        self.task.begin_episode(self.np_random, task_options)
        self.task_description = self.task.description
        world_idx = options.get("world_idx")
        if world_idx is None:
            world_idx = int(self.np_random.integers(len(self.task.world_offsets)))
        shift = float(options.get("random_shift", self.random_shift))
        self.world_offset = self.task.world_offset(world_idx, self.np_random, shift)
        self.world_idx = int(world_idx)

        mujoco.mj_resetData(self.model, self.data)
        self.task.apply_world(self.model, self.world_offset)
        self.data.qpos[self._arm_qpos] = self.home_command[:-1]
        self._apply_command(self.home_command)
        mujoco.mj_kinematics(self.model, self.data)
        self.task.reset_objects(self.model, self.data, self.robot)
        mujoco.mj_forward(self.model, self.data)

        self._command = self.home_command.copy()
        self._prev_command = self.home_command.copy()
        self._command_eef_pose = self.kinematics.fk(self.home_command)
        self._success = self.task.is_success(self.model, self.data)
        self._reward = float(self._success)
        obs = self._observe()
        return obs, {"is_success": self._success, "world_idx": self.world_idx}

    def step(self, action: np.ndarray) -> tuple[dict[str, Any], float, bool, bool, dict[str, Any]]:
        command = self.command_from_action(action)
        self._prev_command = self._command
        self._command = command
        self._command_eef_pose = self.kinematics.fk(command)
        self._apply_command(command)
        mujoco.mj_step(self.model, self.data, nstep=self.frame_skip)
        self._success = self.task.is_success(self.model, self.data)
        self._reward = float(self._success)
        obs = self._observe()
        terminated = self._success and self.terminate_on_success
        return obs, self._reward, terminated, False, {"is_success": self._success}

    def render(self) -> np.ndarray | None:
        """RGB image of ``render_camera`` (reusing this step's frame when it was rendered)."""
        if self.render_mode is None:
            return None
        if self.render_camera in self._rgb:
            return self._rgb[self.render_camera]
        rgb, _ = self._get_renderer().render(self.data, [self.render_camera])
        return rgb[self.render_camera]

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    # ------------------------------------------------------------------ actions
    def command_from_action(self, action: np.ndarray) -> np.ndarray:
        """The 7 joint targets (6 arm + gripper) an action means in the current action mode.

        The result is cached per (action, current command), so a recorder calling
        :meth:`rmb_step_data` with the action before :meth:`step` does not solve the IK twice.
        """
        action = np.asarray(action, dtype=np.float64)
        key = (action.tobytes(), self._command.tobytes())
        if self._command_cache is not None and self._command_cache[0] == key:
            return self._command_cache[1].copy()
        command = self._solve_command(action)
        self._command_cache = (key, command)
        return command.copy()

    def _solve_command(self, action: np.ndarray) -> np.ndarray:
        if action.shape != self.action_space.shape:
            raise ValueError(
                f"{self.action_mode!r} action must have shape {self.action_space.shape}, "
                f"got {action.shape}"
            )
        if not np.all(np.isfinite(action)):
            raise ValueError(f"action has non-finite values: {action}")
        gripper = np.clip(action[-1], *self._grip_range)
        if self.action_mode == "joint":
            arm = np.clip(action[:-1], self.action_space.low[:-1], self.action_space.high[:-1])
            return np.append(arm, gripper)
        if self.action_mode == "eef_abs":
            rot6d = action[3:POLICY_POSE_DIM].reshape(2, 3)
            if np.linalg.norm(np.cross(*rot6d)) < 1e-6:
                raise ValueError(f"eef_abs action has a degenerate 6-D rotation: {action}")
            target = policy_to_pose(action[:POLICY_POSE_DIM].astype(np.float64))
        else:
            target = apply_relative_pose(self._command_eef_pose, action[:REL_POSE_DIM])
        solution = self.kinematics.ik(target, self._command[:-1])
        return np.append(solution.qpos, gripper)

    def _apply_command(self, command: np.ndarray) -> None:
        self.data.ctrl[self._arm_act] = command[:-1]
        self.data.ctrl[self._grip_act] = command[-1]

    # ------------------------------------------------------------------ observations
    def _get_renderer(self) -> MultiCameraRenderer:
        if self._renderer is None:
            width, height = self.image_size
            self._renderer = MultiCameraRenderer(self.model, width, height, **self._render_flags)
        return self._renderer

    def measured_joint_pos(self) -> np.ndarray:
        """Arm joint angles + gripper value in command units (RMB's ``measured_joint_pos``)."""
        gripper = self.robot.gripper_scale * np.mean(self.data.qpos[self._grip_qpos])
        return np.append(self.data.qpos[self._arm_qpos], gripper)

    def measured_joint_vel(self) -> np.ndarray:
        """Arm joint velocities + 0 for the gripper (RMB records no gripper velocity)."""
        return np.append(self.data.qvel[self._arm_dof], 0.0)

    def measured_wrench(self) -> np.ndarray:
        """Wrist force/torque sensor reading (fx, fy, fz, nx, ny, nz) in the sensor frame."""
        sensordata = self.data.sensordata
        return np.concatenate(
            [
                sensordata[self._force_adr : self._force_adr + 3],
                sensordata[self._torque_adr : self._torque_adr + 3],
            ]
        )

    def _observe(self) -> dict[str, Any]:
        self._rgb, self._depth_m = {}, {}
        if self.camera_names:
            self._rgb, self._depth_m = self._get_renderer().render(
                self.data, self.camera_names, rgb=True, depth=self.use_depth
            )
        obs: dict[str, Any] = {"agent_pos": self.measured_joint_pos().astype(np.float32)}
        if self.camera_names:
            obs["pixels"] = dict(self._rgb)
            if self.use_depth:
                obs["depth"] = {cam: metres_to_mm(depth) for cam, depth in self._depth_m.items()}
        return obs

    @property
    def command_eef_pose(self) -> np.ndarray:
        """Eef pose (root frame) of the last command: what ``eef_rel`` actions are relative to."""
        return self._command_eef_pose.copy()

    @property
    def command(self) -> np.ndarray:
        """The last applied joint command (6 arm targets + gripper)."""
        return self._command.copy()

    def fovy(self, camera: str) -> float:
        """Vertical field of view of a camera in degrees (RMB's only stored intrinsic)."""
        if camera not in self.available_cameras:
            raise ValueError(f"unknown camera {camera!r}; available: {self.available_cameras}")
        return float(self.model.camera(camera).fovy[0])

    # ------------------------------------------------------------------ RMB recording
    def rmb_step_data(self, action: np.ndarray | None = None) -> dict[str, Any]:
        """Everything RMB records for the current step, keyed by RMB key names.

        Pairs the current (measured) state and reward with the command of ``action`` (the
        action about to be passed to :meth:`step`; default: the last applied command), the way
        RMB's recorder pairs an observation with the command sent from it. Ready for
        :meth:`rmb_lerobot.EpisodeWriter.append`; relative keys are derived by the writer.
        Images are this step's frames (depth in float metres when ``depth=True``).
        """
        command = self._command if action is None else self.command_from_action(action)
        previous = self._prev_command if action is None else self._command
        measured = self.measured_joint_pos()
        step: dict[str, Any] = {
            K.TIME: float(self.data.time),
            K.REWARD: float(self._reward),
            K.MEASURED_JOINT_POS: measured,
            K.COMMAND_JOINT_POS: command.copy(),
            K.MEASURED_JOINT_VEL: self.measured_joint_vel(),
            K.COMMAND_JOINT_VEL: (command - previous) / self.control_dt,
            K.MEASURED_GRIPPER_JOINT_POS: measured[-1:].copy(),
            K.COMMAND_GRIPPER_JOINT_POS: command[-1:].copy(),
            K.MEASURED_EEF_POSE: self.kinematics.fk(measured),
            K.COMMAND_EEF_POSE: self.kinematics.fk(command),
            K.MEASURED_EEF_WRENCH: self.measured_wrench(),
        }
        for cam, rgb in self._rgb.items():
            step[K.rgb_image_key(cam)] = rgb
        for cam, depth in self._depth_m.items():
            step[K.depth_image_key(cam)] = depth
        return step

    def rmb_attrs(self) -> dict[str, Any]:
        """Episode attributes RMB writes (env, task_desc, world_idx, cameras, depth fovy)."""
        attrs: dict[str, Any] = {
            K.ATTR_ENV: self.task.rmb_env_name + "Env",
            K.ATTR_TASK_DESC: self.task_description,
            K.ATTR_WORLD_IDX: self.world_idx,
            K.ATTR_CAMERA_NAMES: list(self.camera_names),
        }
        for cam in self.camera_names:
            attrs[K.fovy_attr(cam)] = self.fovy(cam)
        return attrs

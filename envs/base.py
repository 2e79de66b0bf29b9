"""The env core: one gymnasium env for every robot, task and backend.

:class:`RmbEnv` composes a :class:`~rmb_lerobot.envs.tasks.base.Task`, a robot record
(:mod:`rmb_lerobot.envs.robots`) and a backend (:mod:`rmb_lerobot.envs.backend`; MuJoCo today)
and owns everything that does not depend on the simulator: the gymnasium API, the reset-option
protocol, the action mode (:mod:`rmb_lerobot.envs.actions`), LeRobot's observation contract
(``pixels``, ``agent_pos``, optional ``depth``), success and termination, and what recorders
get: every RMB key through :meth:`RmbEnv.rmb_step_data` and the episode attributes through
:meth:`RmbEnv.rmb_attrs`, which keeps the observation space small.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np

from rmb_lerobot import keys as K
from rmb_lerobot.codecs.depth_base import metres_to_mm
from rmb_lerobot.envs.actions import ACTION_MODES, CommandState, make_action_mode
from rmb_lerobot.envs.backend import Backend
from rmb_lerobot.envs.registry import SIMULATORS, rmb_env_name
from rmb_lerobot.envs.robots import Robot, robot_for
from rmb_lerobot.envs.tasks.base import Task
from rmb_lerobot.envs.workspace import Workspace

__all__ = ["ACTION_MODES", "DEFAULT_IMAGE_SIZE", "RMB_IMAGE_SIZE", "RmbEnv", "make_backend"]

DEFAULT_IMAGE_SIZE = (128, 128)
RMB_IMAGE_SIZE = (640, 480)
# RMB's control period, 0.004 s x 8 (its recorder reports int(1 / 0.032) = 31 frames per second).
RMB_CONTROL_DT = 0.032


def make_backend(
    simulator: str, task: Task, robot: Robot, workspace: Workspace, **options: Any
) -> Backend:
    """The backend of ``simulator`` for this task, robot and workspace (options: its own)."""
    if simulator == "mujoco":
        from rmb_lerobot.envs.mujoco.backend import MujocoBackend

        return MujocoBackend(task, robot, workspace, **options)
    raise ValueError(f"unknown simulator {simulator!r}; known: {sorted(SIMULATORS)}")


class RmbEnv(gym.Env):
    """An RMB task on a robot in a simulator, with a gymnasium API and LeRobot's observations.

    Parameters
    ----------
    task:
        The task (props, world variations, success test), placed in its workspace (the
        table and fixed cameras of the scene).
    robot:
        The robot record or its short name (default: RMB's UR5e + Robotiq 2F-85).
    simulator:
        The backend to build (``"mujoco"``).
    action_mode:
        ``"joint"`` (default), ``"eef_abs"`` or ``"eef_rel"`` (:mod:`rmb_lerobot.envs.actions`).
    cameras:
        Cameras rendered into the observation, any of :attr:`available_cameras`; ``()`` for none
        (fast: physics only). Default: all of them (RMB's four for the UR5e).
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
    backend_options:
        Passed to the backend (MuJoCo: ``frame_skip``, ``shadows``, ``reflections``,
        ``antialias``, ``visual_mesh_error``, ``tactile``; see
        :class:`~rmb_lerobot.envs.mujoco.backend.MujocoBackend`).
    """

    metadata: ClassVar[dict[str, Any]] = {
        "render_modes": ["rgb_array"],
        "render_fps": int(1 / RMB_CONTROL_DT),
    }

    def __init__(
        self,
        task: Task,
        robot: Robot | str = "ur5e",
        *,
        simulator: str = "mujoco",
        action_mode: str = "joint",
        cameras: Sequence[str] | None = None,
        image_size: tuple[int, int] = DEFAULT_IMAGE_SIZE,
        depth: bool = False,
        random_shift: float = 0.0,
        terminate_on_success: bool = True,
        render_mode: str | None = "rgb_array",
        render_camera: str = "front",
        **backend_options: Any,
    ):
        if action_mode not in ACTION_MODES:
            raise ValueError(f"action_mode must be one of {ACTION_MODES}, got {action_mode!r}")
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        width, height = (int(v) for v in image_size)
        if width <= 0 or height <= 0:
            raise ValueError(f"image_size must be two positive ints (W, H), got {image_size!r}")
        if random_shift < 0:
            raise ValueError(f"random_shift must be >= 0 metres, got {random_shift!r}")
        self.task = task
        self.robot = robot_for(robot) if isinstance(robot, str) else robot
        self.simulator = simulator
        self.rmb_env_name = rmb_env_name(simulator, self.robot, task.name)
        self.image_size = (width, height)
        self.use_depth = bool(depth)
        self.random_shift = float(random_shift)
        self.terminate_on_success = terminate_on_success
        self.render_mode = render_mode
        self.render_camera = render_camera

        self.sim = make_backend(
            simulator,
            task,
            self.robot,
            task.workspace,
            image_size=self.image_size,
            **backend_options,
        )
        self.available_cameras = self.sim.cameras
        cameras = self.available_cameras if cameras is None else tuple(cameras)
        for name in (*cameras, *([render_camera] if render_mode else [])):
            if name not in self.available_cameras:
                raise ValueError(f"unknown camera {name!r}; available: {self.available_cameras}")
        self.camera_names = cameras
        self.control_dt = self.sim.control_dt
        self.task_description = task.description
        self._max_episode_steps = task.max_episode_steps

        self.home_command = self.robot.home_command(task.start_pose(self.robot.name))
        self.action_mode = action_mode
        self._action_mode = make_action_mode(action_mode, self.robot, self.sim.joint_limits())
        self._slices = self.robot.joint_slices()
        self._grippers = [grip for _, grip in self._slices]
        self.observation_space = self._make_observation_space()
        self.action_space = self._action_mode.space

        self.world_idx = 0
        self.world_offset = np.zeros(3)
        self._command = self.home_command.copy()
        self._prev_command = self.home_command.copy()
        self._command_eef_poses = self._eef_poses(self.home_command)
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

        self.sim.reset(self.world_offset, self.home_command)

        self._command = self.home_command.copy()
        self._prev_command = self.home_command.copy()
        self._command_eef_poses = self._eef_poses(self.home_command)
        self._success = self.task.is_success(self.sim)
        self._reward = float(self._success)
        obs = self._observe()
        return obs, {"is_success": self._success, "world_idx": self.world_idx}

    def step(self, action: np.ndarray) -> tuple[dict[str, Any], float, bool, bool, dict[str, Any]]:
        command = self.command_from_action(action)
        self._prev_command = self._command
        self._command = command
        self._command_eef_poses = self._eef_poses(command)
        self.sim.apply_command(command)
        self.sim.step()
        self._success = self.task.is_success(self.sim)
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
        rgb, _ = self.sim.render([self.render_camera])
        return rgb[self.render_camera]

    def close(self) -> None:
        self.sim.close()

    # ------------------------------------------------------------------ actions
    def command_from_action(self, action: np.ndarray) -> np.ndarray:
        """The joint vector (per arm: joint targets, gripper) an action means in the current
        action mode.

        The result is cached per (action, current command), so a recorder calling
        :meth:`rmb_step_data` with the action before :meth:`step` does not solve the IK twice.
        """
        action = np.asarray(action, dtype=np.float64)
        key = (action.tobytes(), self._command.tobytes())
        if self._command_cache is not None and self._command_cache[0] == key:
            return self._command_cache[1].copy()
        state = CommandState(self._command, self._command_eef_poses, self.sim.ik)
        command = self._action_mode.to_command(action, state)
        self._command_cache = (key, command)
        return command.copy()

    # ------------------------------------------------------------------ kinematics
    def _eef_poses(self, joints: np.ndarray) -> tuple[np.ndarray, ...]:
        return tuple(self.sim.fk(i, joints[arm]) for i, (arm, _) in enumerate(self._slices))

    def eef_pose(self, joints: np.ndarray) -> np.ndarray:
        """RMB's eef pose of a joint vector: per arm (7,) in its root frame, concatenated."""
        poses = self._eef_poses(np.asarray(joints, dtype=np.float64))
        return poses[0] if len(poses) == 1 else np.concatenate(poses)

    # ------------------------------------------------------------------ observations
    def measured_joint_pos(self) -> np.ndarray:
        """Arm joint angles + gripper values in command units (RMB's ``measured_joint_pos``)."""
        return self.sim.measured_joint_pos()

    def measured_joint_vel(self) -> np.ndarray:
        """Arm joint velocities + 0 per gripper (RMB records no gripper velocity)."""
        return self.sim.measured_joint_vel()

    def measured_wrench(self) -> np.ndarray:
        """Wrist force/torque per arm (fx, fy, fz, nx, ny, nz) in the sensor frame."""
        return self.sim.measured_wrench()

    def _observe(self) -> dict[str, Any]:
        self._rgb, self._depth_m = {}, {}
        if self.camera_names:
            self._rgb, self._depth_m = self.sim.render(
                self.camera_names, rgb=True, depth=self.use_depth
            )
        obs: dict[str, Any] = {"agent_pos": self.measured_joint_pos().astype(np.float32)}
        if self.camera_names:
            obs["pixels"] = dict(self._rgb)
            if self.use_depth:
                obs["depth"] = {cam: metres_to_mm(depth) for cam, depth in self._depth_m.items()}
        return obs

    @property
    def command_eef_pose(self) -> np.ndarray:
        """Eef pose(s) of the last command: what ``eef_rel`` actions are relative to."""
        poses = self._command_eef_poses
        return poses[0].copy() if len(poses) == 1 else np.concatenate(poses)

    @property
    def command(self) -> np.ndarray:
        """The last applied joint command (per arm: joint targets, gripper)."""
        return self._command.copy()

    def fovy(self, camera: str) -> float:
        """Vertical field of view of a camera in degrees (RMB's only stored intrinsic)."""
        if camera not in self.available_cameras:
            raise ValueError(f"unknown camera {camera!r}; available: {self.available_cameras}")
        return self.sim.fovy(camera)

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
            K.TIME: self.sim.time,
            K.REWARD: float(self._reward),
            K.MEASURED_JOINT_POS: measured,
            K.COMMAND_JOINT_POS: command.copy(),
            K.MEASURED_JOINT_VEL: self.measured_joint_vel(),
            K.COMMAND_JOINT_VEL: (command - previous) / self.control_dt,
            K.MEASURED_GRIPPER_JOINT_POS: measured[self._grippers],
            K.COMMAND_GRIPPER_JOINT_POS: command[self._grippers],
            K.MEASURED_EEF_POSE: self.eef_pose(measured),
            K.COMMAND_EEF_POSE: self.eef_pose(command),
            K.MEASURED_EEF_WRENCH: self.measured_wrench(),
        }
        for cam, rgb in self._rgb.items():
            step[K.rgb_image_key(cam)] = rgb
        for cam, depth in self._depth_m.items():
            step[K.depth_image_key(cam)] = depth
        step.update(self.sim.tactile())  # RMB's fingertip grids, with tactile=True
        return step

    def rmb_attrs(self) -> dict[str, Any]:
        """Episode attributes RMB writes (env, task_desc, world_idx, cameras, depth fovy), plus,
        with depth, each world-fixed camera's pose (:func:`~rmb_lerobot.keys.camera_pose_attr`)."""
        attrs: dict[str, Any] = {
            K.ATTR_ENV: self.rmb_env_name + "Env",
            K.ATTR_TASK_DESC: self.task_description,
            K.ATTR_WORLD_IDX: self.world_idx,
            K.ATTR_CAMERA_NAMES: list(self.camera_names),
        }
        for cam in self.camera_names:
            attrs[K.fovy_attr(cam)] = self.fovy(cam)
            pose = self.sim.camera_pose(cam) if self.use_depth else None
            if pose is not None:  # fixed cameras only: a moving camera has no single pose
                attrs[K.camera_pose_attr(cam)] = pose
        return attrs

"""The env core: one gymnasium env for every robot, task and backend.

:class:`RmbEnv` composes a :class:`~rmb_lerobot.envs.tasks.base.Task`, a backend
(:mod:`rmb_lerobot.envs.backend`: MuJoCo, PyBullet, or anything that implements it) with its
robot record (:mod:`rmb_lerobot.envs.robots`), and owns everything that does not depend on the
simulator: the gymnasium API, the reset-option protocol, the action mode
(:mod:`rmb_lerobot.envs.actions`), LeRobot's observation contract (``pixels``, ``agent_pos``,
optional ``depth``), success and termination, and what recorders get: every RMB key through
:meth:`RmbEnv.rmb_step_data` and the episode attributes through :meth:`RmbEnv.rmb_attrs`,
which keeps the observation space small.
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
from rmb_lerobot.envs.images import DEFAULT_IMAGE_SIZE, RMB_IMAGE_SIZE
from rmb_lerobot.envs.simulators import frames_per_second, rmb_env_name
from rmb_lerobot.envs.tasks.base import Task

__all__ = ["ACTION_MODES", "DEFAULT_IMAGE_SIZE", "RMB_IMAGE_SIZE", "RmbEnv"]


class RmbEnv(gym.Env):
    """An RMB task on a robot behind a backend, with a gymnasium API and LeRobot's observations.

    The env core receives its backend (built by the registry,
    :func:`rmb_lerobot.envs.registry.compose`, from the simulator its table row names) and never
    chooses one: a fake backend runs it as well as MuJoCo, PyBullet or a real arm. The frame
    rate (``metadata["render_fps"]``) follows the backend's control period.

    Args:
        task: The task (world variations, success test), placed in its workspace (the table and
            fixed cameras of the scene).
        backend: The world the task runs in (its robot record is the env's robot).
        action_mode: ``"joint"`` (default), ``"eef_abs"`` or ``"eef_rel"``
            (:mod:`rmb_lerobot.envs.actions`).
        cameras: Cameras rendered into the observation, any of :attr:`available_cameras`; ``()``
            for none (fast: physics only). Default: all of them (RMB's four for the UR5e).
        depth: Also render depth: ``observation["depth"]`` (uint16 mm) and float metres for
            recorders.
        random_shift: Default scale (m) of the uniform random object shift added to the world's
            offset; ``reset(options={"random_shift": s})`` overrides it for one episode.
        terminate_on_success: End the episode (``terminated``) when the success criterion holds.
        render_mode: ``"rgb_array"`` or None.
        render_camera: The camera :meth:`render` shows (None: ``front``, or the first camera
            of a scene without one, as ALOHA's).

    Raises:
        ValueError: an unknown action mode, render mode or camera, or a negative shift.
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["rgb_array"]}

    def __init__(
        self,
        task: Task,
        backend: Backend,
        *,
        action_mode: str = "joint",
        cameras: Sequence[str] | None = None,
        depth: bool = False,
        random_shift: float = 0.0,
        terminate_on_success: bool = True,
        render_mode: str | None = "rgb_array",
        render_camera: str | None = None,
    ):
        if action_mode not in ACTION_MODES:
            raise ValueError(f"action_mode must be one of {ACTION_MODES}, got {action_mode!r}")
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        if random_shift < 0:
            raise ValueError(f"random_shift must be >= 0 metres, got {random_shift!r}")
        self.task = task
        self.sim = backend
        self.robot = backend.robot
        self.simulator = backend.simulator
        self.rmb_env_name = rmb_env_name(self.simulator, self.robot, task.name)
        self.image_size = backend.image_size
        self.use_depth = bool(depth)
        self.random_shift = float(random_shift)
        self.terminate_on_success = terminate_on_success
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "render_fps": frames_per_second(backend.control_dt)}

        self.available_cameras = (*backend.cameras, *backend.tactile_sensors)
        if render_camera is None:
            has_front = "front" in self.available_cameras or not self.available_cameras
            render_camera = "front" if has_front else self.available_cameras[0]
        self.render_camera = render_camera
        cameras = self.available_cameras if cameras is None else tuple(cameras)
        for name in (*cameras, *([render_camera] if render_mode else [])):
            if name not in self.available_cameras:
                raise ValueError(f"unknown camera {name!r}; available: {self.available_cameras}")
        self.camera_names = cameras
        # Fingertip tactile images (RMB's rgb_tactile_names) travel as cameras in the
        # observation, so policies see them as images; recorders get them apart.
        self.tactile_names = tuple(c for c in cameras if c in backend.tactile_sensors)
        self._optical_cameras = tuple(c for c in cameras if c not in backend.tactile_sensors)
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
        n = self.robot.layout.num_joints + self.robot.layout.mobile_dim
        spaces: dict[str, gym.spaces.Space] = {
            "agent_pos": gym.spaces.Box(-np.inf, np.inf, (n,), dtype=np.float32)
        }
        if self.camera_names:
            spaces["pixels"] = gym.spaces.Dict(
                {
                    cam: gym.spaces.Box(0, 255, (*self.sim.image_shape(cam), 3), dtype=np.uint8)
                    for cam in self.camera_names
                }
            )
            if self.use_depth and self._optical_cameras:
                spaces["depth"] = gym.spaces.Dict(
                    {
                        cam: gym.spaces.Box(
                            0, np.iinfo(np.uint16).max, self.sim.image_shape(cam), dtype=np.uint16
                        )
                        for cam in self._optical_cameras
                    }
                )
        return gym.spaces.Dict(spaces)

    # ------------------------------------------------------------------ gymnasium API
    def reset(
        self, *, seed: int | None = None, options: Mapping[str, Any] | None = None
    ) -> tuple[dict[str, Any], dict[str, Any]]:
        """Start an episode. ``options``: ``world_idx`` (0 .. the task's ``num_worlds`` - 1;
        default drawn from the env's generator), ``random_shift`` (metres; default the
        constructor's) and the task's own (``Task.reset_options``, e.g. Pick's
        ``instruction``). Options LeRobot's rollout loop adds (``lerobot_*``, e.g.
        ``lerobot_new_rollout``) are ignored."""
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
            world_idx = int(self.np_random.integers(self.task.num_worlds))
        shift = float(options.get("random_shift", self.random_shift))
        self.world_offset = self.task.world_offset(world_idx, self.np_random, shift)
        self.world_idx = self.task.world_idx = int(world_idx)

        self.sim.seed(self.np_random)
        self.sim.reset(self.world_offset, self.home_command)

        self._command = self.home_command.copy()
        self._prev_command = self.home_command.copy()
        self._command_eef_poses = self._eef_poses(self.home_command)
        self._success = self._is_success()
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
        self._success = self._is_success()
        self._reward = float(self._success)
        obs = self._observe()
        terminated = self._success and self.terminate_on_success
        return obs, self._reward, terminated, False, {"is_success": self._success}

    def _is_success(self) -> bool:
        """The task's success test on the backend's scene; False where there is no scene (a
        real arm: success is the operator's call)."""
        scene = self.sim.scene
        return False if scene is None else bool(self.task.is_success(scene))

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

    def measured_base_velocity(self) -> np.ndarray | None:
        """The mobile base's velocity ``(vx, vy, wz)`` in its frame; None for a fixed robot."""
        if self.robot.base is None:
            return None
        return np.asarray(self.sim.measured_base_velocity(), dtype=np.float64)

    def _agent_pos(self) -> np.ndarray:
        """LeRobot's state: the measured joint vector, then the base velocity if there is a
        base (what a converted dataset's ``observation.state`` holds by default)."""
        measured = self.measured_joint_pos()
        base = self.measured_base_velocity()
        return measured if base is None else np.concatenate([measured, base])

    def _observe(self) -> dict[str, Any]:
        self._rgb, self._depth_m = {}, {}
        if self._optical_cameras:
            self._rgb, self._depth_m = self.sim.render(
                self._optical_cameras, rgb=True, depth=self.use_depth
            )
        if self.tactile_names:
            self._rgb.update(self.sim.render_tactile(self.tactile_names))
        obs: dict[str, Any] = {"agent_pos": self._agent_pos().astype(np.float32)}
        if self.camera_names:
            obs["pixels"] = {cam: self._rgb[cam] for cam in self.camera_names}
            if self._depth_m:
                obs["depth"] = {cam: metres_to_mm(depth) for cam, depth in self._depth_m.items()}
        return obs

    @property
    def command_eef_pose(self) -> np.ndarray:
        """Eef pose(s) of the last command: what ``eef_rel`` actions are relative to."""
        poses = self._command_eef_poses
        return poses[0].copy() if len(poses) == 1 else np.concatenate(poses)

    @property
    def command(self) -> np.ndarray:
        """The last applied command (per arm: joint targets, gripper; then the base velocity
        when the robot has a base)."""
        return self._command.copy()

    def fovy(self, camera: str) -> float:
        """Vertical field of view of a camera in degrees (RMB's only stored intrinsic)."""
        if camera not in self.sim.cameras:
            raise ValueError(f"unknown camera {camera!r}; available: {self.sim.cameras}")
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
        joints = slice(0, self.robot.layout.num_joints)  # the command without a base velocity
        step: dict[str, Any] = {
            K.TIME: self.sim.time,
            K.REWARD: float(self._reward),
            K.MEASURED_JOINT_POS: measured,
            K.COMMAND_JOINT_POS: command[joints].copy(),
            K.MEASURED_JOINT_VEL: self.measured_joint_vel(),
            K.COMMAND_JOINT_VEL: (command[joints] - previous[joints]) / self.control_dt,
            K.MEASURED_GRIPPER_JOINT_POS: measured[self._grippers],
            K.COMMAND_GRIPPER_JOINT_POS: command[self._grippers],
            K.MEASURED_EEF_POSE: self.eef_pose(measured),
            K.COMMAND_EEF_POSE: self.eef_pose(command),
            K.MEASURED_EEF_WRENCH: self.measured_wrench(),
        }
        base = self.robot.base_slice
        if base is not None:  # RMB's mobile keys, only for a robot on a base
            step[K.MEASURED_MOBILE_OMNI_VEL] = self.measured_base_velocity()
            step[K.COMMAND_MOBILE_OMNI_VEL] = command[base].copy()
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
            K.ATTR_CAMERA_NAMES: list(self._optical_cameras),
        }
        if self.tactile_names:
            attrs[K.ATTR_RGB_TACTILE_NAMES] = list(self.tactile_names)
        for cam in self._optical_cameras:
            attrs[K.fovy_attr(cam)] = self.fovy(cam)
            pose = self.sim.camera_pose(cam) if self.use_depth else None
            if pose is not None:  # fixed cameras only: a moving camera has no single pose
                attrs[K.camera_pose_attr(cam)] = pose
        return attrs

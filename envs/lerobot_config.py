"""LeRobot env types for every RMB environment, generated from the one table.

``lerobot-train --env.type=rmb_ur5e_insert ...`` and ``lerobot-eval --env.type=...`` find these
because importing ``lerobot_env_rmb`` (which LeRobot's plugin discovery does) imports this
module. Each type is a small dataclass: cameras, image size, action mode and episode length
are fields, ``features``/``features_map`` follow from them.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field, make_dataclass

import gymnasium as gym
import numpy as np
from lerobot.configs import FeatureType, PolicyFeature
from lerobot.envs.configs import EnvConfig
from lerobot.utils.constants import OBS_STR

from rmb_lerobot import keys as K
from rmb_lerobot import lerobot_names as N
from rmb_lerobot.envs.registry import ENVS, EnvEntry, entry_for, make_env
from rmb_lerobot.envs.simulators import SIMULATORS
from rmb_lerobot.pose import POLICY_POSE_DIM, REL_POSE_DIM

# MuJoCo's control rate is 31.25 Hz; LeRobot wants an integer (RMB itself reports int(31.25)).
# Each registered type takes its own simulator's rate (EnvEntry.fps: 33 for PyBullet).
RMB_FPS = SIMULATORS["mujoco"].fps
DEFAULT_CAMERAS = ("front", "hand")  # RMB's default policy cameras for the UR5e tasks


def action_dim(action_mode: str, layout: K.RobotLayout = K.UR5E_LAYOUT) -> int:
    """Numbers in one action of the given mode (see ``RmbEnv``'s action modes): the arm
    parts, then the base velocity for a robot on a mobile base."""
    dims = {
        "joint": layout.num_joints,
        "eef_abs": POLICY_POSE_DIM * layout.num_eefs + layout.num_grippers,
        "eef_rel": REL_POSE_DIM * layout.num_eefs + layout.num_grippers,
    }
    if action_mode not in dims:
        raise ValueError(f"action_mode must be one of {sorted(dims)}, got {action_mode!r}")
    return dims[action_mode] + layout.mobile_dim


@dataclass
class RmbEnvConfig(EnvConfig):
    """Fields shared by every RMB env type (the registered subclasses only set ``task``)."""

    task: str | None = None  # RMB env name, e.g. "MujocoUR5eInsert"
    fps: int = RMB_FPS
    episode_length: int | None = None  # None: the task's own limit
    cameras: list[str] = field(default_factory=lambda: list(DEFAULT_CAMERAS))
    image_width: int = 128
    image_height: int = 128
    action_mode: str = "joint"
    random_shift: float = 0.0  # metres of uniform object shift on top of the world's offset
    render_mode: str = "rgb_array"
    # Also deliver each camera's depth as observation.images.<camera>_depth (see DepthForLeRobot).
    depth: bool = False
    # Evaluate in one world (0..5) only; None: each episode's world is drawn from its seed.
    world_idx: int | None = None
    # Every episode with this instruction (language-conditioned tasks: Pick's 18); lerobot-eval
    # then scores one instruction, and hands it to the policy as the task.
    instruction: str | None = None
    # Append RMB's fingertip tactile grids (left, then right, 5 x 8 each, row-major) to the
    # state, as a dataset converted with --state-keys measured_joint_pos left_tactile_sensor
    # right_tactile_sensor holds them (see TactileInState).
    tactile: bool = False

    def __post_init__(self) -> None:
        layout = entry_for(self.task).robot_record.layout if self.task else K.UR5E_LAYOUT
        shape = (self.image_height, self.image_width, 3)
        self.features = {
            N.ACTION_KEY: PolicyFeature(
                FeatureType.ACTION, (action_dim(self.action_mode, layout),)
            ),
            N.ENV_STATE_KEY: PolicyFeature(
                FeatureType.STATE, (layout.num_joints + layout.mobile_dim + self._tactile_dim(),)
            ),
        }
        self.features_map = {N.ACTION_KEY: N.ACTION_KEY, N.ENV_STATE_KEY: N.STATE}
        for camera in self.cameras:
            self.features[N.env_pixels_key(camera)] = PolicyFeature(FeatureType.VISUAL, shape)
            self.features_map[N.env_pixels_key(camera)] = N.image_key(camera)
            if self.depth:
                depth_shape = (self.image_height, self.image_width, 1)
                self.features[depth_observation_key(camera)] = PolicyFeature(
                    FeatureType.VISUAL, depth_shape
                )
                self.features_map[depth_observation_key(camera)] = N.depth_image_key(camera)

    def _tactile_dim(self) -> int:
        if not self.tactile:
            return 0
        from rmb_lerobot.envs.sensors.tactile import pads_for

        robot = entry_for(self.task).robot_record.name if self.task else "ur5e"
        return len(pads_for(robot)) * int(np.prod(K.TACTILE_SHAPE))

    @property
    def gym_kwargs(self) -> dict:
        return {
            "cameras": tuple(self.cameras),
            "image_size": (self.image_width, self.image_height),
            "action_mode": self.action_mode,
            "random_shift": self.random_shift,
            "depth": self.depth,
            "render_mode": self.render_mode,
            "render_camera": self.cameras[0] if self.cameras else "front",
            "max_episode_steps": self.episode_length,
            # MuJoCo's fingertip grids (a backend option); PyBullet's tactile images are cameras.
            **({"tactile": True} if self.tactile else {}),
        }

    def create_envs(
        self, n_envs: int, use_async_envs: bool = False
    ) -> dict[str, dict[int, gym.vector.VectorEnv]]:
        """Vector envs built straight from our table (no gym id lookup, no package import).

        Async workers start with forkserver (what LeRobot uses); ``make_env`` is a module
        function, so the env factory pickles by reference.
        """
        factory = functools.partial(
            make_lerobot_env,
            self.task,
            world_idx=self.world_idx,
            instruction=self.instruction,
            **self.gym_kwargs,
        )
        if use_async_envs and n_envs > 1:
            vec = gym.vector.AsyncVectorEnv(
                [factory] * n_envs,
                context="forkserver",
                autoreset_mode=gym.vector.AutoresetMode.SAME_STEP,
            )
        else:
            vec = gym.vector.SyncVectorEnv(
                [factory] * n_envs, autoreset_mode=gym.vector.AutoresetMode.SAME_STEP
            )
        return {self.type: {0: vec}}


def depth_observation_key(camera: str) -> str:
    """``front`` -> ``images.front_depth``, which LeRobot prefixes with ``observation.``."""
    return N.depth_image_key(camera).removeprefix(OBS_STR + ".")


class DepthForLeRobot(gym.ObservationWrapper):
    """Depth as LeRobotDataset returns it: float32 millimetres, channel first, per camera.

    ``RmbEnv(depth=True)`` puts depth in a nested ``depth`` dict (uint16 mm), which LeRobot's
    ``preprocess_observation`` drops; a flat array key ``k`` it passes through as float
    ``observation.<k>``. So each camera becomes ``images.<camera>_depth`` of shape (1, H, W), i.e.
    ``observation.images.<camera>_depth`` (B, 1, H, W) at the policy: the layout and unit a
    dataset converted with ``--depth`` decodes to (LeRobot's default ``depth_output_unit="mm"``).
    """

    def __init__(self, env: gym.Env):
        super().__init__(env)
        spaces = dict(env.observation_space.spaces)
        for camera, space in spaces.pop("depth").spaces.items():
            spaces[depth_observation_key(camera)] = gym.spaces.Box(
                0.0, float(space.high.max()), (1, *space.shape), dtype=np.float32
            )
        self.observation_space = gym.spaces.Dict(spaces)

    def observation(self, observation: dict) -> dict:
        observation = dict(observation)
        for camera, depth_mm in observation.pop("depth").items():
            observation[depth_observation_key(camera)] = depth_mm[None].astype(np.float32)
        return observation


class TactileInState(gym.ObservationWrapper):
    """The fingertip tactile grids appended to ``agent_pos`` (LeRobot's ``observation.state``).

    For an env made with ``tactile=True``: each pad's ``(rows, cols)`` grid, row-major, in
    the robot's pad order (the UR5e: ``left_tactile_sensor``, then ``right_tactile_sensor``),
    after the joint vector: the layout of a dataset converted with ``--state-keys
    measured_joint_pos left_tactile_sensor right_tactile_sensor``.
    """

    def __init__(self, env: gym.Env):
        super().__init__(env)
        from rmb_lerobot.envs.sensors.tactile import pads_for

        self.tactile_keys = tuple(pad.key for pad in pads_for(env.unwrapped.robot.name))
        joints = env.observation_space["agent_pos"].shape[0]
        size = len(self.tactile_keys) * int(np.prod(K.TACTILE_SHAPE))
        self.observation_space = gym.spaces.Dict(
            {
                **env.observation_space.spaces,
                "agent_pos": gym.spaces.Box(-np.inf, np.inf, (joints + size,), dtype=np.float32),
            }
        )

    def observation(self, observation: dict) -> dict:
        grids = self.env.unwrapped.sim.tactile()
        parts = [observation["agent_pos"], *(grids[key].ravel() for key in self.tactile_keys)]
        return {**observation, "agent_pos": np.concatenate(parts).astype(np.float32)}


class FixedResetOptions(gym.Wrapper):
    """Every episode with the same reset options (``world_idx``, ``instruction``): ``reset``
    adds them unless the caller set them."""

    def __init__(self, env: gym.Env, options: dict):
        super().__init__(env)
        self.options = dict(options)

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        return self.env.reset(seed=seed, options={**self.options, **(options or {})})


def make_lerobot_env(
    task: str, world_idx: int | None = None, instruction: str | None = None, **kwargs
) -> gym.Env:
    """:func:`make_env`, with depth in LeRobot's layout when ``depth=True`` (and cameras), the
    tactile grids in the state when ``tactile=True``, in one world if ``world_idx`` is given
    and with one instruction if ``instruction`` is (a task that takes none refuses it)."""
    env = make_env(task, **kwargs)
    if "depth" in env.observation_space.spaces:
        env = DepthForLeRobot(env)
    if kwargs.get("tactile"):
        env = TactileInState(env)
    fixed = {"world_idx": int(world_idx)} if world_idx is not None else {}
    if instruction is not None:
        accepted = env.unwrapped.task.reset_options
        if "instruction" not in accepted:
            raise ValueError(
                f"env {task!r} takes no instruction (got {instruction!r}); "
                f"its reset options: {list(accepted) or 'none'}"
            )
        fixed["instruction"] = instruction
    return FixedResetOptions(env, fixed) if fixed else env


def _register(entry: EnvEntry) -> type[RmbEnvConfig]:
    name = "".join(part.capitalize() for part in entry.lerobot_type.split("_")) + "Env"
    # RMB's default policy cameras: the scene's first (front), the robot's own (hand) and its
    # fingertip tactile images.
    robot = entry.robot_record
    cameras = (entry.workspace.cameras[0].name, *robot.cameras, *robot.tactile_sensors)
    cls = make_dataclass(
        name,
        [
            ("task", str | None, field(default=entry.rmb_env_name)),
            ("fps", int, field(default=entry.fps)),
            ("cameras", list[str], field(default_factory=lambda: list(cameras))),
        ],
        bases=(RmbEnvConfig,),
        namespace={"__doc__": f"LeRobot env type for RMB's {entry.rmb_env_name}."},
    )
    cls.__module__ = __name__
    globals()[name] = cls  # importable by name, so configs pickle by reference
    return EnvConfig.register_subclass(entry.lerobot_type)(cls)


ENV_CONFIGS: dict[str, type[RmbEnvConfig]] = {
    entry.lerobot_type: _register(entry) for entry in ENVS.values()
}
"""LeRobot env type name -> its config class."""

"""The task interface: what a task adds to the scene, how its world varies, what success is.

A task knows nothing about rendering, actions or gymnasium; :class:`rmb_lerobot.envs.base.RmbEnv`
composes it with a robot and the shared scene (dm_control's composer split).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping
from typing import Any

import mujoco
import numpy as np
from rmb_lerobot.envs.mujoco.robot import RobotSpec

NUM_WORLDS = 6


class Task(ABC):
    """One RMB task. Subclasses set the class attributes and implement the four methods.

    ``world_offsets`` is RMB's table of six object shifts (``world_idx`` 0..5, metres, world
    frame); a random shift, uniform in ``[-scale, scale]`` on the axes where ``shift_axes`` is
    1, is added on top when the env asks for one.
    """

    rmb_env_name: str  # RMB's environment class name without "Env", e.g. "MujocoUR5eInsert"
    description: str  # language instruction for language-conditioned policies
    world_offsets: np.ndarray  # (NUM_WORLDS, 3)
    shift_axes: np.ndarray = np.array([1.0, 1.0, 0.0])
    max_episode_steps: int = 300
    home_arm_qpos: tuple[float, ...] | None = None  # None: the robot's home pose
    reset_options: tuple[str, ...] = ()  # extra ``env.reset`` options, see begin_episode

    def begin_episode(  # noqa: B027 - optional hook
        self, rng: np.random.Generator, options: Mapping[str, Any]
    ) -> None:
        """Choose the episode's variant before the world is set (e.g. a language-conditioned
        task's instruction, which then becomes :attr:`description`). ``options`` holds the
        reset options named in :attr:`reset_options` that were given."""

    def episode_variants(self) -> tuple[dict[str, Any], ...]:
        """Every variant a dataset should cover evenly, as reset options (e.g. one per
        instruction of a language-conditioned task); empty for single-variant tasks."""
        return ()

    @abstractmethod
    def build(self, spec: mujoco.MjSpec, robot: RobotSpec) -> None:
        """Add the task's bodies, equalities and contact exclusions to the scene spec."""

    @abstractmethod
    def apply_world(self, model: mujoco.MjModel, offset: np.ndarray) -> None:
        """Move the task's objects by ``offset`` (3,) from their nominal placement."""

    @abstractmethod
    def reset_objects(self, model: mujoco.MjModel, data: mujoco.MjData, robot: RobotSpec) -> None:
        """Set the objects' state at episode start (the robot is already at home, kinematics
        computed)."""

    @abstractmethod
    def is_success(self, model: mujoco.MjModel, data: mujoco.MjData) -> bool:
        """Whether the task's success criterion holds in the current state."""

    def world_offset(
        self, world_idx: int, rng: np.random.Generator | None = None, random_shift: float = 0.0
    ) -> np.ndarray:
        """Nominal shift of world ``world_idx`` plus an optional uniform random shift."""
        if not 0 <= int(world_idx) < len(self.world_offsets) or int(world_idx) != world_idx:
            raise ValueError(
                f"world_idx must be an integer in 0..{len(self.world_offsets) - 1}, "
                f"got {world_idx!r}"
            )
        if random_shift < 0:
            raise ValueError(f"random_shift must be >= 0 metres, got {random_shift!r}")
        offset = np.array(self.world_offsets[int(world_idx)], dtype=np.float64)
        if random_shift > 0:
            if rng is None:
                raise ValueError("a random shift needs a random generator")
            offset += rng.uniform(-random_shift, random_shift, 3) * self.shift_axes
        return offset

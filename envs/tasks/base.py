"""The task interface: how a task's world varies, what success is, where it starts.

A task knows nothing about simulators, rendering, actions or gymnasium:
:class:`rmb_lerobot.envs.base.RmbEnv` composes it with a robot and a backend (dm_control's
composer split). It is placed in the workspace it is given (:mod:`rmb_lerobot.envs.workspace`:
the table's height and centre), not at module constants, so one task serves every robot whose
scene has that table.

What a task owns: its names and description, its worlds (:attr:`Task.world_offsets`,
:meth:`Task.world_offset`; as many as RMB gives that task), episode variants, start poses per
robot, and the success test :meth:`Task.is_success`, which reads the world through a
:class:`~rmb_lerobot.envs.scene.SceneState` (body/frame poses, joint positions, deformables'
points), whatever the backend. How a simulator builds the task's props lives beside that
simulator's backend (``rmb_lerobot.envs.mujoco.tasks.<task>``,
``rmb_lerobot.envs.pybullet.tasks.<task>``), found through the simulator's table of scene
builders; this module imports no simulator.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from rmb_lerobot.envs.workspace import RMB_TABLE, Workspace

if TYPE_CHECKING:
    from rmb_lerobot.envs.scene import SceneState

StartPoses = Mapping[str, tuple[tuple[float, ...], ...]]
"""Robot short name -> per-arm start joint angles."""


def placement_in[Placement](
    placements: Mapping[str, Placement], workspace: Workspace, task: str
) -> Placement:
    """A task's layout for ``workspace`` from its table of RMB's per-scene layouts (keyed by
    :attr:`Workspace.name`); the error names the known workspaces."""
    try:
        return placements[workspace.name]
    except KeyError:
        raise ValueError(
            f"the {task} task has no placement for workspace {workspace.name!r}; "
            f"known: {', '.join(sorted(placements))}"
        ) from None


class Task(ABC):
    """One RMB task. Subclasses set the class attributes and implement :meth:`is_success`.

    ``world_offsets`` is RMB's table of the task's object shifts (one row per ``world_idx``,
    metres, world frame: six for RMB's MuJoCo tasks); a random shift, uniform in
    ``[-scale, scale]`` on the axes where ``shift_axes`` is 1, is added on top when the env asks
    for one. ``start_poses``: per robot short name, the arm joint angles (one tuple per arm) the
    task starts from (RMB's per-env start poses); robots not listed start at their own home
    pose.
    """

    name: str  # short task name, e.g. "insert"; the registry derives every env name from it
    description: str  # language instruction for language-conditioned policies
    world_offsets: np.ndarray  # (num_worlds, 3)
    shift_axes: np.ndarray = np.array([1.0, 1.0, 0.0])
    max_episode_steps: int = 300
    start_poses: ClassVar[StartPoses] = {}
    reset_options: tuple[str, ...] = ()  # extra ``env.reset`` options, see begin_episode

    def __init__(self, workspace: Workspace = RMB_TABLE) -> None:
        self.workspace = workspace
        # The episode's world, set by the env core before the backend resets (RMB's success
        # rules may depend on it: Spoon's goal box; so may a scene's per-world pose).
        self.world_idx = 0

    @property
    def num_worlds(self) -> int:
        """How many worlds (``world_idx`` values) the task has."""
        return len(self.world_offsets)

    def start_pose(self, robot: str) -> tuple[tuple[float, ...], ...] | None:
        """Per-arm start joint angles for robot ``robot``, or None for the robot's home."""
        return self.start_poses.get(robot)

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

    # ------------------------------------------------------------------ neutral
    @abstractmethod
    def is_success(self, scene: SceneState) -> bool:
        """Whether the task's success criterion holds in the current state."""

    def world_offset(
        self, world_idx: int, rng: np.random.Generator | None = None, random_shift: float = 0.0
    ) -> np.ndarray:
        """Nominal shift of world ``world_idx`` plus an optional uniform random shift."""
        if not 0 <= int(world_idx) < self.num_worlds or int(world_idx) != world_idx:
            raise ValueError(
                f"world_idx must be an integer in 0..{self.num_worlds - 1}, got {world_idx!r}"
            )
        if random_shift < 0:
            raise ValueError(f"random_shift must be >= 0 metres, got {random_shift!r}")
        offset = np.array(self.world_offsets[int(world_idx)], dtype=np.float64)
        if random_shift > 0:
            if rng is None:
                raise ValueError("a random shift needs a random generator")
            offset += rng.uniform(-random_shift, random_shift, 3) * self.shift_axes
        return offset

"""The task interface: what a task adds to the scene, how its world varies, what success is.

A task knows nothing about rendering, actions or gymnasium; :class:`rmb_lerobot.envs.base.RmbEnv`
composes it with a robot and a backend (dm_control's composer split). It is placed in the
workspace it is given (:mod:`rmb_lerobot.envs.workspace`: the table's height and centre), not
at module constants, so one task serves every robot whose scene has that table.

Neutral and per-simulator parts:

- simulator-neutral: the names and description, the worlds (:attr:`Task.world_offsets`,
  :meth:`Task.world_offset`), episode variants, start poses per robot, and the success test
  :meth:`Task.is_success`, which reads the world through
  :class:`~rmb_lerobot.envs.backend.SceneState` (body/geom/site poses, joint positions,
  deformables' points), whatever the backend;
- MuJoCo-specific: :meth:`Task.build`, :meth:`Task.apply_world` and :meth:`Task.reset_objects`,
  which the MuJoCo backend (:class:`~rmb_lerobot.envs.mujoco.backend.MujocoBackend`) calls with
  itself (``.robot``, ``.robot_model``, ``.workspace``, and ``.model``/``.data`` once
  compiled). Implementing them is what makes a task a MuJoCo task; another simulator's backend
  calls its own builder hooks.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from rmb_lerobot.envs.workspace import RMB_TABLE, Workspace

if TYPE_CHECKING:
    import mujoco

    from rmb_lerobot.envs.backend import SceneState
    from rmb_lerobot.envs.mujoco.backend import MujocoBackend

NUM_WORLDS = 6
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
    """One RMB task. Subclasses set the class attributes and implement the hooks.

    ``world_offsets`` is RMB's table of six object shifts (``world_idx`` 0..5, metres, world
    frame); a random shift, uniform in ``[-scale, scale]`` on the axes where ``shift_axes`` is
    1, is added on top when the env asks for one. ``start_poses``: per robot short name, the
    arm joint angles (one tuple per arm) the task starts from (RMB's per-env start poses);
    robots not listed start at their own home pose.
    """

    name: str  # short task name, e.g. "insert"; the registry derives every env name from it
    description: str  # language instruction for language-conditioned policies
    world_offsets: np.ndarray  # (NUM_WORLDS, 3)
    shift_axes: np.ndarray = np.array([1.0, 1.0, 0.0])
    max_episode_steps: int = 300
    start_poses: ClassVar[StartPoses] = {}
    reset_options: tuple[str, ...] = ()  # extra ``env.reset`` options, see begin_episode

    def __init__(self, workspace: Workspace = RMB_TABLE) -> None:
        self.workspace = workspace

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

    # ------------------------------------------------------------------ MuJoCo hooks
    @abstractmethod
    def build(self, spec: mujoco.MjSpec, sim: MujocoBackend) -> None:
        """MuJoCo: add the task's bodies, equalities and contact exclusions to the scene spec.
        ``sim`` is the backend being built: ``sim.robot`` (the record), ``sim.robot_model``
        (its MuJoCo names) and ``sim.workspace`` are set, the model is not compiled yet."""

    @abstractmethod
    def apply_world(self, sim: MujocoBackend, offset: np.ndarray) -> None:
        """MuJoCo: move the task's objects by ``offset`` (3,) from their nominal placement
        (in ``sim.model``, right after ``mj_resetData``)."""

    @abstractmethod
    def reset_objects(self, sim: MujocoBackend) -> None:
        """MuJoCo: set the objects' state in ``sim.data`` at episode start (the robot is
        already at home, kinematics computed)."""

    # ------------------------------------------------------------------ neutral
    @abstractmethod
    def is_success(self, scene: SceneState) -> bool:
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

"""RMB's MujocoUR5eParticle: scoop granular particles from one container into another.

Geometry follows RMB's ``env_ur5e_particle.xml``: a source container (23 cm square inside,
walls 4 cm above the table) centred at (-0.05, 0.1), a goal container (15 cm square inside) at
(0.05, -0.2), and a free scoop (8.4 x 8.2 cm plate with 2 cm walls on its back and sides, open
towards +x, and a 6 cm upright handle behind the back wall) lying on the table at
(-0.15, -0.15). As in RMB the scoop starts on the table, not in the hand (RMB's operation grasps
its handle before the demonstration starts; here that grasp is part of the episode). Only the
source container and its particles move: in y from 0 to +0.20 m across the six worlds (the
random shift moves them in x and y).

The particles are 1 cm spheres that translate but do not rotate (three slide joints each),
like the bodies of MuJoCo's ``composite type="particle"`` that RMB uses: they slide like grains
instead of rolling away, and have half the degrees of freedom of free spheres. RMB drops 192 of
them into the source container; here ``particle_grid`` places 30 at rest in a block in its +x
half (the scoop goes in behind them), because every moving particle adds contacts to the
solver and a few dozen are plenty for a criterion that needs three. How MuJoCo builds and
speeds them up: :mod:`rmb_lerobot.envs.mujoco.tasks.particle`.

Success is RMB's ``_get_success``: at least three particle centres lie within 0.08 m of the
goal container's centre on every axis. As in RMB that centre is 4 cm below the table top (the
middle of walls that reach 4 cm below and above it), so a particle counts when it is inside
the container below the top of its walls, not while it rests on a rim or is held above it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, ClassVar

import numpy as np

from rmb_lerobot.envs.tasks.base import StartPoses, Task
from rmb_lerobot.envs.workspace import RMB_TABLE, Workspace

if TYPE_CHECKING:
    from rmb_lerobot.envs.scene import SceneState

SOURCE = "source_case"
GOAL = "goal_case"
SCOOP = "scoop"  # the body and its free joint
SCOOP_HANDLE = "scoop_handle"
PARTICLE = "particle"  # bodies particle_<i>
CASE_HEIGHT = 0.04  # walls above the table
CASE_CENTRE_BELOW_TABLE = 0.04  # RMB's container origin: its walls' centre
CASE_WALL_HALF_THICKNESS = 0.005
SOURCE_HALF_SIDE = 0.12  # wall centre lines from the container's centre
GOAL_HALF_SIDE = 0.08
SCOOP_PLATE_HALF = (0.042, 0.041, 0.001)
SCOOP_WALL_HEIGHT = 0.02
# A smooth scoop: against the particles (MuJoCo takes the larger of two friction coefficients)
# the particles' 0.5 applies, so they slide out once it tilts beyond ~27 degrees.
SCOOP_FRICTION = 0.4
HANDLE_HALF = (0.008, 0.008, 0.03)
HANDLE_POS = (-0.05, 0.0, 0.025)  # in the scoop frame (origin: the plate's centre)
PARTICLE_RADIUS = 0.01
GOAL_HALF_EXTENTS = np.array([0.08, 0.08, 0.08])
SUCCESS_COUNT = 3


def count_in_goal(particles: np.ndarray, goal_centre: np.ndarray) -> int:
    """How many particle centres (n, 3) lie in RMB's goal box around ``goal_centre``."""
    inside = np.all(np.abs(np.asarray(particles) - goal_centre) <= GOAL_HALF_EXTENTS, axis=1)
    return int(inside.sum())


class ParticleTask(Task):
    """``particle_grid`` (along x, y; layers) particles ``particle_spacing`` apart (centre to
    centre), the block's centre ``particle_block_offset`` (x, y) from the source's centre."""

    name = "particle"
    description = "Scoop the particles from the source container into the goal container."
    world_offsets = np.array([[0.0, y, 0.0] for y in (0.0, 0.04, 0.08, 0.12, 0.16, 0.20)])
    max_episode_steps = 700
    # RMB's MujocoUR5eParticleEnv start pose (the Cable pose with the wrist turned by pi / 2).
    start_poses: ClassVar[StartPoses] = {
        "ur5e": ((np.pi, -np.pi / 2, -0.75 * np.pi, -0.25 * np.pi, np.pi / 2, np.pi),)
    }
    particle_grid = (5, 6, 1)
    particle_spacing = 0.0205  # a little over a diameter: the particles start apart, at rest
    particle_block_offset = np.array([0.06, 0.0])
    particle_friction = 0.5

    def __init__(self, workspace: Workspace = RMB_TABLE) -> None:
        super().__init__(workspace)
        table = workspace.table
        self.source_nominal_pos = table.on_top(-0.05, 0.1, -CASE_CENTRE_BELOW_TABLE)
        self.goal_pos = table.on_top(0.05, -0.2, -CASE_CENTRE_BELOW_TABLE)
        self.scoop_pos = table.on_top(-0.15, -0.15, SCOOP_PLATE_HALF[2])

    @property
    def particle_names(self) -> tuple[str, ...]:
        return tuple(f"{PARTICLE}_{i}" for i in range(self.num_particles))

    @property
    def num_particles(self) -> int:
        return int(np.prod(self.particle_grid))

    def particle_start_positions(self, source_pos: np.ndarray) -> np.ndarray:
        """Particle centres (n, 3) at the start, for the source container at ``source_pos``."""
        nx, ny, nz = self.particle_grid
        s = self.particle_spacing
        xs, ys = ((np.arange(n) - (n - 1) / 2) * s for n in (nx, ny))
        zs = PARTICLE_RADIUS + np.arange(nz) * s
        grid = np.array([(x, y, z) for z in zs for x in xs for y in ys])
        floor = np.array(
            [*(source_pos[:2] + self.particle_block_offset), self.workspace.table.top_z]
        )
        return floor + grid

    def particle_positions(self, scene: SceneState) -> np.ndarray:
        """World positions of the particle centres (n, 3)."""
        return scene.body_positions(self.particle_names)

    def is_success(self, scene: SceneState) -> bool:
        goal, _ = scene.body_pose(GOAL)
        return count_in_goal(self.particle_positions(scene), goal) >= SUCCESS_COUNT

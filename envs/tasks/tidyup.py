"""RMB's MujocoHsrTidyup: put two bottles, standing on the floor, each into its container.

Geometry follows RMB's ``env_hsr_tidyup.xml``: the robot starts at the origin facing +x; two
free bottles (5 x 5 x 14 cm boxes whose body origin is the centre of the bottom face, starting
1 cm above the floor) at (0.7, +0.08) (``bottle1``) and (0.7, -0.08) (``bottle2``); two open
containers (20 x 30 cm floor, 12 cm walls, origin at the centre of the bottom) at (1.0, 0)
(``container1``) and (1.2, 0) (``container2``). As in RMB only the bottles move: both together,
in y from -0.06 to +0.09 m across the six worlds (``bottle_pos_offsets``).

RMB's ``_get_reward`` gives 0.5 per bottle whose origin is within (0.1, 0.15, 0.08) m of its own
container's origin on every axis (:meth:`TidyUpTask.reward`); success is the full reward, both
bottles in their containers.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from rmb_lerobot.envs.tasks.base import Task
from rmb_lerobot.envs.workspace import HSR_FLOOR, Workspace

if TYPE_CHECKING:
    from rmb_lerobot.envs.scene import SceneState

BOTTLES = ("bottle1", "bottle2")  # bodies and (with ``_freejoint``) their free joints
CONTAINERS = ("container1", "container2")  # bottle i belongs into container i
BOTTLE_HALF_SIZE = (0.025, 0.025, 0.07)
BOTTLE_START_HEIGHT = 0.01  # body origin above the floor at the start (RMB's)
BOTTLE_XY = ((0.7, 0.08), (0.7, -0.08))
CONTAINER_XY = ((1.0, 0.0), (1.2, 0.0))
CONTAINER_HALF_SIZE = (0.1, 0.15)  # outer half extents in x and y
CONTAINER_FLOOR_HALF_THICKNESS = 0.005
CONTAINER_WALL_HALF = (0.005, 0.06)  # wall half thickness and half height
CONTAINER_INSIDE = np.array([0.1, 0.15, 0.08])  # RMB's container_half_extents
REWARD_PER_BOTTLE = 0.5


class TidyUpTask(Task):
    name = "tidyup"
    description = "Put each bottle into its container."
    world_offsets = np.array([[0.0, y, 0.0] for y in (-0.06, -0.03, 0.0, 0.03, 0.06, 0.09)])
    max_episode_steps = 1500

    def __init__(self, workspace: Workspace = HSR_FLOOR) -> None:
        super().__init__(workspace)
        floor = workspace.table
        self.bottle_nominal_pos = tuple(
            floor.on_top(x, y, BOTTLE_START_HEIGHT) for x, y in BOTTLE_XY
        )
        self.container_pos = tuple(floor.on_top(x, y) for x, y in CONTAINER_XY)

    def bottles_in_place(self, scene: SceneState) -> tuple[bool, ...]:
        """Per bottle: its origin is inside its container's box (RMB's test)."""
        return tuple(
            bool(
                np.all(
                    np.abs(scene.body_pose(bottle)[0] - scene.body_pose(container)[0])
                    <= CONTAINER_INSIDE
                )
            )
            for bottle, container in zip(BOTTLES, CONTAINERS, strict=True)
        )

    def reward(self, scene: SceneState) -> float:
        """RMB's reward: 0.5 per bottle in its own container."""
        return REWARD_PER_BOTTLE * sum(self.bottles_in_place(scene))

    def is_success(self, scene: SceneState) -> bool:
        return all(self.bottles_in_place(scene))

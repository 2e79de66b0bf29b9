"""RMB's MujocoG1Bottles: two bottles on the table in front of the Unitree G1, one per hand.

Scene from RMB's ``assets/mujoco/envs/g1/env_g1_bottles.xml``: two free cylinders of 3 cm radius
and 14 cm height (MuJoCo's default density: 0.40 kg each), ``bottle1`` (blue) at (-0.7, +0.1)
and ``bottle2`` (pink) at (-0.7, -0.1), 0.3 m in front of the robot's pelvis, on the table of
:data:`~rmb_lerobot.envs.workspace.G1_TABLE` (here the bottles stand on the top; RMB starts
them 1 cm above it and lets them drop). RMB's Bottles has one world (its ``modify_world``
changes nothing); the env's random shift moves both bottles together in x and y.

Success: RMB gives this env no reward, so one is defined here from what the scene is for (one
bottle for each hand): both bottles held up at once, each with its bottom at least
:attr:`BottlesTask.lift_height` (10 cm) above the table top and its axis within
:attr:`BottlesTask.max_tilt` (30 deg) of vertical (lifted upright, not knocked over or dragged
up by its rim).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from rmb_lerobot.envs.tasks.base import Task
from rmb_lerobot.envs.workspace import G1_TABLE, Workspace

if TYPE_CHECKING:
    from rmb_lerobot.envs.scene import SceneState

BOTTLES = ("bottle1", "bottle2")  # bodies (and free joints): the left hand's, the right hand's
BOTTLE_RADIUS = 0.03
BOTTLE_HALF_HEIGHT = 0.07
BOTTLE_XY = ((-0.7, 0.1), (-0.7, -0.1))  # env_g1_bottles.xml, world frame
BOTTLE_RGBA = ((0.1, 0.5, 0.8, 1.0), (0.8, 0.1, 0.5, 1.0))


class BottlesTask(Task):
    name = "bottles"
    description = "Pick up both bottles, one with each hand, and hold them up."
    world_offsets = np.zeros((1, 3))  # RMB's one world
    max_episode_steps = 300
    lift_height = 0.10  # m, bottle bottom above the table top
    max_tilt = np.deg2rad(30.0)

    def __init__(self, workspace: Workspace = G1_TABLE) -> None:
        super().__init__(workspace)
        # Body origins at the bottles' bottom centres, standing on the table top.
        self.nominal_positions = tuple(workspace.table.on_top(x, y) for x, y in BOTTLE_XY)

    def lifted(self, scene: SceneState, bottle: str) -> bool:
        """Whether ``bottle`` is up by :attr:`lift_height` and upright within
        :attr:`max_tilt`."""
        pos, rot = scene.body_pose(bottle)
        up = float(np.clip(rot[2, 2], -1.0, 1.0))
        high = pos[2] - self.workspace.table.top_z >= self.lift_height
        return bool(high and np.arccos(up) <= self.max_tilt)

    def is_success(self, scene: SceneState) -> bool:
        return all(self.lifted(scene, bottle) for bottle in BOTTLES)

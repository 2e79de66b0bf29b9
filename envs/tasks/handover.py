"""RMB's MujocoAlohaHandover: one arm picks an object up, hands it to the other arm, which
sets it down on the second mat.

Geometry follows RMB's ``env_aloha_handover.xml`` (positions on the ALOHA table, world frame):
a free object (an 8 x 8 x 2 cm base plate with a 3 x 3 x 14 cm handle standing on it) on a
20 cm yellow mat (``mat1``) at (0.22, 0.22), in front of the left arm; a cyan mat (``mat2``)
at (-0.22, -0.22), in front of the right arm. Across the six worlds the object and its mat move
along -y by 0..0.10 m and the second mat by the opposite amount (``modify_world``); a random
shift moves them the same way (RMB adds it to the same offset).

Success is RMB's ``_get_reward`` at its full reward: the centre of the object's base plate
(geom ``obj_base``) within (0.1, 0.1, 0.08) m of ``mat2``'s origin on every axis, i.e. the
object stands on the second mat. (RMB's partial rewards, 0.5 with the handle within 0.1 m of
the right gripper and 0.2 of the left, mark progress, not success.)
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from rmb_lerobot.envs.tasks.base import Task
from rmb_lerobot.envs.workspace import RMB_TABLE, Workspace

if TYPE_CHECKING:
    from rmb_lerobot.envs.scene import SceneState

OBJECT = "obj"  # the body; its free joint is OBJECT_JOINT
OBJECT_JOINT = "obj_freejoint"
OBJECT_BASE, OBJECT_HANDLE = "obj_base", "obj_handle"
MAT1, MAT2 = "mat1", "mat2"
BASE_HALF_SIZE = (0.04, 0.04, 0.01)
BASE_Z = 0.01  # base plate centre above the object's origin
HANDLE_HALF_SIZE = (0.015, 0.015, 0.07)
HANDLE_Z = 0.08  # handle centre above the object's origin
OBJECT_HEIGHT = 0.005  # the object's origin above the table top
MAT_HALF_SIZE = (0.1, 0.1, 0.001)
OBJECT_XY, MAT2_XY = (0.22, 0.22), (-0.22, -0.22)  # on the table (world x, y)
MAT2_HALF_EXTENTS = np.array([0.1, 0.1, 0.08])  # RMB's success box around mat2 (m)


class HandoverTask(Task):
    """RMB's Handover on the ALOHA table: the object and mat1 shift by the world's offset, mat2
    by its opposite."""

    name = "handover"
    description = "Pick up the object, hand it over to the other arm and place it on the blue mat."
    world_offsets = np.array([[0.0, -0.02 * i, 0.0] for i in range(6)])
    max_episode_steps = 600

    def __init__(self, workspace: Workspace = RMB_TABLE) -> None:
        super().__init__(workspace)
        table = workspace.table
        self.object_nominal_pos = table.on_top(*OBJECT_XY, OBJECT_HEIGHT)
        self.mat1_nominal_pos = table.on_top(*OBJECT_XY)
        self.mat2_nominal_pos = table.on_top(*MAT2_XY)

    def is_success(self, scene: SceneState) -> bool:
        base, _ = scene.geom_pose(OBJECT_BASE)
        mat2, _ = scene.body_pose(MAT2)
        return bool(np.all(np.abs(base - mat2) <= MAT2_HALF_EXTENTS))

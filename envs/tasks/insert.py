"""RMB's MujocoUR5eInsert: put a square peg, held in the gripper, into a square hole.

As in RMB the peg starts in the hand, held by a weld to the gripper (so the task is about
placing, not grasping, and the gripper command does not matter), with contacts between the
peg and the robot excluded. The hole (5 cm opening, 4 cm deep, for a 3 cm peg) sits on the
table and moves in y from -0.06 to +0.09 m across the six worlds. Success: the peg's centre is
within 0.012 m of the hole's axis in xy, its lower end is at most 0.01 m above the hole's floor
(inserted at least 3 cm) and its axis is within 10 degrees of vertical.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from rmb_lerobot.envs.tasks.base import Task
from rmb_lerobot.envs.workspace import RMB_TABLE, Workspace

if TYPE_CHECKING:
    from rmb_lerobot.envs.scene import SceneState

PEG = "peg"
HOLE = "hole"
PEG_HALF_WIDTH = 0.015
PEG_HALF_LENGTH = 0.04
HOLE_DEPTH = 0.04
HOLE_OPENING_HALF_WIDTH = 0.025
# Peg centre along the gripper's base-mount z axis (RMB welds it 0.17 m from the flange).
PEG_OFFSET_FROM_MOUNT = 0.163


class InsertTask(Task):
    name = "insert"
    description = "Insert the square peg into the hole."
    world_offsets = np.array([[0.0, y, 0.0] for y in (-0.06, -0.03, 0.0, 0.03, 0.06, 0.09)])
    max_episode_steps = 300
    xy_tolerance = 0.012
    depth_tolerance = 0.01
    max_tilt_deg = 10.0

    def __init__(self, workspace: Workspace = RMB_TABLE) -> None:
        super().__init__(workspace)
        self.hole_nominal_pos = workspace.table.on_top(-0.08, -0.08)

    def is_success(self, scene: SceneState) -> bool:
        centre, rot = scene.body_pose(PEG)
        hole_pos, _ = scene.body_pose(HOLE)
        axis = rot[:, 2]
        xy_ok = np.linalg.norm(centre[:2] - hole_pos[:2]) <= self.xy_tolerance
        lower_end_z = centre[2] - PEG_HALF_LENGTH * abs(axis[2])
        depth_ok = lower_end_z <= hole_pos[2] + self.depth_tolerance
        tilt_ok = abs(axis[2]) >= np.cos(np.deg2rad(self.max_tilt_deg))
        return bool(xy_ok and depth_ok and tilt_ok)

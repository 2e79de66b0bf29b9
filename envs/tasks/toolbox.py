"""RMB's MujocoUR5eToolbox: grasp a toolbox by its handle and place it onto a mat.

Geometry follows RMB's ``env_ur5e_toolbox.xml``: a free 12 x 12 x 8 cm box whose body origin
is the centre of its bottom face, with a handle on top (two posts 5 cm apart and a 16 x 16 mm
bar 11.2-12.8 cm above the bottom, 3.2 cm over the lid: fits the Robotiq 2F-85's 85 mm
opening and leaves room for its fingers). The toolbox stands at (0, -0.2) turned by 90 degrees
(bar along world x); the mat (16 cm yellow square on a 24 cm purple one, 3 mm thick) lies at
(0, +0.2). As in RMB only the toolbox moves: in y from -0.06 to +0.09 m across the six worlds.
The random shift is applied in x and y only (RMB also shifts the start height, which drops the
box onto the table or starts it inside it).

Success is RMB's ``_get_reward`` (pick-and-place, not just picking): the toolbox origin is
within 0.03 m of the mat's origin in x and in y and less than 0.005 m above it, i.e. the box
rests on the mat (its bottom is then 3 mm above the mat origin).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, ClassVar

import numpy as np

from rmb_lerobot.envs.tasks.base import StartPoses, Task
from rmb_lerobot.envs.workspace import RMB_TABLE, Workspace

if TYPE_CHECKING:
    from rmb_lerobot.envs.scene import SceneState

TOOLBOX = "toolbox"  # the body and its free joint
MAT = "mat"
HANDLE = "toolbox_handle"
BOX_HALF_SIZE = (0.06, 0.06, 0.04)
HANDLE_POST_Y = 0.03  # posts at +-y in the toolbox frame
HANDLE_HEIGHT = 0.12  # bar axis above the toolbox origin (its bottom face)
HANDLE_HALF_WIDTH = 0.008  # bar half-size across its axis (16 mm square section)
HANDLE_HALF_LENGTH = 0.04
# Mat layers: (half side, centre height above the mat origin, colour), each 2 mm thick.
MAT_LAYERS = ((0.08, 0.002, (0.8, 0.8, 0.1, 1.0)), (0.12, 0.001, (0.6, 0.0, 0.4, 1.0)))
MAT_HALF_THICKNESS = 0.001
MAT_TOP = 0.003  # top of the upper layer above the mat origin


class ToolboxTask(Task):
    name = "toolbox"
    description = "Grasp the handle of the toolbox and move it onto the mat."
    world_offsets = np.array([[0.0, y, 0.0] for y in (-0.06, -0.03, 0.0, 0.03, 0.06, 0.09)])
    max_episode_steps = 400
    # RMB's MujocoUR5eToolboxEnv start pose: the Insert pose with the wrist turned by pi / 2.
    start_poses: ClassVar[StartPoses] = {
        "ur5e": ((np.pi, -np.pi / 2, -0.55 * np.pi, -0.45 * np.pi, np.pi / 2, np.pi),)
    }
    toolbox_quat = np.array([np.cos(np.pi / 4), 0.0, 0.0, np.sin(np.pi / 4)])  # yaw 90 deg
    xy_tolerance = 0.03
    z_tolerance = 0.005

    def __init__(self, workspace: Workspace = RMB_TABLE) -> None:
        super().__init__(workspace)
        self.toolbox_nominal_pos = workspace.table.on_top(0.0, -0.2)
        self.mat_pos = workspace.table.on_top(0.0, 0.2)

    def is_success(self, scene: SceneState) -> bool:
        toolbox, _ = scene.body_pose(TOOLBOX)
        mat, _ = scene.body_pose(MAT)
        xy_ok = np.max(np.abs(toolbox[:2] - mat[:2])) < self.xy_tolerance
        return bool(xy_ok and toolbox[2] < mat[2] + self.z_tolerance)

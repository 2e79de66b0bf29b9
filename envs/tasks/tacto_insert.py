"""RMB's TactoSawyerInsert: pull a board from between two blocks and stand it in a slot box.

RMB's ``TactoSawyerInsertEnv``: a thin board (``board.urdf``, a .008 x .05 x .29 box loaded at
``global_scaling`` 0.6: 4.8 x 30 x 174 mm, 0.2 kg, a tactile body) stands on the floor at
(0.505, -0.03, 0.077), clamped between two fixed blocks (``cube.urdf``, .03 x .03 x .136 at
scale 0.68: 20.4 x 20.4 x 92.5 mm) at (0.493, -0.03, 0.03) and (0.517, -0.03, 0.03); a fixed
slot box (``box.obj`` rotated rpy (pi/2, 0, pi/2), scale 0.6: 36 x 120 x 120 mm outside, the
slot's narrow side along world x, its long side along y, open at the top) stands at
(0.505, 0.2, 0.05). Five worlds (RMB's ``modify_world``): the board shifted in x and z and
pitched about y by +40 .. -40 deg, leaning on one block, the other block moved below it as a
stop (RMB's ``cube1_pos_offsets`` / ``cube2_pos_offsets``). Success (RMB's reward): the board's
centre within 1 cm of the box's centre in x, 7 cm in y, and below 0.1 m, i.e. stood in the
slot (its centre is 0.087 m high standing in the slot, 0.197 m on the box's rim).

The Sawyer's home hangs the gripper above the board with the fingers closing along world y, so
the pads squeeze the board's 30 mm width (its two 4.8 mm edges), as RMB's pre-motion does.

Random shift: RMB adds it to the board alone (on x, y and z), which with blocks 0.4 mm from the
board pushes the board into a block; here it moves the board and both blocks together, in x
and y only (:attr:`TactoInsertTask.shift_axes`), so every shifted world is RMB's world moved.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, ClassVar

import numpy as np

from rmb_lerobot.envs.tasks.base import StartPoses, Task
from rmb_lerobot.envs.workspace import TACTO_FLOOR, Workspace

if TYPE_CHECKING:
    from rmb_lerobot.envs.scene import SceneState

# Body names (RMB's attribute names).
BOARD = "board"
CUBE1 = "cube1"
CUBE2 = "cube2"
BOX = "box"

RMB_SCALE_BOARD = 0.6  # board.urdf and box.urdf's global_scaling
RMB_SCALE_CUBE = 0.68  # cube.urdf's global_scaling
BOARD_HALF_SIZE = (0.0024, 0.015, 0.087)  # .008 x .05 x .29 x 0.6, halved
BOARD_MASS = 0.2  # kg (board.urdf; pybullet does not scale the mass)
BOARD_POS = (0.505, -0.03, 0.077)  # RMB's base_position; every world offsets it
CUBE_HALF_SIZE = (0.0102, 0.0102, 0.04624)  # .03 x .03 x .136 x 0.68, halved
CUBE1_POS = (0.493, -0.03, 0.03)
CUBE2_POS = (0.517, -0.03, 0.03)
BOX_POS = (0.505, 0.2, 0.05)

# The slot box in the world frame (box.obj's vertices x 0.6, its mesh axes (x, y, z) turned by
# the rpy (pi/2, 0, pi/2) onto world (y, z, x)): outside +-(0.1, 0.1, 0.03) mesh = 36 x 120 x
# 120 mm. The cavity opens at mesh +y (world up) with +-(0.085858, 0.015858) in mesh (x, z) and
# widens to +-(0.088453, 0.018453) at its floor, mesh y = -0.088453: the walls here are
# straight at the opening's size (what a board must pass), the floor at the mesh's depth. The
# box's centre is 0.05 m high, so like RMB's it sinks 1 cm into the ground and its cavity floor
# 3 mm: a board in the slot stands on the ground.
BOX_HALF_SIZE = (0.018, 0.06, 0.06)
SLOT_HALF_SIZE = (0.015858 * 0.6, 0.085858 * 0.6)  # (x, y) at the opening: 9.5 x 51.5 mm
SLOT_FLOOR_Z = -0.088453 * 0.6  # cavity floor below the box centre: -53.1 mm (world z)

# RMB's per-world tables (TactoSawyerInsertEnv.py): board translation, board pitch, blocks.
BOARD_OFFSETS = np.array(
    [
        [-0.043, 0.0, -0.009],
        [-0.015, 0.0, 0.005],
        [0.0, 0.0, 0.01],
        [0.015, 0.0, 0.005],
        [0.04, 0.0, -0.009],
    ]
)
BOARD_PITCH_DEG = np.array([40.0, 20.0, 0.0, -20.0, -40.0])  # about world y (RMB's euler xyz)
CUBE1_OFFSETS = np.array(
    [
        [-0.099, 0.0, -0.05],
        [-0.045, 0.0, -0.05],
        [-0.001, 0.0, 0.0],
        [0.016, 0.0, 0.0],
        [0.031, 0.0, 0.0],
    ]
)
CUBE2_OFFSETS = np.array(
    [
        [-0.034, 0.0, 0.0],
        [-0.016, 0.0, 0.0],
        [0.001, 0.0, 0.0],
        [0.045, 0.0, -0.05],
        [0.096, 0.0, -0.05],
    ]
)


class TactoInsertTask(Task):
    """Stand the board in the slot box: its centre over the box and below 0.1 m."""

    name = "insert"
    description = "Pull the board out from between the blocks and insert it into the box."
    world_offsets = BOARD_OFFSETS
    shift_axes = np.array([1.0, 1.0, 0.0])  # board and blocks move together (module doc)
    # 12 s at 33 Hz; the expert needs 243 steps on average, 281 at most (100 episodes of the
    # five worlds, and 25 with a 3 cm random shift).
    max_episode_steps = 400
    max_dx = 0.01  # board centre to box centre, |x| (m), RMB's
    max_dy = 0.07  # |y| (m), RMB's
    max_z = 0.1  # board centre height (m), RMB's
    start_poses: ClassVar[StartPoses] = {}

    def __init__(self, workspace: Workspace = TACTO_FLOOR) -> None:
        super().__init__(workspace)
        table = workspace.table
        self.board_nominal_pos = table.on_top(*BOARD_POS)
        self.cube_nominal_pos = (table.on_top(*CUBE1_POS), table.on_top(*CUBE2_POS))
        self.box_pos = table.on_top(*BOX_POS)

    def board_pitch(self, world_idx: int) -> float:
        """The board's pitch about world y in world ``world_idx`` (radians)."""
        return float(np.deg2rad(BOARD_PITCH_DEG[world_idx]))

    def cube_offsets(self, world_idx: int) -> tuple[np.ndarray, np.ndarray]:
        """RMB's offsets of the two blocks in world ``world_idx`` (m)."""
        return CUBE1_OFFSETS[world_idx].copy(), CUBE2_OFFSETS[world_idx].copy()

    def is_success(self, scene: SceneState) -> bool:
        (x, y, z), _ = scene.body_pose(BOARD)
        (xb, yb, _), _ = scene.body_pose(BOX)
        return bool(abs(x - xb) < self.max_dx and abs(y - yb) < self.max_dy and z < self.max_z)

"""RMB's TactoSawyerSpoon: sort a transparent spoon into the box its orientation calls for.

RMB's ``TactoSawyerSpoonEnv`` (PyBullet, DIGIT fingertips): a spoon stands upright in a blue
start box at (0.8, 0, .), wedged between the box's -y wall and an invisible fixed block. World 0
stands it bowl down (handle up), world 1 bowl up (handle down); the goal is the red box at
(0.8, +0.3) in world 0 and the green box at (0.8, -0.3) in world 1. The spoon is nearly
invisible (RMB's alpha 0.1), so the camera barely tells which end is up: the fingertip sensors,
which feel a narrow handle or a wide bowl, do.

Geometry (RMB's ``objects/spoon``): every box URDF is loaded at ``global_scaling`` 0.4: a floor
(0.3 x 0.3 x 0.1 collision box 0.15 below the frame) and four walls 0.025 x 0.3 x 0.5 at
+-0.1455, so a box whose frame is at height 0.1 has its floor's top at 0.06, walls 0.01 thick
from 0 to 0.2 m, and an inside 0.1064 m square. The block (``cube.urdf``, .06 x .03 x .136 at
scale 0.68, alpha 0) stands at (0.78, -0.025, 0.1) inside the start box. The spoon mesh at scale
0.06 is a flat spoon 0.229 m long: an elliptic bowl 48 x 72 mm and a handle narrowing from 16.8
to 9.4 mm, 4.8 mm thick; its body frame (RMB's link origin, also its centre of mass) is the bowl's
centre on one face, the handle along the frame's +y, the thickness along +z.

Success (RMB's ``_get_reward``): the spoon's frame within +-0.12 m (0.3 x scaling) of the goal
box's frame in x and y, and below ``0.75 * 0.4 - 0.1 = 0.2`` m in world 0 (bowl down: the bowl
centre sits at about 0.1 in the box) or ``0.75 * 0.4 + 0.1 = 0.4`` m in world 1.

At rest (2 s with the robot at its start pose; RMB's poses are a few millimetres above the floor)
the spoon stands on its bowl 4 mm lower and upright in world 0, leaning 2 deg onto the block's
top edge; in world 1 it stands on its handle's tip and tips 8 mm towards the robot, resting on
the top edges of the -x and -y walls (measured contacts).

Placement: :attr:`TactoSpoonTask.world_offsets` are zero; the per-world spoon poses are the
tables :data:`SPOON_POSITIONS` / :data:`SPOON_RPY_DEG` (RMB's). An env's random shift moves the
spoon, the start box and the block together (RMB moves the spoon and the start box and leaves
the block behind, which then no longer holds the spoon upright).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, ClassVar

import numpy as np

from rmb_lerobot.envs.tasks.base import StartPoses, Task
from rmb_lerobot.envs.workspace import TACTO_SPOON_FLOOR, Workspace

if TYPE_CHECKING:
    from rmb_lerobot.envs.scene import SceneState

SPOON = "spoon"
START_BOX = "start_box"
GREEN_BOX = "green_box"
RED_BOX = "red_box"
BLOCK = "block"  # RMB's invisible ``cube``: keeps the spoon upright against the -y wall

# ---------------------------------------------------------------- the spoon (RMB mesh x 0.06)
SPOON_MASS = 0.01  # kg, RMB's spoon.urdf
BOWL_HALF_WIDTH = 0.024  # across the spoon (frame x)
BOWL_HALF_LENGTH = 0.036  # along the spoon (frame y), centred on the frame
HANDLE_END = 0.1933  # frame y of the handle's tip
HANDLE_WIDTH_AT_BOWL = 0.0168
HANDLE_WIDTH_AT_TIP = 0.0094
SPOON_THICKNESS = 0.0048  # frame z from 0 to this
SPOON_LENGTH = HANDLE_END + BOWL_HALF_LENGTH  # 0.229 m

# Per world: the spoon frame's position and roll-pitch-yaw (degrees, PyBullet's extrinsic x-y-z
# Euler angles), RMB's ``spoon_positions`` / ``spoon_orientations_rpy``. Roll +90 points the
# handle (frame +y) up, roll -90 points it down; pitch -5 leans the top end towards the robot.
SPOON_POSITIONS = np.array([[0.775, -0.04, 0.1], [0.755, -0.05, 0.25]])
SPOON_RPY_DEG = np.array([[90.0, -5.0, 0.0], [-90.0, -5.0, 0.0]])

# ---------------------------------------------------------------- boxes (RMB URDF x 0.4)
BOX_SCALING = 0.4
START_BOX_POS = (0.8, 0.0, 0.1)
GREEN_BOX_POS = (0.8, -0.3, 0.1)
RED_BOX_POS = (0.8, 0.3, 0.1)
BOX_FLOOR_HALF = (0.06, 0.06, 0.02)  # 0.3 x 0.3 x 0.1 x 0.4, halved
BOX_FLOOR_Z = -0.06  # floor centre below the box frame (RMB's collision origin -0.15 x 0.4)
BOX_WALL_HALF = (0.005, 0.06, 0.1)  # 0.025 x 0.3 x 0.5 x 0.4, halved (x-facing walls)
BOX_WALL_OFFSET = 0.0582  # wall centres from the box frame (0.1455 x 0.4)
BOX_WALL_TOP = 0.2  # world height of the walls' tops (frame at 0.1, half height 0.1)
BOX_INNER_HALF = BOX_WALL_OFFSET - BOX_WALL_HALF[0]  # 0.0532 m
BOX_FLOOR_TOP = START_BOX_POS[2] + BOX_FLOOR_Z + BOX_FLOOR_HALF[2]  # 0.06 m

BLOCK_HALF = (0.0204, 0.0102, 0.04624)  # .06 x .03 x .136 x 0.68, halved
BLOCK_POS = (0.78, -0.025, 0.1)

# ---------------------------------------------------------------- success (RMB's reward)
GOAL_BOXES = (RED_BOX, GREEN_BOX)  # per world_idx, RMB's ``goal_boxes`` order
GOAL_BOX_POSITIONS = (RED_BOX_POS, GREEN_BOX_POS)
GOAL_HALF_WIDTH = 0.3 * BOX_SCALING  # 0.12 m
GOAL_HEIGHT = 0.75 * BOX_SCALING  # 0.3 m
GOAL_MAX_Z = (GOAL_HEIGHT - 0.1, GOAL_HEIGHT + 0.1)  # per world_idx: 0.2 m, 0.4 m


def spoon_quat_wxyz(world_idx: int) -> np.ndarray:
    """The spoon's start orientation in world ``world_idx`` as a ``(w, x, y, z)`` quaternion.

    PyBullet's ``getQuaternionFromEuler`` convention (rotate about x, then y, then z, all about
    the fixed axes), written out so this module needs no simulator.
    """
    roll, pitch, yaw = np.deg2rad(SPOON_RPY_DEG[world_idx]) / 2
    cr, sr, cp, sp, cy, sy = (
        np.cos(roll),
        np.sin(roll),
        np.cos(pitch),
        np.sin(pitch),
        np.cos(yaw),
        np.sin(yaw),
    )
    return np.array(
        [
            cr * cp * cy + sr * sp * sy,
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
        ]
    )


class TactoSpoonTask(Task):
    """Put the spoon into the red box if it stands bowl down, the green box if bowl up."""

    name = "spoon"
    description = (
        "Pick the spoon out of the blue box and put it into the red box if its bowl is down, "
        "or into the green box if its bowl is up."
    )
    world_offsets = np.zeros((2, 3))  # the per-world poses are SPOON_POSITIONS / SPOON_RPY_DEG
    # 15 s at 33 Hz. The expert succeeds after 205 to 245 steps (6 to 7.5 s) and has let go
    # of the spoon by step 245 to 290 (measured, 100 episodes per action mode).
    max_episode_steps = 500
    # RMB's TactoSawyerSpoonEnv start pose (the fingers at +-0.02, the record's home gripper).
    start_poses: ClassVar[StartPoses] = {"sawyer": ((0.1, -1.37, -0.68, 1.7, 0.2, 1.3, 1.1),)}

    def __init__(self, workspace: Workspace = TACTO_SPOON_FLOOR) -> None:
        super().__init__(workspace)

    def is_success(self, scene: SceneState) -> bool:
        """RMB's reward: the spoon's frame over this world's goal box and low enough.

        Returns:
            True when the spoon frame's x and y are within 0.12 m of the goal box's (red in
            world 0, green in world 1) and its height is below 0.2 m (world 0) or 0.4 m
            (world 1).
        """
        x, y, z = scene.body_pose(SPOON)[0]
        bx, by, _ = scene.body_pose(GOAL_BOXES[self.world_idx])[0]
        return bool(
            z < GOAL_MAX_Z[self.world_idx]
            and abs(x - bx) < GOAL_HALF_WIDTH
            and abs(y - by) < GOAL_HALF_WIDTH
        )

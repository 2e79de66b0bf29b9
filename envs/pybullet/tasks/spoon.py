"""PyBullet scene of RMB's TactoSawyerSpoon (:mod:`rmb_lerobot.envs.tasks.tacto_spoon`).

Every prop is built from boxes in code (:func:`~rmb_lerobot.envs.pybullet.tasks.base.
add_compound`), to the size of RMB's models:

- the spoon: one rigid body of seven boxes, a 48 x 72 mm bowl (three overlapping boxes that
  follow its ellipse) and a handle of three boxes narrowing from 16 to 11 mm, 4.4 to 4.8 mm thick,
  0.229 m long in all (RMB's ``vhacd_spoon.obj`` at scale 0.06); mass 0.01 kg, its frame and
  centre of mass at the bowl's centre as RMB's URDF puts them; RMB's translucent grey (alpha 0.1).
- the blue start box and the green and red goal boxes: fixed, a floor and four walls each (RMB's
  box URDFs at scale 0.4; the floor drawn where it collides, where RMB draws it 2 to 4 cm lower).
- the block: RMB's invisible fixed ``cube`` beside the spoon, which keeps it upright.

The spoon and the three boxes are seen by the fingertip sensors, as in RMB.
"""

from __future__ import annotations

from itertools import pairwise
from typing import TYPE_CHECKING

import numpy as np

from rmb_lerobot.envs.pybullet.tasks.base import PybulletTaskScene, add_box, add_compound
from rmb_lerobot.envs.tasks.tacto_spoon import (
    BLOCK,
    BLOCK_HALF,
    BLOCK_POS,
    BOWL_HALF_LENGTH,
    BOWL_HALF_WIDTH,
    BOX_FLOOR_HALF,
    BOX_FLOOR_Z,
    BOX_WALL_HALF,
    BOX_WALL_OFFSET,
    GREEN_BOX,
    GREEN_BOX_POS,
    HANDLE_END,
    HANDLE_WIDTH_AT_BOWL,
    HANDLE_WIDTH_AT_TIP,
    RED_BOX,
    RED_BOX_POS,
    SPOON,
    SPOON_MASS,
    SPOON_POSITIONS,
    SPOON_THICKNESS,
    START_BOX,
    START_BOX_POS,
    TactoSpoonTask,
    spoon_quat_wxyz,
)

if TYPE_CHECKING:
    from collections.abc import Sequence

    from rmb_lerobot.envs.pybullet.backend import PybulletBackend

Box = tuple[tuple[float, float, float], tuple[float, float, float]]

# RMB's colours: the spoon's translucent grey, the boxes' materials, the block's clear blue.
SPOON_RGBA = (0.5, 0.5, 0.5, 0.1)
BLUE = (0.0, 0.0, 0.7, 1.0)
GREEN = (0.0, 0.7, 0.0, 1.0)
RED = (0.7, 0.0, 0.0, 1.0)
CLEAR = (0.2, 0.2, 0.8, 0.0)

HANDLE_THICKNESS = 0.0044  # RMB's handle is 0.4 mm thinner than the bowl, on the same middle


def spoon_boxes() -> list[Box]:
    """The spoon as ``(half_extents, offset)`` boxes in its frame (bowl centre on the origin,
    handle along +y, thickness from z 0 to :data:`SPOON_THICKNESS`).

    The bowl's ellipse (half axes 24 x 36 mm) is three boxes whose corners lie near it (2 mm
    outside at most); the handle is three boxes, each as wide as the tapering handle at its
    middle, from inside the bowl to the tip.
    """
    mid = SPOON_THICKNESS / 2
    bowl = [
        ((BOWL_HALF_WIDTH, 0.016, mid), (0.0, 0.0, mid)),
        ((0.019, 0.027, mid), (0.0, 0.0, mid)),
        ((0.011, BOWL_HALF_LENGTH, mid), (0.0, 0.0, mid)),
    ]
    handle = []
    joints = (0.03, 0.085, 0.14, HANDLE_END)
    taper = (HANDLE_WIDTH_AT_BOWL - HANDLE_WIDTH_AT_TIP) / (HANDLE_END - BOWL_HALF_LENGTH)
    for start, end in pairwise(joints):
        centre = (start + end) / 2
        width = HANDLE_WIDTH_AT_BOWL - taper * max(centre - BOWL_HALF_LENGTH, 0.0)
        handle.append(((width / 2, (end - start) / 2, HANDLE_THICKNESS / 2), (0.0, centre, mid)))
    return bowl + handle


def box_boxes() -> list[Box]:
    """An open box (RMB's ``*_box.urdf`` at scale 0.4) in its frame: floor and four walls."""
    wall_x, wall_y, wall_z = BOX_WALL_HALF
    return [
        (BOX_FLOOR_HALF, (0.0, 0.0, BOX_FLOOR_Z)),
        ((wall_x, wall_y, wall_z), (-BOX_WALL_OFFSET, 0.0, 0.0)),
        ((wall_x, wall_y, wall_z), (BOX_WALL_OFFSET, 0.0, 0.0)),
        ((wall_y, wall_x, wall_z), (0.0, -BOX_WALL_OFFSET, 0.0)),
        ((wall_y, wall_x, wall_z), (0.0, BOX_WALL_OFFSET, 0.0)),
    ]


class SpoonScene(PybulletTaskScene[TactoSpoonTask]):
    """The spoon standing in the blue box, the green and red goal boxes, the hidden block."""

    def build(self, sim: PybulletBackend) -> None:
        cid = sim.client_id
        spoon = add_compound(
            cid, spoon_boxes(), SPOON_POSITIONS[0], mass=SPOON_MASS, rgba=SPOON_RGBA
        )
        sim.add_body(SPOON, spoon, tactile=True)
        for name, position, rgba in (
            (START_BOX, START_BOX_POS, BLUE),
            (GREEN_BOX, GREEN_BOX_POS, GREEN),
            (RED_BOX, RED_BOX_POS, RED),
        ):
            sim.add_body(name, add_compound(cid, box_boxes(), position, rgba=rgba), tactile=True)
        sim.add_body(BLOCK, add_box(cid, BLOCK_HALF, BLOCK_POS, rgba=CLEAR))

    def apply_world(self, sim: PybulletBackend, offset: np.ndarray) -> None:
        """RMB's spoon pose of the world; the start box and the block shift with the spoon."""
        world = self.task.world_idx
        sim.reset_body(SPOON, SPOON_POSITIONS[world] + offset, spoon_quat_wxyz(world))
        for name, position in ((START_BOX, START_BOX_POS), (BLOCK, BLOCK_POS)):
            sim.reset_body(name, _shifted(position, offset))


def _shifted(position: Sequence[float], offset: np.ndarray) -> np.ndarray:
    return np.asarray(position, dtype=np.float64) + offset

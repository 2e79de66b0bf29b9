"""PyBullet scene of RMB's TactoSawyerInsert (:mod:`rmb_lerobot.envs.tasks.tacto_insert`).

The board and the two blocks are boxes of RMB's scaled sizes; the slot box, a mesh in RMB
(``box.obj``), is a compound of five boxes here (a floor and four walls) with its outer size
and its cavity's opening and depth (the task module has the numbers).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pybullet as p
from scipy.spatial.transform import Rotation

from rmb_lerobot.envs.pybullet.tasks.base import PybulletTaskScene, add_box, add_compound
from rmb_lerobot.envs.tasks.tacto_insert import (
    BOARD,
    BOARD_HALF_SIZE,
    BOARD_MASS,
    BOX,
    BOX_HALF_SIZE,
    CUBE1,
    CUBE2,
    CUBE_HALF_SIZE,
    SLOT_FLOOR_Z,
    SLOT_HALF_SIZE,
    TactoInsertTask,
)

if TYPE_CHECKING:
    from collections.abc import Sequence

    from rmb_lerobot.envs.pybullet.backend import PybulletBackend

# RMB's colours: board.urdf's green (alpha 0.1 there: opaque here, so cameras see it),
# box.urdf's yellow; cube.urdf's blue is fully transparent in RMB, a visible blue here.
GREEN = (0.2, 0.8, 0.2, 1.0)
BLUE = (0.2, 0.2, 0.8, 1.0)
YELLOW = (0.6, 0.6, 0.2, 1.0)


def slot_box_parts() -> list[tuple[Sequence[float], Sequence[float]]]:
    """The slot box as ``(half_extents, offset)`` boxes about its centre: the floor under the
    cavity, two long walls (normal x) and two end walls (normal y) between them.

    Returns:
        Five boxes spanning exactly the outer box, leaving the cavity ``SLOT_HALF_SIZE`` wide
        from ``SLOT_FLOOR_Z`` up to the open top.
    """
    hx, hy, hz = BOX_HALF_SIZE
    sx, sy = SLOT_HALF_SIZE
    floor_half = (hz + SLOT_FLOOR_Z) / 2  # from the bottom (-hz) to the cavity floor
    wall_half = (hz - SLOT_FLOOR_Z) / 2  # from the cavity floor to the top (+hz)
    wall_z = SLOT_FLOOR_Z + wall_half
    side_half, end_half = (hx - sx) / 2, (hy - sy) / 2
    return [
        ((hx, hy, floor_half), (0.0, 0.0, -hz + floor_half)),
        ((side_half, hy, wall_half), (sx + side_half, 0.0, wall_z)),
        ((side_half, hy, wall_half), (-sx - side_half, 0.0, wall_z)),
        ((sx, end_half, wall_half), (0.0, sy + end_half, wall_z)),
        ((sx, end_half, wall_half), (0.0, -sy - end_half, wall_z)),
    ]


class InsertScene(PybulletTaskScene[TactoInsertTask]):
    """The board (seen by the fingertip sensors) between two fixed blocks, the fixed slot box."""

    def build(self, sim: PybulletBackend) -> None:
        cid = sim.client_id
        # Contacts are solved in sorted pair order (PhysicsSettings); with _forget_contacts an
        # episode is independent of the ones before it.
        board = add_box(
            cid, BOARD_HALF_SIZE, self.task.board_nominal_pos, mass=BOARD_MASS, rgba=GREEN
        )
        sim.add_body(BOARD, board, tactile=True)
        for name, pos in zip((CUBE1, CUBE2), self.task.cube_nominal_pos, strict=True):
            sim.add_body(name, add_box(cid, CUBE_HALF_SIZE, pos, rgba=BLUE))
        sim.add_body(BOX, add_compound(cid, slot_box_parts(), self.task.box_pos, rgba=YELLOW))

    def apply_world(self, sim: PybulletBackend, offset: np.ndarray) -> None:
        """The board at RMB's offset and pitch of the world, the blocks at theirs; the env's
        random shift (``offset`` minus the world's own) moves all three together."""
        self._forget_contacts(sim)
        world = self.task.world_idx
        shift = offset - self.task.world_offsets[world]
        pitch = Rotation.from_euler("y", self.task.board_pitch(world))
        x, y, z, w = pitch.as_quat()  # scipy: (x, y, z, w); reset_body takes (w, x, y, z)
        sim.reset_body(BOARD, self.task.board_nominal_pos + offset, (w, x, y, z))
        for name, nominal, cube_offset in zip(
            (CUBE1, CUBE2), self.task.cube_nominal_pos, self.task.cube_offsets(world), strict=True
        ):
            sim.reset_body(name, nominal + cube_offset + shift)

    @staticmethod
    def _forget_contacts(sim: PybulletBackend) -> None:
        """Drop the contacts the board and blocks kept from the last episode.

        Bullet keeps a contact manifold (with its points' last impulses, which warm-start the
        solver) for every pair of bodies whose bounding boxes overlap, across teleports. The
        board starts pressed against a block, so an episode following one that ended in the
        same world warm-started from the old contacts: the same seed gave joint readings
        1e-4 rad apart (measured; with the pairs also unsorted, 7e-6 rad after a reset without
        steps). Moving the three bodies apart and running the broadphase once deletes those
        pairs, so every episode starts from no contacts.
        """
        for k, name in enumerate((BOARD, CUBE1, CUBE2)):
            sim.reset_body(name, (10.0 * (k + 1), 10.0, 10.0))
        p.performCollisionDetection(physicsClientId=sim.client_id)

"""PyBullet scene of RMB's TactoSawyerGrasp (:mod:`rmb_lerobot.envs.tasks.tacto_grasp`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from rmb_lerobot.envs.pybullet.tasks.base import PybulletTaskScene, add_box
from rmb_lerobot.envs.tasks.tacto_grasp import (
    BOX,
    BOX_FRICTION,
    BOX_HALF_SIZE,
    BOX_MASS,
    TactoGraspTask,
)

if TYPE_CHECKING:
    from rmb_lerobot.envs.pybullet.backend import PybulletBackend

GREEN = (0.2, 0.8, 0.2, 1.0)  # RMB's cube.urdf colour


class GraspScene(PybulletTaskScene[TactoGraspTask]):
    """The green box on the floor, seen by both fingertip sensors."""

    def build(self, sim: PybulletBackend) -> None:
        body = add_box(
            sim.client_id,
            BOX_HALF_SIZE,
            self.task.box_nominal_pos,
            mass=BOX_MASS,
            rgba=GREEN,
            friction=BOX_FRICTION,
        )
        sim.add_body(BOX, body, tactile=True)

    def apply_world(self, sim: PybulletBackend, offset: np.ndarray) -> None:
        sim.reset_body(BOX, self.task.box_nominal_pos + offset)

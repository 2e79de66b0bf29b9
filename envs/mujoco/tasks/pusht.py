"""MuJoCo scene of RMB's PushT (:mod:`rmb_lerobot.envs.tasks.pusht`): the free T-block and the
drawn goal T."""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

from rmb_lerobot.envs.mujoco.tasks.base import MujocoTaskScene
from rmb_lerobot.envs.tasks.pusht import (
    BAR_HALF_SIZE,
    DENSITY,
    FRICTION,
    GOAL,
    GOAL_GREY,
    GOAL_HALF_THICKNESS,
    RED,
    STEM_HALF_SIZE,
    STEM_OFFSET,
    TBLOCK,
    TBLOCK_JOINT,
    PushTTask,
)

if TYPE_CHECKING:
    from rmb_lerobot.envs.mujoco.backend import MujocoBackend


def _yaw_quat(yaw: float) -> list[float]:
    return [np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)]


class PushTScene(MujocoTaskScene[PushTTask]):
    """The T-block (free, moved by the world's offset) and the goal T drawn without collision."""

    def build(self, spec: mujoco.MjSpec, sim: MujocoBackend) -> None:
        material = spec.add_material(name=TBLOCK)
        material.rgba = list(RED)
        material.specular = 1.0  # RMB's material: specular 1, shininess 1 (a shiny metal)
        material.shininess = 1.0
        block = spec.worldbody.add_body(
            name=TBLOCK, pos=list(self.task.block_nominal_pos), quat=_yaw_quat(self.task.block_yaw)
        )
        block.add_freejoint(name=TBLOCK_JOINT)
        goal = spec.worldbody.add_body(
            name=GOAL, pos=list(self.task.goal_pos), quat=_yaw_quat(self.task.goal_yaw)
        )
        for i, (half, y) in enumerate(((BAR_HALF_SIZE, 0.0), (STEM_HALF_SIZE, STEM_OFFSET))):
            block.add_geom(
                name=f"{TBLOCK}{i + 1}",
                type=mujoco.mjtGeom.mjGEOM_BOX,
                size=list(half),
                pos=[0.0, y, 0.0],
                density=DENSITY,
                friction=list(FRICTION),
                material=TBLOCK,
            )
            goal.add_geom(
                name=f"{GOAL}{i + 1}",
                type=mujoco.mjtGeom.mjGEOM_BOX,
                size=[half[0], half[1], GOAL_HALF_THICKNESS],
                pos=[0.0, y, 0.0],
                rgba=list(GOAL_GREY),
                contype=0,
                conaffinity=0,
            )

    def apply_world(self, sim: MujocoBackend, offset: np.ndarray) -> None:
        sim.model.body(TBLOCK).pos = self.task.block_nominal_pos + offset

    def reset_objects(self, sim: MujocoBackend) -> None:
        joint = sim.data.joint(TBLOCK_JOINT)
        joint.qpos[:3] = sim.model.body(TBLOCK).pos
        joint.qpos[3:] = _yaw_quat(self.task.block_yaw)
        joint.qvel[:] = 0.0

"""MuJoCo scene of RMB's G1 Bottles (:mod:`rmb_lerobot.envs.tasks.bottles`): two free
cylinders standing on the table."""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

from rmb_lerobot.envs.mujoco.tasks.base import MujocoTaskScene
from rmb_lerobot.envs.tasks.bottles import (
    BOTTLE_HALF_HEIGHT,
    BOTTLE_RADIUS,
    BOTTLE_RGBA,
    BOTTLES,
    BottlesTask,
)

if TYPE_CHECKING:
    from rmb_lerobot.envs.mujoco.backend import MujocoBackend


class BottlesScene(MujocoTaskScene[BottlesTask]):
    """The two bottles (free bodies, origins at their bottom centres), moved by the world's
    offset."""

    def build(self, spec: mujoco.MjSpec, sim: MujocoBackend) -> None:
        for name, pos, rgba in zip(BOTTLES, self.task.nominal_positions, BOTTLE_RGBA, strict=True):
            body = spec.worldbody.add_body(name=name, pos=list(pos))
            body.add_freejoint(name=name)
            body.add_geom(
                type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                size=[BOTTLE_RADIUS, BOTTLE_HALF_HEIGHT, 0],
                pos=[0, 0, BOTTLE_HALF_HEIGHT],
                rgba=list(rgba),
            )

    def apply_world(self, sim: MujocoBackend, offset: np.ndarray) -> None:
        for name, pos in zip(BOTTLES, self.task.nominal_positions, strict=True):
            sim.model.body(name).pos = pos + offset

    def reset_objects(self, sim: MujocoBackend) -> None:
        for name in BOTTLES:
            joint = sim.data.joint(name)
            joint.qpos[:3] = sim.model.body(name).pos
            joint.qpos[3:] = (1.0, 0.0, 0.0, 0.0)
            joint.qvel[:] = 0.0

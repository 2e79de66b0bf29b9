"""MuJoCo scene of RMB's TidyUp (:mod:`rmb_lerobot.envs.tasks.tidyup`): two free bottles and two
open containers on the floor."""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

from rmb_lerobot.envs.mujoco.tasks.base import MujocoTaskScene
from rmb_lerobot.envs.tasks.tidyup import (
    BOTTLE_HALF_SIZE,
    BOTTLES,
    CONTAINER_FLOOR_HALF_THICKNESS,
    CONTAINER_HALF_SIZE,
    CONTAINER_WALL_HALF,
    CONTAINERS,
    TidyUpTask,
)

if TYPE_CHECKING:
    from rmb_lerobot.envs.mujoco.backend import MujocoBackend

# RMB's materials' colours: bottles blue and magenta, containers green and red.
BOTTLE_RGBA = ((0.1, 0.5, 0.8, 1.0), (0.8, 0.1, 0.5, 1.0))
CONTAINER_RGBA = ((0.1, 0.5, 0.1, 1.0), (0.5, 0.1, 0.1, 1.0))


def _add_container(spec: mujoco.MjSpec, name: str, pos: np.ndarray, rgba) -> None:
    """A static open box: a floor plate and four walls (RMB's sizes)."""
    box = mujoco.mjtGeom.mjGEOM_BOX
    hx, hy = CONTAINER_HALF_SIZE
    floor, (wall, height) = CONTAINER_FLOOR_HALF_THICKNESS, CONTAINER_WALL_HALF
    body = spec.worldbody.add_body(name=name, pos=list(pos))
    body.add_geom(type=box, size=[hx, hy, floor], pos=[0, 0, floor], rgba=list(rgba))
    for y in (hy + wall, -(hy + wall)):
        body.add_geom(type=box, size=[hx, wall, height], pos=[0, y, height], rgba=list(rgba))
    for x in (hx - wall, -(hx - wall)):
        body.add_geom(type=box, size=[wall, hy, height], pos=[x, 0, height], rgba=list(rgba))


class TidyUpScene(MujocoTaskScene[TidyUpTask]):
    """The bottles (free, both moved by the world's offset) and the containers."""

    def build(self, spec: mujoco.MjSpec, sim: MujocoBackend) -> None:
        hx, hy, hz = BOTTLE_HALF_SIZE
        for name, pos, rgba in zip(BOTTLES, self.task.bottle_nominal_pos, BOTTLE_RGBA, strict=True):
            body = spec.worldbody.add_body(name=name, pos=list(pos))
            body.add_freejoint(name=f"{name}_freejoint")
            # MuJoCo's default density, as RMB's: 0.35 kg.
            body.add_geom(
                type=mujoco.mjtGeom.mjGEOM_BOX, size=[hx, hy, hz], pos=[0, 0, hz], rgba=list(rgba)
            )
        for name, pos, rgba in zip(
            CONTAINERS, self.task.container_pos, CONTAINER_RGBA, strict=True
        ):
            _add_container(spec, name, pos, rgba)

    def apply_world(self, sim: MujocoBackend, offset: np.ndarray) -> None:
        for name, pos in zip(BOTTLES, self.task.bottle_nominal_pos, strict=True):
            sim.model.body(name).pos = pos + offset

    def reset_objects(self, sim: MujocoBackend) -> None:
        for name in BOTTLES:
            joint = sim.data.joint(f"{name}_freejoint")
            joint.qpos[:3] = sim.model.body(name).pos
            joint.qpos[3:] = (1.0, 0.0, 0.0, 0.0)
            joint.qvel[:] = 0.0

"""MuJoCo scene of RMB's Pick (:mod:`rmb_lerobot.envs.tasks.pick`): the nine free objects built
from their primitives and the two static baskets."""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

from rmb_lerobot.envs.mujoco.tasks.base import MujocoTaskScene
from rmb_lerobot.envs.tasks.pick import (
    BOX,
    CAPSULE,
    CYLINDER,
    SPHERE,
    Basket,
    PickTask,
    yaw_quat,
)

if TYPE_CHECKING:
    from rmb_lerobot.envs.mujoco.backend import MujocoBackend

GEOM_TYPES: dict[str, mujoco.mjtGeom] = {
    BOX: mujoco.mjtGeom.mjGEOM_BOX,
    CYLINDER: mujoco.mjtGeom.mjGEOM_CYLINDER,
    CAPSULE: mujoco.mjtGeom.mjGEOM_CAPSULE,
    SPHERE: mujoco.mjtGeom.mjGEOM_SPHERE,
}
"""MuJoCo's geom type of each of the task's primitive shapes (:attr:`Geom.type`)."""


class PickScene(MujocoTaskScene[PickTask]):
    """The objects (free, placed by the layout's shifts) and the baskets (moved by the world's)."""

    def build(self, spec: mujoco.MjSpec, sim: MujocoBackend) -> None:
        for obj in self.task.objects:
            body = spec.worldbody.add_body(
                name=obj.body, pos=[*obj.slot, self.task.table_z], quat=yaw_quat(obj.yaw).tolist()
            )
            body.add_freejoint(name=obj.body)
            density = obj.mass / sum(g.volume() for g in obj.geoms if g.collide)
            for g in obj.geoms:
                geom = body.add_geom(
                    type=GEOM_TYPES[g.type],
                    size=[*g.size, *[0.0] * (3 - len(g.size))],
                    pos=list(g.pos),
                    rgba=list(g.rgba),
                    condim=4,
                    quat=list(g.quat),
                    density=density if g.collide else 0.0,
                )
                if not g.collide:
                    geom.contype = geom.conaffinity = 0
                    geom.group = 1
        for basket in self.task.baskets:
            self._build_basket(spec, basket)

    def _build_basket(self, spec: mujoco.MjSpec, basket: Basket) -> None:
        body = spec.worldbody.add_body(name=basket.body, pos=[*basket.pos, self.task.table_z])
        (ix, iy), w, h = basket.inner, basket.wall, basket.height
        rgba = list(basket.rgba)
        box = mujoco.mjtGeom.mjGEOM_BOX
        body.add_geom(
            type=box,
            size=[ix + 2 * w, iy + 2 * w, basket.floor / 2],
            pos=[0, 0, basket.floor / 2],
            rgba=rgba,
        )
        for sx in (-1, 1):
            body.add_geom(
                type=box, size=[w, iy + 2 * w, h / 2], pos=[sx * (ix + w), 0, h / 2], rgba=rgba
            )
        for sy in (-1, 1):
            body.add_geom(type=box, size=[ix, w, h / 2], pos=[0, sy * (iy + w), h / 2], rgba=rgba)

    def apply_world(self, sim: MujocoBackend, offset: np.ndarray) -> None:
        model = sim.model
        for basket in self.task.baskets:
            model.body(basket.body).pos = np.array([*basket.pos, self.task.table_z]) + offset
        for obj, xy in zip(
            self.task.objects, self.task.nominal_positions + self.task.object_shifts, strict=True
        ):
            model.body(obj.body).pos = [*xy, self.task.table_z]

    def reset_objects(self, sim: MujocoBackend) -> None:
        model, data = sim.model, sim.data
        for obj in self.task.objects:
            joint = data.joint(obj.body)
            joint.qpos[:3] = model.body(obj.body).pos
            joint.qpos[3:] = yaw_quat(obj.yaw)
            joint.qvel[:] = 0.0

"""MuJoCo scene of RMB's Handover (:mod:`rmb_lerobot.envs.tasks.handover`): the free object
(base plate + handle) and the two mats."""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

from rmb_lerobot.envs.mujoco.tasks.base import MujocoTaskScene
from rmb_lerobot.envs.tasks.handover import (
    BASE_HALF_SIZE,
    BASE_Z,
    HANDLE_HALF_SIZE,
    HANDLE_Z,
    MAT1,
    MAT2,
    MAT_HALF_SIZE,
    OBJECT,
    OBJECT_BASE,
    OBJECT_HANDLE,
    OBJECT_JOINT,
    HandoverTask,
)

if TYPE_CHECKING:
    from rmb_lerobot.envs.mujoco.backend import MujocoBackend

# env_aloha_handover.xml materials: object magenta, mat1 yellow, mat2 cyan.
_OBJECT_RGBA = [0.8, 0.0, 0.5, 1.0]
_MAT_RGBA = {MAT1: [0.8, 0.8, 0.1, 1.0], MAT2: [0.0, 0.8, 0.8, 1.0]}


class HandoverScene(MujocoTaskScene[HandoverTask]):
    """The object (free; MuJoCo's default density as RMB: 0.25 kg) and the two mats."""

    def build(self, spec: mujoco.MjSpec, sim: MujocoBackend) -> None:
        box = mujoco.mjtGeom.mjGEOM_BOX
        obj = spec.worldbody.add_body(name=OBJECT, pos=list(self.task.object_nominal_pos))
        obj.add_freejoint(name=OBJECT_JOINT)
        obj.add_geom(
            name=OBJECT_BASE,
            type=box,
            size=list(BASE_HALF_SIZE),
            pos=[0, 0, BASE_Z],
            rgba=_OBJECT_RGBA,
        )
        obj.add_geom(
            name=OBJECT_HANDLE,
            type=box,
            size=list(HANDLE_HALF_SIZE),
            pos=[0, 0, HANDLE_Z],
            rgba=_OBJECT_RGBA,
        )
        for name, pos in ((MAT1, self.task.mat1_nominal_pos), (MAT2, self.task.mat2_nominal_pos)):
            mat = spec.worldbody.add_body(name=name, pos=list(pos))
            mat.add_geom(
                type=box,
                size=list(MAT_HALF_SIZE),
                pos=[0, 0, MAT_HALF_SIZE[2]],
                rgba=_MAT_RGBA[name],
            )

    def apply_world(self, sim: MujocoBackend, offset: np.ndarray) -> None:
        sim.model.body(OBJECT).pos = self.task.object_nominal_pos + offset
        sim.model.body(MAT1).pos = self.task.mat1_nominal_pos + offset
        sim.model.body(MAT2).pos = self.task.mat2_nominal_pos - offset

    def reset_objects(self, sim: MujocoBackend) -> None:
        # A free body's pose lives in its joint, so copy the world's placement there.
        qpos = sim.data.joint(OBJECT_JOINT).qpos
        qpos[:3] = sim.model.body(OBJECT).pos
        qpos[3:] = (1.0, 0.0, 0.0, 0.0)
        sim.data.joint(OBJECT_JOINT).qvel[:] = 0.0

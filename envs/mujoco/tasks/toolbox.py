"""MuJoCo scene of RMB's Toolbox (:mod:`rmb_lerobot.envs.tasks.toolbox`): the free toolbox with
its handle and the two-layer mat."""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

from rmb_lerobot.envs.mujoco.tasks.base import MujocoTaskScene
from rmb_lerobot.envs.tasks.toolbox import (
    BOX_HALF_SIZE,
    HANDLE,
    HANDLE_HALF_LENGTH,
    HANDLE_HALF_WIDTH,
    HANDLE_HEIGHT,
    HANDLE_POST_Y,
    MAT,
    MAT_HALF_THICKNESS,
    MAT_LAYERS,
    TOOLBOX,
    ToolboxTask,
)

if TYPE_CHECKING:
    from rmb_lerobot.envs.mujoco.backend import MujocoBackend


class ToolboxScene(MujocoTaskScene[ToolboxTask]):
    """The toolbox (free, moved by the world's offset) and the mat on the table."""

    def build(self, spec: mujoco.MjSpec, sim: MujocoBackend) -> None:
        box = mujoco.mjtGeom.mjGEOM_BOX
        toolbox = spec.worldbody.add_body(
            name=TOOLBOX, pos=list(self.task.toolbox_nominal_pos), quat=list(self.task.toolbox_quat)
        )
        toolbox.add_freejoint(name=TOOLBOX)
        grey = [0.4, 0.4, 0.5, 1.0]
        hx, hy, hz = BOX_HALF_SIZE
        # MuJoCo's default density (1000 kg/m^3), as in RMB: the toolbox weighs 1.18 kg.
        toolbox.add_geom(type=box, size=[hx, hy, hz], pos=[0, 0, hz], rgba=grey)
        post_half_height = 0.5 * (HANDLE_HEIGHT - 2 * hz)
        for y in (-HANDLE_POST_Y, HANDLE_POST_Y):
            toolbox.add_geom(
                type=box,
                size=[HANDLE_HALF_WIDTH, 0.005, post_half_height],
                pos=[0, y, 2 * hz + post_half_height],
                rgba=grey,
            )
        toolbox.add_geom(
            name=HANDLE,
            type=box,
            size=[HANDLE_HALF_WIDTH, HANDLE_HALF_LENGTH, HANDLE_HALF_WIDTH],
            pos=[0, 0, HANDLE_HEIGHT],
            rgba=grey,
        )
        mat = spec.worldbody.add_body(name=MAT, pos=list(self.task.mat_pos))
        for half, z, rgba in MAT_LAYERS:
            mat.add_geom(
                type=box, size=[half, half, MAT_HALF_THICKNESS], pos=[0, 0, z], rgba=list(rgba)
            )

    def apply_world(self, sim: MujocoBackend, offset: np.ndarray) -> None:
        sim.model.body(TOOLBOX).pos = self.task.toolbox_nominal_pos + offset

    def reset_objects(self, sim: MujocoBackend) -> None:
        # A free body's pose lives in its joint, so copy the world's placement there.
        qpos = sim.data.joint(TOOLBOX).qpos
        qpos[:3] = sim.model.body(TOOLBOX).pos
        qpos[3:] = self.task.toolbox_quat
        sim.data.joint(TOOLBOX).qvel[:] = 0.0

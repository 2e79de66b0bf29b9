"""MuJoCo scene of RMB's Insert (:mod:`rmb_lerobot.envs.tasks.insert`): the peg, welded in the
hand, and the hole on the table."""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

from rmb_lerobot.envs.mujoco.tasks.base import MujocoTaskScene
from rmb_lerobot.envs.tasks.insert import (
    HOLE,
    HOLE_DEPTH,
    PEG,
    PEG_HALF_LENGTH,
    PEG_HALF_WIDTH,
    PEG_OFFSET_FROM_MOUNT,
    InsertTask,
)

if TYPE_CHECKING:
    from rmb_lerobot.envs.mujoco.backend import MujocoBackend


class InsertScene(MujocoTaskScene[InsertTask]):
    """The peg (free, welded to the hand, no contact with the robot) and the four-walled hole."""

    def build(self, spec: mujoco.MjSpec, sim: MujocoBackend) -> None:
        peg = spec.worldbody.add_body(name=PEG, pos=[0.0, 0.0, 1.0])
        peg.add_freejoint(name=PEG)
        half = [PEG_HALF_WIDTH, PEG_HALF_WIDTH, PEG_HALF_LENGTH / 2]
        for z, rgba in (
            (PEG_HALF_LENGTH / 2, (0.8, 0.1, 0.5, 1)),
            (-PEG_HALF_LENGTH / 2, (0.8, 0.5, 0.1, 1)),
        ):
            peg.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=half, pos=[0, 0, z], rgba=rgba)
        hole = spec.worldbody.add_body(name=HOLE, pos=list(self.task.hole_nominal_pos))
        # Four walls around a square opening, as in RMB's env_ur5e_insert.xml.
        walls = (
            ((0.02, 0.045), (0.045, -0.02)),
            ((0.02, 0.045), (-0.045, 0.02)),
            ((0.045, 0.02), (0.02, 0.045)),
            ((0.045, 0.02), (-0.02, -0.045)),
        )
        for i, ((sx, sy), (px, py)) in enumerate(walls):
            hole.add_geom(
                name=f"{HOLE}{i + 1}",
                type=mujoco.mjtGeom.mjGEOM_BOX,
                size=[sx, sy, HOLE_DEPTH / 2],
                pos=[px, py, HOLE_DEPTH / 2],
                rgba=[0.1, 0.8, 0.5, 1.0],
            )
        (arm,), (arm_model,) = sim.robot.arms, sim.robot_model.arms  # one-arm task
        spec.add_equality(
            name=PEG,
            type=mujoco.mjtEq.mjEQ_WELD,
            objtype=mujoco.mjtObj.mjOBJ_BODY,
            name1=arm.hand_frame,
            name2=PEG,
            data=[0, 0, 0, 0, 0, PEG_OFFSET_FROM_MOUNT, 1, 0, 0, 0, 1, 0],
        )
        for body in spec.body(arm_model.base_body).find_all(mujoco.mjtObj.mjOBJ_BODY):
            spec.add_exclude(bodyname1=body.name, bodyname2=PEG)

    def apply_world(self, sim: MujocoBackend, offset: np.ndarray) -> None:
        sim.model.body(HOLE).pos = self.task.hole_nominal_pos + offset

    def reset_objects(self, sim: MujocoBackend) -> None:
        mount = sim.data.body(sim.robot.arms[0].hand_frame)
        mat = mount.xmat.reshape(3, 3)
        qpos = sim.data.joint(PEG).qpos
        qpos[:3] = mount.xpos + mat[:, 2] * PEG_OFFSET_FROM_MOUNT
        qpos[3:] = mount.xquat
        sim.data.joint(PEG).qvel[:] = 0.0

"""MuJoCo scene of RMB's Door (:mod:`rmb_lerobot.envs.tasks.door`): two posts and a leaf on a
vertical hinge with a bar handle."""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

from rmb_lerobot.envs.mujoco.tasks.base import MujocoTaskScene
from rmb_lerobot.envs.tasks.door import (
    DOOR,
    DOOR_LEAF,
    HANDLE_BAR_RADIUS,
    HANDLE_BAR_X,
    HANDLE_BAR_Y,
    HINGE_HEIGHT,
    HINGE_Y,
    DoorTask,
)

if TYPE_CHECKING:
    from rmb_lerobot.envs.mujoco.backend import MujocoBackend


class DoorScene(MujocoTaskScene[DoorTask]):
    """The door frame (moved by the world's offset) and its hinged leaf, closed at start."""

    def build(self, spec: mujoco.MjSpec, sim: MujocoBackend) -> None:
        cylinder, box = mujoco.mjtGeom.mjGEOM_CYLINDER, mujoco.mjtGeom.mjGEOM_BOX
        frame = spec.worldbody.add_body(name=DOOR, pos=list(self.task.door_nominal_pos))
        for y in (HINGE_Y, -HINGE_Y):
            frame.add_geom(
                type=cylinder,
                size=[0.015, HINGE_HEIGHT, 0],
                pos=[0, y, HINGE_HEIGHT],
                rgba=[0.1, 0.3, 0.1, 1],
            )
        leaf = frame.add_body(name=DOOR_LEAF, pos=[0, HINGE_Y, HINGE_HEIGHT])
        leaf.add_joint(
            name=DOOR,
            type=mujoco.mjtJoint.mjJNT_HINGE,
            axis=[0, 0, 1],
            range=[-np.pi, 0],
            armature=1e-5,
            limited=mujoco.mjtLimited.mjLIMITED_TRUE,
        )
        leaf.add_geom(
            type=box, size=[0.005, 0.09, 0.145], pos=[0, -0.1, 0], rgba=[0.7, 0.9, 0.9, 1]
        )
        bar_mid = 0.5 * (HANDLE_BAR_Y[0] + HANDLE_BAR_Y[1])
        bar_half = 0.5 * (HANDLE_BAR_Y[1] - HANDLE_BAR_Y[0])
        leaf.add_geom(  # stem from the panel to the bar
            type=cylinder,
            size=[0.005, 0.02, 0],
            pos=[-0.02, -0.17, 0],
            quat=[np.cos(np.pi / 4), 0, np.sin(np.pi / 4), 0],
            rgba=[0.1, 0.6, 0.3, 1],
        )
        leaf.add_geom(  # the bar the gripper grasps
            name="handle",
            type=cylinder,
            size=[HANDLE_BAR_RADIUS, bar_half, 0],
            pos=[HANDLE_BAR_X, bar_mid, 0],
            quat=[np.cos(np.pi / 4), np.sin(np.pi / 4), 0, 0],
            rgba=[0.1, 0.6, 0.3, 1],
            friction=[1.0, 0.005, 0.0001],
        )

        # The leaf's edges touch the posts; MuJoCo does not filter contacts between a static body
        # and its child, so without this the hinge jams.
        spec.add_exclude(bodyname1=DOOR, bodyname2=DOOR_LEAF)

    def apply_world(self, sim: MujocoBackend, offset: np.ndarray) -> None:
        sim.model.body(DOOR).pos = self.task.door_nominal_pos + offset

    def reset_objects(self, sim: MujocoBackend) -> None:
        sim.data.joint(DOOR).qpos[:] = 0.0
        sim.data.joint(DOOR).qvel[:] = 0.0

"""RMB's MujocoUR5eDoor: grasp the handle of a small hinged door and pull it open.

Geometry follows RMB's ``env_ur5e_door.xml``: two posts, a 18 x 29 cm panel on a vertical hinge
(joint ``door``, range -pi..0, opening towards the robot for negative angles) and a horizontal
bar handle on a stem, 3.5 cm in front of the panel. The door moves in y from -0.06 to +0.09 m
across the six worlds. Success: the hinge angle is at most -45 degrees.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, ClassVar

import mujoco
import numpy as np

from rmb_lerobot.envs.tasks.base import StartPoses, Task
from rmb_lerobot.envs.workspace import RMB_TABLE, Workspace

if TYPE_CHECKING:
    from rmb_lerobot.envs.backend import SceneState
    from rmb_lerobot.envs.mujoco.backend import MujocoBackend

DOOR = "door"  # the static frame body and the hinge joint
DOOR_LEAF = "door_leaf"
HINGE_HEIGHT = 0.15
HINGE_Y = 0.1  # hinge axis in the door frame
HANDLE_BAR_X = -0.035  # bar centre line in the leaf (hinge) frame
HANDLE_BAR_Y = (-0.175, -0.115)  # bar extent along the leaf
HANDLE_BAR_RADIUS = 0.0075


class DoorTask(Task):
    name = "door"
    description = "Grasp the door handle and open the door."
    world_offsets = np.array([[0.0, y, 0.0] for y in (-0.06, -0.03, 0.0, 0.03, 0.06, 0.09)])
    max_episode_steps = 400
    # RMB's MujocoUR5eDoorEnv start pose: gripper tilted towards the door.
    start_poses: ClassVar[StartPoses] = {
        "ur5e": ((np.pi, -0.4 * np.pi, -0.65 * np.pi, -0.25 * np.pi, np.pi / 2, np.pi / 2),)
    }
    open_angle_deg = -45.0

    def __init__(self, workspace: Workspace = RMB_TABLE) -> None:
        super().__init__(workspace)
        self.door_nominal_pos = workspace.table.on_top(0.15, -0.08)

    def build(self, spec: mujoco.MjSpec, sim: MujocoBackend) -> None:
        cylinder, box = mujoco.mjtGeom.mjGEOM_CYLINDER, mujoco.mjtGeom.mjGEOM_BOX
        frame = spec.worldbody.add_body(name=DOOR, pos=list(self.door_nominal_pos))
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
        sim.model.body(DOOR).pos = self.door_nominal_pos + offset

    def reset_objects(self, sim: MujocoBackend) -> None:
        sim.data.joint(DOOR).qpos[:] = 0.0
        sim.data.joint(DOOR).qvel[:] = 0.0

    def is_success(self, scene: SceneState) -> bool:
        return bool(scene.joint_position(DOOR)[0] <= np.deg2rad(self.open_angle_deg))

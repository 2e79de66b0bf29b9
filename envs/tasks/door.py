"""RMB's MujocoUR5eDoor: grasp the handle of a small hinged door and pull it open.

Geometry follows RMB's ``env_ur5e_door.xml``: two posts, a 18 x 29 cm panel on a vertical hinge
(joint ``door``, range -pi..0, opening towards the robot for negative angles) and a horizontal
bar handle on a stem, 3.5 cm in front of the panel. The door moves in y from -0.06 to +0.09 m
across the six worlds. Success: the hinge angle is at most -45 degrees.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, ClassVar

import numpy as np

from rmb_lerobot.envs.tasks.base import StartPoses, Task
from rmb_lerobot.envs.workspace import RMB_TABLE, Workspace

if TYPE_CHECKING:
    from rmb_lerobot.envs.scene import SceneState

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

    def is_success(self, scene: SceneState) -> bool:
        return bool(scene.joint_position(DOOR)[0] <= np.deg2rad(self.open_angle_deg))

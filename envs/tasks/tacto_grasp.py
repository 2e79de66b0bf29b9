"""RMB's TactoSawyerGrasp: grasp a small box on the floor and lift it (PyBullet, tactile).

RMB's ``TactoSawyerGraspEnv``: a 6 x 3 x 9 cm box (its ``cube.urdf`` mesh scaled 0.10 x 0.05 x
0.15 and loaded at ``global_scaling`` 0.6; mass 0.1 kg, friction 0.5) stands at (0.6, 0, .) in
front of the Sawyer; one world, with an optional uniform jitter. Success (RMB's reward): the
box's centre above 0.1 m and the box at rest (linear and angular speed below 0.025).

Where RMB drops the box from z = 0.1 m at every reset, it starts here resting on the floor
(centre at its half height): the state RMB's box reaches after falling, without a fall whose
bounce differs between machines.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, ClassVar

import numpy as np

from rmb_lerobot.envs.tasks.base import StartPoses, Task
from rmb_lerobot.envs.workspace import TACTO_FLOOR, Workspace

if TYPE_CHECKING:
    from rmb_lerobot.envs.scene import SceneState

BOX = "cube"
BOX_HALF_SIZE = (0.03, 0.015, 0.045)  # RMB: 1 m mesh x (0.10, 0.05, 0.15) x 0.6, halved
BOX_MASS = 0.1
BOX_FRICTION = 0.5
BOX_XY = (0.6, 0.0)


class TactoGraspTask(Task):
    """Lift the box above 0.1 m and hold it still."""

    name = "grasp"
    description = "Grasp the box and lift it."
    world_offsets = np.zeros((1, 3))
    max_episode_steps = 200  # 6 s at 33 Hz; the expert needs about 4
    lift_height = 0.1
    max_speed = 0.025
    start_poses: ClassVar[StartPoses] = {}

    def __init__(self, workspace: Workspace = TACTO_FLOOR) -> None:
        super().__init__(workspace)
        self.box_nominal_pos = workspace.table.on_top(*BOX_XY, BOX_HALF_SIZE[2])

    def is_success(self, scene: SceneState) -> bool:
        pos, _ = scene.body_pose(BOX)
        velocity = scene.joint_velocity(BOX)
        linear, angular = np.linalg.norm(velocity[:3]), np.linalg.norm(velocity[3:])
        return bool(
            pos[2] > self.lift_height and linear < self.max_speed and angular < self.max_speed
        )

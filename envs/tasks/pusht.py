"""RMB's MujocoXarm7PushT: push a T-shaped block over the table into a drawn goal pose.

Geometry follows RMB's ``env_xarm7_pusht.xml`` (lines 44-55): the T-block is a free body of two
boxes, the bar (half size 0.1 x 0.02 x 0.02 m) at the body origin and the stem (0.02 x 0.08 x
0.02 m) centred 0.1 m along the body's y axis, so the origin is the middle of the bar. It starts
at (0.15, 0) on the xArm table (top z 0.74, the block's centre 2 cm above it) turned 1.4 rad
about z; the goal region, the same T drawn flat on the table without collision, lies at
(0, 0.1) turned -1 rad. As in RMB only the block moves: along y from -0.06 to +0.09 m across
the six worlds (``MujocoXarm7PushtEnv.py`` lines 24-33), the random shift on top.

The block is made of MuJoCo's defaults as in RMB: density 1000 kg/m^3 (0.576 kg) and sliding
friction 1, with RMB's red material.

Success is RMB's ``_get_reward``: the block's origin within 0.03 m of the goal's in xy, and the
yaw difference (wrapped to [-pi, pi]) under 5 degrees.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from rmb_lerobot.envs.tasks.base import Task
from rmb_lerobot.envs.workspace import RMB_TABLE, Workspace

if TYPE_CHECKING:
    from rmb_lerobot.envs.scene import SceneState

TBLOCK = "tblock"  # the block's body (RMB's name)
TBLOCK_JOINT = "tblock_freejoint"  # its free joint (RMB's name)
GOAL = "target_region"  # the drawn goal pose (RMB's name)
# env_xarm7_pusht.xml lines 46-47 and 51-54: bar and stem half sizes and the stem's offset.
BAR_HALF_SIZE = (0.1, 0.02, 0.02)
STEM_HALF_SIZE = (0.02, 0.08, 0.02)
STEM_OFFSET = 0.1  # stem centre along the block's y axis (m)
BLOCK_HALF_HEIGHT = BAR_HALF_SIZE[2]
DENSITY = 1000.0  # kg/m^3: RMB gives none, so MuJoCo's default
FRICTION = (1.0, 0.005, 0.0001)  # MuJoCo's default geom friction (RMB sets none)
RED = (1.0, 0.0, 0.0, 1.0)  # RMB's ``tblock`` material rgba (on a metal texture)
GOAL_GREY = (0.5, 0.5, 0.5, 1.0)  # RMB's target_region rgba
GOAL_HALF_THICKNESS = 0.001  # RMB's drawn goal: 2 mm boxes centred on the table top


def block_mass() -> float:
    """The block's mass at :data:`DENSITY` (kg)."""
    return DENSITY * 8 * (np.prod(BAR_HALF_SIZE) + np.prod(STEM_HALF_SIZE))


def yaw_of(rot: np.ndarray) -> float:
    """Rotation about the world z axis of a body whose z axis is (nearly) vertical (rad)."""
    return float(np.arctan2(rot[1, 0], rot[0, 0]))


def wrap_angle(angle: float) -> float:
    """``angle`` wrapped to [-pi, pi]."""
    return float(np.arctan2(np.sin(angle), np.cos(angle)))


class PushTTask(Task):
    name = "pusht"
    description = "Push the T-shaped block into the goal region."
    # MujocoXarm7PushtEnv.py lines 24-33.
    world_offsets = np.array([[0.0, y, 0.0] for y in (-0.06, -0.03, 0.0, 0.03, 0.06, 0.09)])
    # RMB's random shift also moves the block in z (uniform in +-scale on all three axes, line
    # 59): a block shifted up falls onto the table, one shifted down starts inside it and is
    # shot out of it. Neither is a different task, so the shift here moves it on the table only.
    shift_axes = np.array([1.0, 1.0, 0.0])
    # The scripted expert needs 15-35 s (mean ~840 control steps at 31.25 Hz, at most ~1070
    # over 100 episodes); 1500 steps (48 s) leave margin. RMB's demonstrations take 10-20 s.
    max_episode_steps = 1500
    # env_xarm7_pusht.xml line 44 (block) and 50 (goal), relative to the table centre.
    block_xy = (0.15, 0.0)
    block_yaw = 1.4
    goal_xy = (0.0, 0.1)
    goal_yaw = -1.0
    # MujocoXarm7PushtEnv._get_reward: 0.03 m in xy, 5 degrees in yaw (both strict).
    xy_tolerance = 0.03
    yaw_tolerance = np.deg2rad(5.0)

    def __init__(self, workspace: Workspace = RMB_TABLE) -> None:
        super().__init__(workspace)
        table = workspace.table
        self.block_nominal_pos = table.on_top(*self.block_xy, BLOCK_HALF_HEIGHT)
        self.goal_pos = table.on_top(*self.goal_xy)

    def pose_error(self, scene: SceneState) -> tuple[float, float]:
        """The block's distance from the goal in xy (m) and its yaw error (rad, wrapped)."""
        pos, rot = scene.body_pose(TBLOCK)
        goal_pos, goal_rot = scene.body_pose(GOAL)
        dist = float(np.linalg.norm(pos[:2] - goal_pos[:2]))
        return dist, wrap_angle(yaw_of(rot) - yaw_of(goal_rot))

    def is_success(self, scene: SceneState) -> bool:
        dist, yaw_error = self.pose_error(scene)
        return bool(dist < self.xy_tolerance and abs(yaw_error) < self.yaw_tolerance)

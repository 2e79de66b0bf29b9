"""The neutral demo task of RMB's real envs (``RealUR5eDemoEnv``, ``RealXarm7DemoEnv``,
``RealUR5eDualDemoEnv``): RMB's real home poses, one world, no success test (the operator
decides). Imports no simulator."""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from rmb_lerobot.envs.scene import SceneState
from rmb_lerobot.envs.tasks.base import StartPoses, Task

# RealUR5eDemoEnv.py:13-24 (the gripper, 0 = open, is the record's home command).
UR5E_REAL_HOME = (1.18000162, -1.91696992, 1.5561803, -1.21203147, -1.57465679, -0.39695961)
# RealUR5eDualDemoEnv.py:12-32, left arm (the right arm is the single UR5e's home).
UR5E_DUAL_LEFT_REAL_HOME = (
    -1.18000162,
    -1.22462273,
    -1.5561803,
    -1.9295612,
    1.57465679,
    0.39695961,
)
# RealXarm7DemoEnv.py:13-17: [0, -30, 0, 45, 0, 75, 0] deg.
XARM7_REAL_HOME = tuple(float(v) for v in np.deg2rad([0.0, -30.0, 0.0, 45.0, 0.0, 75.0, 0.0]))


class RealDemoTask(Task):
    """RMB's real demo: start at the real home pose, record what the operator does.

    The dual UR5e's arms start at RMB's ``RealUR5eDualDemoEnv`` pose: the left arm mirrored
    about the workspace, the right arm at the single UR5e's home.
    """

    name = "demo"
    description = "Demonstrate the task with the real robot."
    world_offsets = np.zeros((1, 3))
    max_episode_steps = 1000  # 20 s at 50 Hz
    start_poses: ClassVar[StartPoses] = {
        "ur5e": (UR5E_REAL_HOME,),
        "xarm7": (XARM7_REAL_HOME,),
        "ur5e_dual": (UR5E_DUAL_LEFT_REAL_HOME, UR5E_REAL_HOME),
    }

    def is_success(self, scene: SceneState) -> bool:
        """Never: a real cell has no scene to test (the env does not call this)."""
        return False


class NoExpert:
    """A real env has no scripted expert: the operator (a teleoperator) or a policy drives.

    Raises:
        NotImplementedError: Always, when made.
    """

    def __init__(self, *args: object, **kwargs: object):
        raise NotImplementedError(
            "real envs have no scripted expert: drive them with a teleoperator or a policy"
        )

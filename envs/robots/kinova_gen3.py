"""RMB's Kinova Gen3 (7 DoF) with a Robotiq 2F-85 (MuJoCo model: envs/mujoco/models/kinova_gen3.py).

Facts from RMB (RoboManipBaselines 8535948, ``robo_manip_baselines/envs/``): joint names
``joint_1..7`` and the measured gripper formula (``mujoco/kinovagen3/MujocoKinovaGen3EnvBase.py``
``_get_obs``: the UR5e's, rad2deg(mean of four 2F-85 joints) / 45 * 255), home pose
(``MujocoKinovaGen3CableEnv.py``: [0, 20, 0, 100, 0, 60, 0] deg), mount on RMB's stand
(``assets/mujoco/envs/kinovagen3/env_kinovagen3_cable.xml``: ``kinovagen3_root_frame`` at
(-0.5, 0, 0.8), as the Panda's) and the wrist camera (``kinovagen3_body.xml``: ``hand`` on
``bracelet_link`` at (0, -0.05639, -0.058475), quaternion (0, 0, 0, 1), fovy 41.84 deg, the
Gen3 vision module's colour sensor).

The end-effector frame is Kinova's tool frame (the Gen3 user guide's interface frame, 61.5 mm
beyond joint 7 along its axis, z out of the flange), not RMB's IK frame (joint 7's origin,
whose z points back into the arm): every robot here keeps the eef z axis along the approach
direction, which the scripted experts rely on.
"""

from __future__ import annotations

import numpy as np

from rmb_lerobot.envs.robots.common import Arm, HandCamera, Pose, Robot
from rmb_lerobot.envs.robots.ur5e import UR5E

_GRIPPER = "gripper/"  # prefix of the 2F-85's names in the composed model (the UR5e's)

KINOVA_GEN3 = Robot(
    name="kinova_gen3",
    rmb_name="KinovaGen3",
    arms=(
        Arm(
            name="arm",
            joints=tuple(f"joint_{i}" for i in range(1, 8)),
            home=tuple(float(q) for q in np.deg2rad([0, 20, 0, 100, 0, 60, 0])),
            # The UR5e's 2F-85 (same model, names, command 0..255 and measured formula).
            gripper=UR5E.arms[0].gripper,
            mount=Pose(pos=(-0.5, 0.0, 0.8)),
            root_frame="kinovagen3_root_frame",
            eef_frame="tool_frame",  # Kinova's tool frame on bracelet_link (see above)
            tcp_frame=_GRIPPER + "pinch",
            hand_frame="bracelet_link",  # the gripper and the camera are mounted on it
            wrench_frame=_GRIPPER + "ft_site",  # on the gripper's mount, as the UR5e's
            hand_camera=HandCamera(
                "hand",
                Pose(pos=(0.0, -0.05639, -0.058475), quat=(0.0, 0.0, 0.0, 1.0)),
                41.83792730009236,
            ),
        ),
    ),
)
"""RMB's MuJoCo Kinova Gen3: 8-D action (7 joints + gripper 0..255), cameras front, left,
right (the scene's) and hand."""

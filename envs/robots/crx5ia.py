"""RMB's FANUC CRX-5iA with a Robotiq 2F-85 (MuJoCo model: envs/mujoco/models/crx5ia.py).

Facts from RMB (RoboManipBaselines 8535948, ``robo_manip_baselines/envs/``): joint names
``J1..J6`` and the measured gripper formula (``mujoco/crx5ia/MujocoCrx5iaEnvBase.py``
``_get_obs``: the UR5e's), home pose (``MujocoCrx5iaCableEnv.py``: [0, 0, 0, 0, -90, 0] deg:
upper arm up, forearm forward, tool pointing down), mount on RMB's stand
(``assets/mujoco/envs/crx5ia/env_crx5ia_cable.xml``: ``crx5ia_root_frame`` at (-0.5, 0, 0.8)).
RMB's CRX-5iA has no wrist camera.

The end-effector frame is the faceplate frame (on the flange, z out of it along the J6 axis,
as FANUC's controller reports the tool pose with no tool set), not RMB's IK frame (J6's joint
frame, 0.145 m behind the flange with x along the tool): every robot here keeps the eef z axis
along the approach direction, which the scripted experts rely on.
"""

from __future__ import annotations

import numpy as np

from rmb_lerobot.envs.robots.common import Arm, Pose, Robot
from rmb_lerobot.envs.robots.ur5e import UR5E

_GRIPPER = "gripper/"  # prefix of the 2F-85's names in the composed model (the UR5e's)

CRX5IA = Robot(
    name="crx5ia",
    rmb_name="Crx5ia",
    arms=(
        Arm(
            name="arm",
            joints=tuple(f"J{i}" for i in range(1, 7)),
            home=tuple(float(q) for q in np.deg2rad([0, 0, 0, 0, -90, 0])),
            # The UR5e's 2F-85 (same model, names, command 0..255 and measured formula).
            gripper=UR5E.arms[0].gripper,
            mount=Pose(pos=(-0.5, 0.0, 0.8)),
            root_frame="crx5ia_root_frame",
            eef_frame="faceplate",  # on the flange (see above)
            tcp_frame=_GRIPPER + "pinch",
            hand_frame="flange",  # the body the gripper is mounted on
            wrench_frame=_GRIPPER + "ft_site",  # on the gripper's mount, as RMB's force_sensor
        ),
    ),
)
"""RMB's MuJoCo FANUC CRX-5iA: 7-D action (6 joints + gripper 0..255), cameras front, left,
right (the scene's)."""

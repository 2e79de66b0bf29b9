"""RMB's Franka Panda with the Franka hand (MuJoCo model: envs/mujoco/models/panda.py)."""

from __future__ import annotations

import numpy as np

from rmb_lerobot.envs.robots.common import Arm, Gripper, GripperKind, Pose, Robot

PANDA = Robot(
    name="panda",
    rmb_name="Panda",
    arms=(
        Arm(
            name="arm",
            joints=tuple(f"joint{i}" for i in range(1, 8)),
            # MujocoPandaCableEnv.py lines 20-30.
            home=tuple(float(q) for q in np.deg2rad([0, 25, 0, -58, 0, 82, -40])),
            gripper=Gripper(
                # RMB's command is the finger opening, 0 (closed) .. 1 (0.04 m each finger);
                # measured = mean(fingers) / 0.04 (MujocoPandaEnvBase.py line 106).
                joints=("finger_joint1", "finger_joint2"),
                open=1.0,
                closed=0.0,
                measured_scale=1.0 / 0.04,
                kind=GripperKind.SLIDE,
            ),
            # env_panda_cable.xml line 36: panda_root_frame on RMB's stand.
            mount=Pose(pos=(-0.5, 0.0, 0.8)),
            root_frame="panda_root_frame",
            eef_frame="eef",  # on panda_link7 (the flange)
            tcp_frame="pinch",  # between the fingertip pads (franka_ros panda_hand_tcp)
            hand_frame="panda_hand",
            wrench_frame="ft_site",
        ),
    ),
)

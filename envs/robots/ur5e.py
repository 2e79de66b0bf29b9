"""RMB's UR5e with a Robotiq 2F-85 gripper (MuJoCo model: envs/mujoco/robot.py)."""

from __future__ import annotations

import numpy as np

from rmb_lerobot.envs.robots.common import Arm, Gripper, HandCamera, Pose, Robot

_UR5E_GRIPPER = "gripper/"  # prefix of the Robotiq 2F-85's names inside the composed model

UR5E = Robot(
    name="ur5e",
    rmb_name="UR5e",
    arms=(
        Arm(
            name="arm",
            joints=(
                "shoulder_pan_joint",
                "shoulder_lift_joint",
                "elbow_joint",
                "wrist_1_joint",
                "wrist_2_joint",
                "wrist_3_joint",
            ),
            # RMB's MujocoUR5eInsertEnv start pose (pan towards the table, gripper down).
            home=(np.pi, -np.pi / 2, -0.55 * np.pi, -0.45 * np.pi, np.pi / 2, np.pi / 2),
            gripper=Gripper(
                # RMB: measured gripper = rad2deg(mean of these four angles) / 45 * 255.
                joints=tuple(
                    _UR5E_GRIPPER + name
                    for name in (
                        "right_driver_joint",
                        "right_spring_link_joint",
                        "left_driver_joint",
                        "left_spring_link_joint",
                    )
                ),
                open=0.0,
                closed=255.0,
                measured_scale=255.0 / np.deg2rad(45.0),
            ),
            # RMB's stand: arm base 0.605 m behind the table centre, 0.8 m high, turned by pi
            # about z so that the root frame is the UR DH base frame and the arm faces +x.
            mount=Pose(pos=(-0.605, 0.0, 0.8), quat=(0.0, 0.0, 0.0, 1.0)),
            root_frame="ur5e_root_frame",
            eef_frame="attachment_site",
            tcp_frame=_UR5E_GRIPPER + "pinch",
            hand_frame=_UR5E_GRIPPER + "base_mount",
            wrench_frame=_UR5E_GRIPPER + "ft_site",
            # RMB's wrist D435i: 5 cm off the tool axis, looking along the gripper, fovy 62 deg.
            hand_camera=HandCamera("hand", Pose(pos=(0.0, 0.05, 0.0), quat=(0, 0, 1, 0)), 62.0),
        ),
    ),
    # The original RMB's single-arm UR5e envs (gymnasium spec names, as its recorder writes
    # them) that the registry does not derive: other simulators, real demos, and RMB's single
    # Cabinet (ours are CabinetHinge and CabinetSlide).
    rmb_envs=frozenset(
        {
            "MujocoUR5eCabinetEnv",
            "IsaacUR5eChainEnv",
            "IsaacUR5eCabinetEnv",
            "RealUR5eDemoEnv",
        }
    ),
)

"""RMB's UFactory xArm7 with its xArm gripper (MuJoCo model: envs/mujoco/models/xarm7.py)."""

from __future__ import annotations

from rmb_lerobot.envs.robots.common import Arm, Gripper, HandCamera, Pose, Robot

XARM7 = Robot(
    name="xarm7",
    rmb_name="Xarm7",
    arms=(
        Arm(
            name="arm",
            joints=tuple(f"joint{i}" for i in range(1, 8)),
            # MujocoXarm7CableEnv.py line 20 (also PushT's start pose).
            home=(0.0, 0.0, 0.0, 0.8, 0.0, 0.8, 0.0),
            gripper=Gripper(
                # MujocoXarm7EnvBase._get_obs: measured = mean of these six angles / 0.8 * 255.
                joints=(
                    "left_driver_joint",
                    "left_finger_joint",
                    "left_inner_knuckle_joint",
                    "right_driver_joint",
                    "right_finger_joint",
                    "right_inner_knuckle_joint",
                ),
                open=0.0,
                closed=255.0,
                measured_scale=255.0 / 0.8,
            ),
            # env_xarm7_*.xml: xarm7_root_frame on RMB's xArm table, 0.22 m behind its centre.
            mount=Pose(pos=(-0.22, 0.0, 0.74)),
            root_frame="xarm7_root_frame",
            eef_frame="eef",  # on link7 at joint 7 (RMB's IK frame, ik_eef_joint_id 7)
            tcp_frame="link_tcp",
            hand_frame="link7",  # the gripper and the camera are mounted on link 7
            wrench_frame="ft_site",
            # xarm7_body.xml lines 104-108: the wrist D435 on link7, fovy 62 deg; the quaternion
            # of RMB's euler="0 3.1415 1.5708" (3.1415, not pi).
            hand_camera=HandCamera(
                "hand",
                Pose(
                    pos=(0.06746, 0.0, 0.0237),
                    quat=(3.2757930e-05, 0.70710808, 0.70710548, 3.2758051e-05),
                ),
                62.0,
            ),
        ),
    ),
    rmb_envs=frozenset({"RealXarm7DemoEnv"}),
)

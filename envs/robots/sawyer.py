"""RMB's TACTO robot: a Rethink Sawyer with a WSG50 gripper and DIGIT sensors (PyBullet model:
envs/pybullet/sawyer.py)."""

from __future__ import annotations

from rmb_lerobot.envs.robots.common import Arm, Gripper, GripperKind, Pose, Robot

SAWYER = Robot(
    name="sawyer",
    rmb_name="Sawyer",
    arms=(
        Arm(
            name="arm",
            joints=tuple(f"right_j{i}" for i in range(7)),
            # RMB's TactoSawyerGrasp/Insert start pose (TactoSawyerGraspEnv.py:16-28).
            home=(0.0, -1.24, -0.58, 2.18, 0.27, 0.7, 1.0),
            # The WSG50's prismatic fingers go to (-g, +g) for command g (metres, larger is
            # wider; RMB's joint limits 0.0027..0.055); RMB measures mean |finger position|.
            gripper=Gripper(
                joints=("base_joint_gripper_left", "base_joint_gripper_right"),
                open=0.055,
                closed=0.0027,
                measured_scale=1.0,
                home=0.02,
                joint_signs=(-1.0, 1.0),
                kind=GripperKind.SLIDE,
            ),
            # RMB asks for the base at (0, 0, 0.1); pybulletX puts the base's centre of mass
            # there, so the root link frame is at (0.1, 0, 0.03) (envs/pybullet/sawyer.py).
            mount=Pose(pos=(0.1, 0.0, 0.03)),
            root_frame="base",
            eef_frame="right_l6",  # RMB's IK end effector (Pinocchio joint 7 of sawyer.urdf)
            tcp_frame="tool_centre",  # between the two DIGIT gel pads
            hand_frame="right_hand",
            wrench_frame="right_hand",  # RMB's F/T joint
            tactile_sensors=("tactile_left", "tactile_right"),
        ),
    ),
)
"""RMB's TACTO robot: a Rethink Sawyer with a Weiss WSG50 gripper and a DIGIT tactile sensor on
each fingertip (PyBullet)."""

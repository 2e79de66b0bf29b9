"""RMB's Toyota HSR: omnidirectional base, 5-joint arm, two-finger hand (MuJoCo model:
envs/mujoco/models/hsr.py).

Facts from RMB (RoboManipBaselines, ``robo_manip_baselines/envs/mujoco/hsr/``):

- joints ``arm_lift_joint``, ``arm_flex_joint``, ``arm_roll_joint``, ``wrist_flex_joint``,
  ``wrist_roll_joint`` and the hand's ``hand_motor_joint`` (``MujocoHsrEnvBase.py``
  ``_get_obs``: the measured gripper value is that joint's position, so the scale is 1);
- start pose ``[0.25, -2.0, 0.0, -1.0, 0.0]`` and hand 0.8 (``MujocoHsrTidyupEnv.py``);
- base joints ``mobile_x_joint``, ``mobile_y_joint``, ``mobile_theta_joint`` driven by
  velocity actuators with ``ctrlrange`` -1..1 (``hsr_config.xml``), commanded and measured in
  the base's own frame (``convert_mobile_vel_frame``);
- the arm's root frame is ``base_link`` (``get_root_pose_func``): end-effector poses are in the
  moving base's frame;
- the ``head`` camera on ``head_rgbd_sensor_link`` (0.08 m along its z, turned 3 pi / 4 about
  x: 45 degrees down) and the ``hand`` camera on ``hand_palm_link`` (``hsr_body.xml``), both
  fovy 62 deg.

The hand closes along ``hand_motor_joint``: 1.24 rad is fully open, -0.798 fully closed (its
limits in hsrb4s.urdf.xacro). The end-effector frame is the palm's turned by 90 degrees about
its z axis (z along the fingers, x along the closing direction), as the experts expect of every
robot here.
"""

from __future__ import annotations

import numpy as np

from rmb_lerobot.envs.robots.common import (
    Arm,
    BodyCamera,
    Gripper,
    GripperKind,
    HandCamera,
    MobileBase,
    Pose,
    Robot,
)

_HALF = float(np.sqrt(0.5))

HSR = Robot(
    name="hsr",
    rmb_name="Hsr",
    arms=(
        Arm(
            name="arm",
            joints=(
                "arm_lift_joint",
                "arm_flex_joint",
                "arm_roll_joint",
                "wrist_flex_joint",
                "wrist_roll_joint",
            ),
            home=(0.25, -2.0, 0.0, -1.0, 0.0),
            gripper=Gripper(
                joints=("hand_motor_joint",),
                open=1.24,
                closed=-0.798,
                measured_scale=1.0,
                home=0.8,
                kind=GripperKind.HAND,
            ),
            mount=Pose(),  # the arm rides on the base: base_link is its root
            root_frame="base_link",
            eef_frame="hand_eef",
            tcp_frame="hand_tcp",
            hand_frame="hand_palm_link",
            wrench_frame="wrist_ft_sensor",
            hand_camera=HandCamera(
                "hand", Pose(pos=(0.039, 0.0, -0.0045), quat=(0.0, _HALF, _HALF, 0.0)), 62.0
            ),
        ),
    ),
    base=MobileBase(
        joints=("mobile_x_joint", "mobile_y_joint", "mobile_theta_joint"),
        frame="base_link",
        max_linear_vel=1.0,
        max_angular_vel=1.0,
    ),
    body_cameras=(
        BodyCamera(
            "head",
            parent="head_rgbd_sensor_link",
            pose=Pose(
                pos=(0.0, 0.0, 0.08),
                quat=(float(np.cos(3 * np.pi / 8)), float(np.sin(3 * np.pi / 8)), 0.0, 0.0),
            ),
            fovy=62.0,
        ),
    ),
)
"""RMB's MuJoCo HSR: 9-D action (5 arm joints + hand, then the base velocity ``(vx, vy, wz)``
in the base frame), cameras ``hand`` and ``head``."""

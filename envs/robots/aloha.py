"""RMB's ALOHA: two ViperX 300 6-DoF arms with slide fingers facing each other across one
table (MuJoCo model: envs/mujoco/models/aloha.py).

Facts from RMB (RoboManipBaselines 8535948, ``robo_manip_baselines/envs/``):

- joint names per arm ``waist``, ``shoulder``, ``elbow``, ``forearm_roll``, ``wrist_angle``,
  ``wrist_rotate`` and the fingers ``left_finger``, ``right_finger``, each under ``left/`` or
  ``right/`` (``mujoco/aloha/MujocoAlohaEnvBase.py`` ``_get_obs_single_arm``);
- home ``[0, -0.96, 1.16, 0, -0.3, 0]`` per arm, fingers at 0.037 m
  (``MujocoAlohaCableEnv.py``, ``MujocoAlohaHandoverEnv.py``);
- gripper: the command is the fingers' opening on their rail in metres, 0.002 (closed) ..
  0.037 (open) (``assets/mujoco/robots/aloha/aloha_arms_config.xml`` class ``finger``: the
  real robot's software limits); RMB records the measured value as ``rad2deg`` of the mean
  finger position, a unit slip (the fingers slide, in metres), so here the measured value is
  the mean opening in metres (scale 1), comparable with the command;
- mounts (``aloha_arms_body.xml`` inside the env XMLs' body turned -90 deg about z): left
  base at (-0.019, 0.469), facing -y; right base at (-0.019, -0.469), facing +y; 0.02 m above
  the table top. RMB's table top is at z = 0 with the floor at -0.75 m; here the floor is at
  z = 0, so every height is RMB's + 0.75 m;
- wrist cameras ``wrist_cam_left`` / ``wrist_cam_right`` on the gripper (RealSense D405
  mount: ``aloha_arms_body.xml``, focal 1.93 mm on a 2.14 mm high sensor: fovy 58.0 deg);
- the eef pose RMB records is in each arm's ``base_link`` frame (``arm_root_pose``).

The eef frame (``<side>/eef``) sits on ``gripper_link`` with z along the approach (the
gripper's x axis) and x along the fingers' closing direction, as every robot here; the tool
centre point is RMB's ``<side>/gripper`` site between the fingertips.
"""

from __future__ import annotations

import numpy as np

from rmb_lerobot.envs.robots.common import Arm, Gripper, GripperKind, HandCamera, Pose, Robot

ARM_JOINTS = ("waist", "shoulder", "elbow", "forearm_roll", "wrist_angle", "wrist_rotate")
FINGER_JOINTS = ("left_finger", "right_finger")
HOME = (0.0, -0.96, 1.16, 0.0, -0.3, 0.0)  # rad, both arms
FINGER_OPEN, FINGER_CLOSED = 0.037, 0.002  # m: RMB's finger control range
TABLE_TOP_Z = 0.75  # RMB's table top (z = 0 there) over our floor
BASE_Z = TABLE_TOP_Z + 0.02
# fovy of the D405 wrist cameras (and RMB's overhead and worm's-eye cameras): focal 1.93 mm,
# sensor 2.14 mm high.
D405_FOVY = float(np.degrees(2 * np.arctan(2.14 / 2 / 1.93)))
# Wrist camera in gripper_link: RMB's camera on gripper_base (pos (0, -0.0825, -0.0096), euler
# (2.705, 0, 0)) composed with gripper_base's pose in gripper_link (pos (0.035, 0, 0), euler
# (0, 1.57, -1.57)); computed once with MuJoCo's euler convention (tests check it).
WRIST_CAMERA_POSE = Pose(
    pos=(0.02534, -0.00007, 0.08247),
    quat=(0.59607, 0.38040, -0.37993, -0.59637),
)


def _arm(side: str, pos: tuple[float, float, float], yaw: float) -> Arm:
    """One ViperX arm, every name under ``<side>/``, base at ``pos`` turned ``yaw`` about z."""

    def named(name: str) -> str:
        return f"{side}/{name}"

    return Arm(
        name=side,
        joints=tuple(map(named, ARM_JOINTS)),
        home=HOME,
        gripper=Gripper(
            joints=tuple(map(named, FINGER_JOINTS)),
            open=FINGER_OPEN,
            closed=FINGER_CLOSED,
            measured_scale=1.0,
            kind=GripperKind.SLIDE,
        ),
        mount=Pose(pos=pos, quat=(float(np.cos(yaw / 2)), 0.0, 0.0, float(np.sin(yaw / 2)))),
        root_frame=named("base_link"),
        eef_frame=named("eef"),
        tcp_frame=named("gripper"),
        hand_frame=named("gripper_link"),
        wrench_frame=named("ft_site"),
        hand_camera=HandCamera(f"wrist_cam_{side}", WRIST_CAMERA_POSE, D405_FOVY),
    )


ALOHA = Robot(
    name="aloha",
    rmb_name="Aloha",
    arms=(
        _arm("left", (-0.019, 0.469, BASE_Z), -np.pi / 2),
        _arm("right", (-0.019, -0.469, BASE_Z), np.pi / 2),
    ),
)
"""RMB's MuJoCo ALOHA: 14-D action (per arm 6 joints + finger opening in metres), cameras
``overhead_cam``, ``worms_eye_cam`` (the scene's), ``wrist_cam_left``, ``wrist_cam_right``."""

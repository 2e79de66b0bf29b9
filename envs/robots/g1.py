"""RMB's Unitree G1 upper body: two 7-joint arms with three-finger hands, legs and waist fixed
(MuJoCo model: envs/mujoco/models/g1.py, from ``example-robot-data``'s G1 description).

Facts from RMB (RoboManipBaselines 8535948, ``robo_manip_baselines/envs/``):

- joint names and the 16-D action (``mujoco/g1/MujocoG1EnvBase.py``): per arm, left first,
  ``<side>_shoulder_pitch/roll/yaw_joint``, ``<side>_elbow_joint``,
  ``<side>_wrist_roll/pitch/yaw_joint``, then the hand value, which is the position of
  ``<side>_hand_middle_0_joint`` (measured and commanded alike: RMB's ``_get_obs_single_arm``);
- the hand: one actuator on the middle finger's first joint; the other finger joints follow it
  through joint couplings (``assets/mujoco/robots/g1/g1_config.xml``), so the hand value closes
  the whole hand. The left middle joint runs 0 (open) .. -pi/2 (closed), the right one 0 .. +pi/2
  (the joint ranges of the URDF): :class:`~rmb_lerobot.envs.robots.GripperKind` ``hand``;
- the arms' IK root is the pelvis (``arm_root_pose=self.get_body_pose("pelvis")``), which
  ``robots/g1/g1_body.xml`` puts at (-1.0, 0, 0.05) with the floor at z = -0.75; this repo's
  floor is at z = 0, so the pelvis stands at (-1.0, 0, 0.8), facing +x;
- the ``head`` camera (``g1_body.xml``): on ``torso_link`` at (0.05, 0, 0.4), MJCF euler
  (0, -pi/4, -pi/2), fovy 62 deg.

Home pose: RMB gives one (``MujocoG1BottlesEnv.py``) but leaves it unapplied (its floating
robot "moves quickly to the initial posture and loses balance"); this robot's pelvis is fixed,
so a home pose is applied: :data:`HOME_LEFT` / :data:`HOME_RIGHT`, each open hand palm down
over its bottle of RMB's Bottles scene, ready to grasp it from above.

The end-effector frame (``<side>_eef``) is the palm link's origin with its axes (x along the
fingers, the palm facing -y on the left hand and +y on the right); the tool centre point
(``<side>_grasp``) is where a 3 cm radius bottle sits in the closed hand.
"""

from __future__ import annotations

import numpy as np

from rmb_lerobot.envs.robots.common import (
    Arm,
    BodyCamera,
    Gripper,
    GripperKind,
    Pose,
    Robot,
)

ARM_JOINTS = (
    "shoulder_pitch_joint",
    "shoulder_roll_joint",
    "shoulder_yaw_joint",
    "elbow_joint",
    "wrist_roll_joint",
    "wrist_pitch_joint",
    "wrist_yaw_joint",
)
HAND_JOINT = "hand_middle_0_joint"  # RMB's gripper joint: the synergy's driving joint
PELVIS = "pelvis"
PELVIS_POS = (-1.0, 0.0, 0.8)
# RMB's head camera orientation, MJCF euler (0, -pi/4, -pi/2) (intrinsic xyz) as a quaternion
# (tests/envs/mujoco/models/test_g1.py checks it against MuJoCo's conversion).
HEAD_QUAT = (0.6532814824381883, 0.27059805007309845, -0.27059805007309845, -0.6532814824381883)
HAND_CLOSED = np.pi / 2  # |middle_0| of the closed hand (its joint limit, rad)

# Home: each open hand palm down 10 cm above its bottle's top (its grasp point at
# (-0.74, +-0.12, 1.0)), fingers turned 50 deg inwards and 20 deg down (the expert's grasp
# orientation, envs/experts/bottles.py), found by IK and rounded; mirror images.
HOME_LEFT = (-0.314, 1.16, -0.187, -0.52, 0.211, -0.198, -0.654)
HOME_RIGHT = (-0.314, -1.16, 0.187, -0.52, -0.211, -0.198, 0.654)


def _arm(side: str, home: tuple[float, ...], sign: float) -> Arm:
    """One G1 arm; ``sign`` is the sign of the hand joint when closing (-1 left, +1 right)."""
    return Arm(
        name=side,
        joints=tuple(f"{side}_{joint}" for joint in ARM_JOINTS),
        home=home,
        gripper=Gripper(
            joints=(f"{side}_{HAND_JOINT}",),
            open=0.0,
            closed=sign * HAND_CLOSED,
            measured_scale=1.0,  # RMB records the joint's position itself
            kind=GripperKind.HAND,
        ),
        mount=Pose(pos=PELVIS_POS),
        root_frame=PELVIS,
        eef_frame=f"{side}_eef",
        tcp_frame=f"{side}_grasp",
        hand_frame=f"{side}_hand_palm_link",
        wrench_frame=f"{side}_wrist_ft",
    )


G1 = Robot(
    name="g1",
    rmb_name="G1",
    arms=(_arm("left", HOME_LEFT, -1.0), _arm("right", HOME_RIGHT, 1.0)),
    body_cameras=(
        BodyCamera(
            "head",
            parent="torso_link",
            pose=Pose(pos=(0.05, 0.0, 0.4), quat=HEAD_QUAT),
            fovy=62.0,
        ),
    ),
)
"""RMB's MuJoCo G1 (upper body): 16-D action (per arm 7 joints + hand), camera ``head``."""

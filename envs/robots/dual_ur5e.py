"""RMB's dual UR5e: two UR5e arms with 2F-85 grippers on one stand (MuJoCo model:
envs/mujoco/models/dual_ur5e.py)."""

from __future__ import annotations

import dataclasses

import numpy as np

from rmb_lerobot.envs.robots.common import Arm, HandCamera, Pose, Robot
from rmb_lerobot.envs.robots.ur5e import UR5E


def _ur5e_arm(side: str, mount_y: float, home: tuple[float, ...]) -> Arm:
    """One arm of RMB's dual UR5e: the single UR5e's arm under the ``<side>/`` name prefix,
    mounted ``mount_y`` off the centre line, with its own hand camera ``<side>_hand``."""
    prefix = f"{side}/"
    arm = UR5E.arms[0]

    def named(name: str) -> str:
        return prefix + name

    return Arm(
        name=side,
        joints=tuple(map(named, arm.joints)),
        home=home,
        gripper=dataclasses.replace(arm.gripper, joints=tuple(map(named, arm.gripper.joints))),
        mount=Pose(pos=(arm.mount.pos[0], mount_y, arm.mount.pos[2]), quat=arm.mount.quat),
        root_frame=named(arm.root_frame),
        eef_frame=named(arm.eef_frame),
        tcp_frame=named(arm.tcp_frame),
        hand_frame=named(arm.hand_frame),
        wrench_frame=named(arm.wrench_frame) if arm.wrench_frame else None,
        hand_camera=HandCamera(f"{side}_hand", arm.hand_camera.pose, arm.hand_camera.fovy)
        if arm.hand_camera
        else None,
    )


UR5E_DUAL = Robot(
    name="ur5e_dual",
    rmb_name="UR5eDual",
    # env_ur5e_dual_cable.xml: left/ and right/ arms at y = +-0.4 on one 1.32 m stand; the
    # start pose of MujocoUR5eDualCableEnv.py (RMB has no other dual MuJoCo env).
    arms=(
        _ur5e_arm(
            "left",
            0.4,
            tuple(float(q) for q in np.pi * np.array([0.9, -0.4, -0.65, -0.2, 0.5, 0.5])),
        ),
        _ur5e_arm(
            "right",
            -0.4,
            tuple(float(q) for q in np.pi * np.array([0.1, -0.6, 0.65, -0.8, -0.5, -0.5])),
        ),
    ),
    rmb_envs=frozenset({"RealUR5eDualDemoEnv"}),
)

"""RMB's MuJoCo ALOHA: two ViperX 300 6-DoF arms with slide fingers, generated with MjSpec.

No installable package ships a ViperX model that loads beside MuJoCo 4 (``gym-aloha`` pins
``mujoco<3.9``; facts wave3.md 5.2) and RMB's model files are not copied, so each arm is built
here from Trossen Robotics' published kinematics.

Sources:

- kinematics: Interbotix ``interbotix_xsarm_descriptions/urdf/vx300s.urdf.xacro`` joint
  origins (:data:`LINKS`: waist 0.079 m above the base, shoulder 0.04805 above the waist, the
  upper arm 0.3 m up and 0.05955 forward, forearm 0.2 + 0.1, wrist 0.069744) and axes (waist z,
  shoulder / elbow / wrist_angle y, forearm_roll / wrist_rotate x), as RMB's
  ``assets/mujoco/robots/aloha/aloha_arms_body.xml`` (the Menagerie ALOHA) has them;
- joint limits, damping, armature, friction loss, servo gains and force limits: RMB's
  ``aloha_arms_config.xml`` classes (:data:`JOINT_DYNAMICS`);
- link masses: the URDF's inertial masses (:data:`MASSES`);
- fingers: prismatic, opening 0..0.041 m each (the rail), command 0.002..0.037 m (RMB's
  ``finger`` class, position servo kp 2000, kv 124, |force| <= 35 N, the right finger coupled
  to the left by a joint equality), sliding along the gripper's y axis as RMB's;
- tool centre point: RMB's ``<side>/gripper`` site (0.13 m along the gripper, 3 mm below);
- wrist cameras: RMB's D405 pose on the gripper (:data:`~rmb_lerobot.envs.robots.aloha.
  WRIST_CAMERA_POSE`); an F/T site on ``gripper_link`` (RMB records no wrench for ALOHA; the
  env's wrench keys read it).

What is approximate: the links' shape (capsules of 20-40 mm radius along the joint offsets, a
box for the gripper housing, two 1 cm thick finger plates: not Trossen's meshes), the
inertias (uniform density over those shapes, the URDF's masses) and the contact model (box
pads with MuJoCo's soft contacts instead of RMB's three fingertip spheres and meshes).
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np

from rmb_lerobot.envs.mujoco.models.common import (
    ArmModel,
    RobotModel,
    add_servo,
)
from rmb_lerobot.envs.mujoco.models.generated import ARM_CONAFFINITY, ARM_CONTYPE, add_link_shapes
from rmb_lerobot.envs.robots import Arm, Robot

Vec3 = tuple[float, float, float]
# Per arm joint: its link body (after the side prefix), the body's position in its parent (m),
# the joint axis.
LINKS: tuple[tuple[str, Vec3, Vec3], ...] = (
    ("shoulder_link", (0.0, 0.0, 0.079), (0, 0, 1)),
    ("upper_arm_link", (0.0, 0.0, 0.04805), (0, 1, 0)),
    ("upper_forearm_link", (0.05955, 0.0, 0.3), (0, 1, 0)),
    ("lower_forearm_link", (0.2, 0.0, 0.0), (1, 0, 0)),
    ("wrist_link", (0.1, 0.0, 0.0), (0, 1, 0)),
    ("gripper_link", (0.069744, 0.0, 0.0), (1, 0, 0)),
)
# Per arm joint: range (rad), damping, armature, frictionloss, servo kp, |force| (N m).
JOINT_DYNAMICS: tuple[tuple[tuple[float, float], float, float, float, float, float], ...] = (
    ((-3.14158, 3.14158), 5.76, 0.0, 0.0, 43.0, 35.0),
    ((-1.85005, 1.25664), 20.0, 0.395, 2.0, 265.0, 144.0),
    ((-1.76278, 1.6057), 18.49, 0.383, 1.15, 227.0, 59.0),
    ((-3.14158, 3.14158), 6.78, 0.14, 0.0, 78.0, 22.0),
    ((-1.8675, 2.23402), 6.28, 0.008, 0.0, 37.0, 35.0),
    ((-3.14158, 3.14158), 1.2, 0.0, 0.0, 10.4, 35.0),
)
MASSES = {  # kg, vx300s.urdf inertials (gripper_link carries the gripper housing too)
    "base_link": 0.969034,
    "shoulder_link": 0.798614,
    "upper_arm_link": 0.792592,
    "upper_forearm_link": 0.322228,
    "lower_forearm_link": 0.414823,
    "wrist_link": 0.115395,
    "gripper_link": 0.251652 + 0.42158,
    "finger": 0.0862937,
}
# Link shapes: segments in the body frame and radius.
_SHAPES: dict[str, tuple[tuple[tuple[Vec3, Vec3], ...], float]] = {
    "shoulder_link": ((((0.0, 0.0, -0.003), (0.0, 0.0, 0.045)),), 0.04),
    "upper_arm_link": (
        (((0.0, 0.0, 0.03), (0.0, 0.0, 0.3)), ((0.0, 0.0, 0.3), (0.05955, 0.0, 0.3))),
        0.028,
    ),
    "upper_forearm_link": ((((0.03, 0.0, 0.0), (0.2, 0.0, 0.0)),), 0.024),
    "lower_forearm_link": ((((0.0, 0.0, 0.0), (0.08, 0.0, 0.0)),), 0.022),
    "wrist_link": ((((0.0, 0.0, 0.0), (0.045, 0.0, 0.0)),), 0.02),
}
FINGER_RANGE = (0.0, 0.041)  # m, the rail
FINGER_KP, FINGER_KV, FINGER_FORCE = 2000.0, 124.0, 35.0
FINGER_DAMPING, FINGER_ARMATURE = 40.0, 0.243
FINGER_X = 0.075  # finger bodies ride the rail here (m along gripper_link x)
# One plate per finger: centre (in the finger body) and half sizes; its inner face is at the
# finger's joint position from the gripper's centre line, as RMB's joint value means.
PAD_HALF = (0.04, 0.005, 0.012)
PAD_X = 0.045  # plate from 0.08 to 0.16 along the gripper (the TCP at 0.13 is on it)
HOUSING_HALF, HOUSING_X = (0.03, 0.06, 0.02), 0.04  # gripper housing box (rail 12 cm long)
TCP_POS = (0.13, 0.0, -0.003)  # RMB's <side>/gripper site
BASE_RADIUS, BASE_HEIGHT = 0.05, 0.06
# The eef frame on gripper_link: z along the approach (+x), x along the fingers (+y).
EEF_MAT = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
_BLACK, _GREY, _PAD = (0.15, 0.15, 0.15, 1.0), (0.35, 0.35, 0.38, 1.0), (0.05, 0.05, 0.05, 1.0)


def _mat_quat(mat: np.ndarray) -> list[float]:
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, np.asarray(mat, dtype=np.float64).reshape(9))
    return quat.tolist()


def _prefix(record: Arm) -> str:
    """``left/`` of ``left/waist``: the arm's name prefix, as the record spells its joints."""
    return record.joints[0].rsplit("/", 1)[0] + "/"


def _add_finger(gripper: mujoco.MjsBody, joint: str, sign: float) -> None:
    """A finger plate sliding along ``sign`` * y of the gripper, its inner face at the joint
    position from the centre line."""
    finger = gripper.add_body(name=joint + "_link", pos=[FINGER_X, 0.0, 0.0])
    finger.add_joint(
        name=joint,
        type=mujoco.mjtJoint.mjJNT_SLIDE,
        axis=[0.0, sign, 0.0],
        range=list(FINGER_RANGE),
        damping=[FINGER_DAMPING, 0.0, 0.0],
        armature=FINGER_ARMATURE,
        # Stiff rail ends: with MuJoCo's default limit softness (0.02 s) the fingers overran
        # the rail by 6 mm when the arm was swung at random (the contract's stress test).
        solref_limit=[0.008, 1.0],
    )
    finger.add_geom(
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=list(PAD_HALF),
        pos=[PAD_X, sign * PAD_HALF[1], 0.0],
        mass=MASSES["finger"],
        rgba=list(_PAD),
        contype=ARM_CONTYPE,
        conaffinity=ARM_CONAFFINITY,
        condim=4,
        friction=[1.5, 0.005, 0.0005],
        priority=1,
        solref=[0.004, 1.0],
        solimp=[0.95, 0.99, 0.001, 0.5, 2.0],
    )


def _build_arm(spec: mujoco.MjSpec, record: Arm) -> ArmModel:
    """One ViperX at the record's mount, every name with the record's prefix."""
    prefix = _prefix(record)
    base = spec.worldbody.add_body(
        name=record.root_frame, pos=list(record.mount.pos), quat=list(record.mount.quat)
    )
    add_link_shapes(
        base,
        [((0.0, 0.0, 0.0), (0.0, 0.0, BASE_HEIGHT))],
        BASE_RADIUS,
        MASSES["base_link"],
        _BLACK,
        kind=mujoco.mjtGeom.mjGEOM_CYLINDER,
    )
    body = base
    actuators = []
    for joint, (link, pos, axis), dynamics in zip(
        record.joints, LINKS, JOINT_DYNAMICS, strict=True
    ):
        limits, damping, armature, friction, kp, force = dynamics
        body = body.add_body(name=prefix + link, pos=list(pos))
        body.add_joint(
            name=joint,
            type=mujoco.mjtJoint.mjJNT_HINGE,
            axis=list(axis),
            range=list(limits),
            damping=[damping, 0.0, 0.0],
            armature=armature,
            frictionloss=friction,
        )
        if link in _SHAPES:
            segments, radius = _SHAPES[link]
            add_link_shapes(body, segments, radius, MASSES[link], _BLACK)
        # RMB's actuators are named as their joints (``left/waist``).
        add_servo(spec, joint, joint, kp=kp, kv=0.0, ctrl_range=limits, force_range=(-force, force))
        actuators.append(joint)
    gripper = body
    if gripper.name != record.hand_frame:
        raise ValueError(
            f"the ViperX hand is {gripper.name!r}, the record says {record.hand_frame!r}"
        )
    gripper.add_geom(
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=list(HOUSING_HALF),
        pos=[HOUSING_X, 0.0, 0.0],
        mass=MASSES["gripper_link"],
        rgba=list(_GREY),
        contype=ARM_CONTYPE,
        conaffinity=ARM_CONAFFINITY,
    )
    left, right = record.gripper.joints
    _add_finger(gripper, left, -1.0)
    _add_finger(gripper, right, 1.0)
    spec.add_equality(
        type=mujoco.mjtEq.mjEQ_JOINT,
        name1=right,
        name2=left,
        data=[0.0, 1.0, 0.0, 0.0, 0.0] + [0.0] * 7,
    )
    gripper_actuator = prefix + "gripper"
    add_servo(
        spec,
        gripper_actuator,
        left,
        kp=FINGER_KP,
        kv=FINGER_KV,
        ctrl_range=record.gripper.command_range,
        force_range=(-FINGER_FORCE, FINGER_FORCE),
    )
    gripper.add_site(name=record.eef_frame, quat=_mat_quat(EEF_MAT), size=[0.005, 0, 0], group=4)
    gripper.add_site(name=record.tcp_frame, pos=list(TCP_POS), size=[0.005, 0, 0], group=4)
    gripper.add_site(name=record.wrench_frame, size=[0.005, 0, 0], group=4)
    force, torque = prefix + "force", prefix + "torque"
    for name, kind in (
        (force, mujoco.mjtSensor.mjSENS_FORCE),
        (torque, mujoco.mjtSensor.mjSENS_TORQUE),
    ):
        spec.add_sensor(
            name=name, type=kind, objtype=mujoco.mjtObj.mjOBJ_SITE, objname=record.wrench_frame
        )
    camera = record.hand_camera
    if camera is None:
        raise ValueError(f"arm {record.name!r}: RMB's ALOHA has a wrist camera on each arm")
    gripper.add_camera(
        name=camera.name, pos=list(camera.pose.pos), quat=list(camera.pose.quat), fovy=camera.fovy
    )
    return ArmModel(
        record=record,
        arm_actuators=tuple(actuators),
        gripper_actuator=gripper_actuator,
        base_body=record.root_frame,
        force_sensor=force,
        torque_sensor=torque,
        hand_camera=camera.name,
    )


def build_aloha(
    robot: Robot,
    *,
    visual_mesh_error: float | None = None,
    mesh_cache: Path | bool | None = None,
) -> RobotModel:
    """Both ViperX arms at their records' mounts, on the table (no stand).

    Args:
        robot: The ALOHA record (:data:`rmb_lerobot.envs.robots.ALOHA`): two arms named by
            RMB's ``left/`` and ``right/`` joints, their mounts, grippers and wrist cameras.
        visual_mesh_error: Unused: the model has no meshes (accepted as every builder does).
        mesh_cache: Unused, as ``visual_mesh_error``.

    Returns:
        The model, arms in the record's order, cameras ``wrist_cam_left`` / ``wrist_cam_right``.

    Raises:
        ValueError: If an arm does not name six joints and two fingers.
    """
    del visual_mesh_error, mesh_cache
    for record in robot.arms:
        if len(record.joints) != len(LINKS) or len(record.gripper.joints) != 2:
            raise ValueError(
                f"{robot.name}: a ViperX arm has {len(LINKS)} joints and 2 fingers, arm "
                f"{record.name!r} names {record.joints} and {record.gripper.joints}"
            )
    spec = mujoco.MjSpec()
    spec.modelname = "aloha"
    spec.compiler.autolimits = True
    spec.compiler.degree = False  # joint ranges in radians (MjSpec's default is degrees)
    spec.option.timestep = 0.004  # env_aloha_common.xml
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC  # aloha_arms_config.xml
    spec.option.impratio = 10.0
    arms = tuple(_build_arm(spec, record) for record in robot.arms)
    cameras = {arm.hand_camera: arm.hand_camera for arm in arms if arm.hand_camera}
    return RobotModel("aloha", spec, arms, cameras, stand=None)

"""RMB's MuJoCo Toyota HSR: generated from Toyota's published kinematics with MjSpec.

No installable package ships an HSR model and RMB's model files are not copied, so the robot is
built here from simple shapes.

Sources:

- kinematics and limits: Toyota's ``hsrb_description`` (``robots/hsrb4s.urdf.xacro``,
  https://github.com/hsr-project/hsrb_description, the file RMB's ``hsr_body.xml`` was
  converted from): ``arm_lift_joint`` 0.34 m above ``base_link``, prismatic 0..0.69 m;
  ``arm_flex_joint`` at (0.141, 0.078, 0) of the lift link, axis -y, -2.62..0 rad;
  ``arm_roll_joint`` 0.345 m along the flex link (0.005 m forward), axis z, -2.09..3.84;
  ``wrist_flex_joint`` at the roll joint, axis -y, -1.92..1.22; ``wrist_roll_joint`` axis z,
  -1.92..3.67; the wrist force/torque sensor 0.0735 m past it; ``hand_palm_link`` at (0.012, 0,
  0.1405) of the wrist roll link, turned by pi about z; the fingers' proximal joints at
  (-0.01675, -+0.0245, -0.0175) of the palm, axes +-x, -0.798..1.24 rad, moved together with
  ``hand_motor_joint`` (the URDF's mimic joints; here joint equalities, as RMB's); the head's
  RGB-D sensor at (-0.079796, 0.022, 0.215172) of ``head_tilt_link`` (0.02 m ahead of the
  pan link, 0.752 m above the base; RMB fixes the torso and head joints);
- servos: RMB's ``hsr_config.xml``: velocity actuators (kv 1000, -1..1) on the base's planar
  x, y and yaw joints, position servos kp 2000 (lift), 100 (flex), 10 (roll), 100 (wrist
  flex), 10 (wrist roll), 10 (hand); RMB asks for critical damping (``dampratio 1``), here
  the damping is chosen by hand for these shapes' inertias;
- base mass 50 kg (RMB's inertial of ``base_link``); the arm links' masses are RMB's
  inertials (1.28, 1.34, 0.25, 0.68, 0.76 kg).

What is approximate: every link's shape (a cylinder base of 0.215 m radius, the published
footprint, a column torso, capsules for the arm, boxes for the head, palm and fingers), hence
what collides and what the cameras see; the inertias (uniform density over those shapes); the
fingers are single rigid links (the real hand's distal spring joints are fixed, as in RMB's
model), with pads 10 cm long; the base's wheels are not modelled (the base slides on three
planar joints, as in RMB's model).

Gravity compensation: the arm's and hand's bodies are gravity-compensated (MuJoCo
``gravcomp``). RMB's model has none, and with its soft gains (kp 100 on the flex joint) the arm
sags about 0.1 rad under its own weight; the real HSR's servos hold the arm where it is
commanded, which the compensation stands in for (a held object still loads the servos).
"""

from __future__ import annotations

import mujoco
import numpy as np

from rmb_lerobot.envs.mujoco.models.common import (
    ArmModel,
    RobotModel,
    add_ft_sensor,
    add_servo,
)
from rmb_lerobot.envs.mujoco.models.generated import (
    ARM_CONAFFINITY,
    ARM_CONTYPE,
    add_link_shapes,
    new_arm_spec,
)
from rmb_lerobot.envs.robots import Robot

BASE_RADIUS = 0.215  # m, the HSR's footprint (430 mm across)
BASE_HEIGHT = (0.02, 0.24)  # m, bottom (clear of the floor: the base slides) and top
BASE_MASS = 50.0
TORSO_HEIGHT = 0.752  # torso_lift_link above base_link (torso joint fixed, as RMB's)
LIFT_HEIGHT = 0.34  # arm_lift_joint origin above base_link
FLEX_ORIGIN = (0.141, 0.078, 0.0)
ROLL_ORIGIN = (0.005, 0.0, 0.345)
FT_OFFSET = 0.0735
PALM_ORIGIN = (0.012, 0.0, 0.1405)
FINGER_ORIGIN = (-0.01675, 0.0245, -0.0175)  # right finger; the left one at -y
FINGER_HALF = (0.01, 0.007, 0.055)  # finger box half sizes (m): its pad faces the other
HEAD_TILT_ORIGIN = (0.02, 0.0, 0.0)
HEAD_SENSOR_POSE = ((-0.079796, 0.022, 0.215172), (0.5, -0.5, 0.5, -0.5))
TCP_DEPTH = 0.075  # tool point along the palm's z, between the finger pads
LIMITS = ((0.0, 0.69), (-2.62, 0.0), (-2.09, 3.84), (-1.92, 1.22), (-1.92, 3.67))
HAND_RANGE = (-0.798, 1.24)
MASSES = (1.27582, 1.33929, 0.247936, 0.681225, 0.761692)  # lift, flex, roll, wrist flex, roll
# (kp, kv, max force) per arm joint: RMB's kp; kv chosen here by hand.
GAINS = ((2000.0, 300.0, 300.0), (100.0, 20.0, 100.0), (10.0, 2.0, 100.0))
GAINS += ((100.0, 8.0, 100.0), (10.0, 1.0, 100.0))
HAND_GAINS = (10.0, 2.0, 100.0)
ARMATURE = 0.05  # kg m^2 (kg for the lift): keeps the light wrist servos stable at 4 ms
BASE_KV = 1000.0
_WHITE = (0.9, 0.9, 0.9, 1.0)
_DARK = (0.15, 0.15, 0.15, 1.0)


def _planar_base(spec: mujoco.MjSpec, robot: Robot) -> mujoco.MjsBody:
    """``base_link`` on the floor with the base's x, y slides and yaw hinge, driven by
    velocity actuators named as the joints (RMB's)."""
    assert robot.base is not None
    base = spec.worldbody.add_body(name=robot.base.frame)
    x, y, yaw = robot.base.joints
    slide, hinge = mujoco.mjtJoint.mjJNT_SLIDE, mujoco.mjtJoint.mjJNT_HINGE
    base.add_joint(name=x, type=slide, axis=[1, 0, 0])
    base.add_joint(name=y, type=slide, axis=[0, 1, 0])
    base.add_joint(name=yaw, type=hinge, axis=[0, 0, 1])
    bottom, top = BASE_HEIGHT
    add_link_shapes(
        base,
        [((0.0, 0.0, bottom), (0.0, 0.0, top))],
        BASE_RADIUS,
        BASE_MASS,
        _WHITE,
        kind=mujoco.mjtGeom.mjGEOM_CYLINDER,
    )
    # The torso column up to the head (render and collision, light: its mass is the base's).
    base.add_geom(
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[0.06, 0.05, (TORSO_HEIGHT - top) / 2],
        pos=[-0.07, 0.0, (TORSO_HEIGHT + top) / 2],
        rgba=list(_WHITE),
        mass=0.1,
        contype=ARM_CONTYPE,
        conaffinity=ARM_CONAFFINITY,
    )
    for joint in robot.base.joints:
        act = spec.add_actuator(name=joint, target=joint, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.gaintype = mujoco.mjtGain.mjGAIN_FIXED
        act.biastype = mujoco.mjtBias.mjBIAS_AFFINE
        act.gainprm[0] = BASE_KV
        act.biasprm[0:3] = [0.0, 0.0, -BASE_KV]
        act.ctrlrange = [-1.0, 1.0]
        act.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
    return base


def _head(base: mujoco.MjsBody, robot: Robot) -> None:
    """Torso, pan and tilt links (fixed) and the head camera on the RGB-D sensor link."""
    torso = base.add_body(name="torso_lift_link", pos=[0, 0, TORSO_HEIGHT])
    pan = torso.add_body(name="head_pan_link")
    tilt = pan.add_body(name="head_tilt_link", pos=list(HEAD_TILT_ORIGIN))
    tilt.add_geom(
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[0.06, 0.09, 0.06],
        pos=[-0.08, 0.0, 0.06],
        rgba=list(_DARK),
        mass=2.0,
        contype=ARM_CONTYPE,
        conaffinity=ARM_CONAFFINITY,
    )
    pos, quat = HEAD_SENSOR_POSE
    sensor = tilt.add_body(name="head_rgbd_sensor_link", pos=list(pos), quat=list(quat))
    for camera in robot.body_cameras:
        parent = sensor if camera.parent == sensor.name else base.find_child(camera.parent)
        if parent is None:
            raise ValueError(f"{robot.name}: no body {camera.parent!r} for camera {camera.name!r}")
        parent.add_camera(
            name=camera.name,
            pos=list(camera.pose.pos),
            quat=list(camera.pose.quat),
            fovy=camera.fovy,
        )


def _arm(spec: mujoco.MjSpec, base: mujoco.MjsBody, robot: Robot) -> mujoco.MjsBody:
    """Lift, flex, roll, wrist flex and wrist roll links; returns the wrist roll link."""
    (record,) = robot.arms
    lift_j, flex_j, roll_j, wflex_j, wroll_j = record.joints
    hinge, slide = mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE
    lift = base.add_body(name="arm_lift_link", pos=[0, 0, LIFT_HEIGHT])
    lift.add_joint(name=lift_j, type=slide, axis=[0, 0, 1], range=list(LIMITS[0]))
    add_link_shapes(lift, [((-0.07, 0.0, 0.0), FLEX_ORIGIN)], 0.04, MASSES[0], _WHITE)
    flex = lift.add_body(name="arm_flex_link", pos=list(FLEX_ORIGIN))
    flex.add_joint(name=flex_j, type=hinge, axis=[0, -1, 0], range=list(LIMITS[1]))
    add_link_shapes(flex, [((0.0, 0.0, 0.0), (0.0, 0.0, 0.25))], 0.045, MASSES[1], _WHITE)
    roll = flex.add_body(name="arm_roll_link", pos=list(ROLL_ORIGIN))
    roll.add_joint(name=roll_j, type=hinge, axis=[0, 0, 1], range=list(LIMITS[2]))
    add_link_shapes(roll, [((0.0, 0.0, -0.09), (0.0, 0.0, -0.02))], 0.04, MASSES[2], _WHITE)
    wflex = roll.add_body(name="wrist_flex_link")
    wflex.add_joint(name=wflex_j, type=hinge, axis=[0, -1, 0], range=list(LIMITS[3]))
    add_link_shapes(
        wflex, [((0.0, -0.035, 0.0), (0.0, 0.035, 0.0))], 0.03, MASSES[3], _DARK,
        kind=mujoco.mjtGeom.mjGEOM_CYLINDER,
    )  # fmt: skip
    mount = wflex.add_body(name="wrist_ft_sensor_mount_link")
    mount.add_joint(name=wroll_j, type=hinge, axis=[0, 0, 1], range=list(LIMITS[4]))
    add_link_shapes(mount, [((0.0, 0.0, 0.035), (0.0, 0.0, 0.07))], 0.03, 0.05, _DARK)
    # The F/T sensor frame (turned by pi about x), and the wrist roll link back at the joint.
    ft = mount.add_body(name="wrist_ft_sensor_frame", pos=[0, 0, FT_OFFSET], quat=[0, 1, 0, 0])
    ft.add_geom(
        type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.005, 0, 0], mass=0.01, contype=0,
        conaffinity=0, group=3,
    )  # fmt: skip
    wroll = ft.add_body(name="wrist_roll_link", pos=[0, 0, FT_OFFSET], quat=[0, -1, 0, 0])
    add_link_shapes(wroll, [((0.0, 0.0, 0.07), (0.0, 0.0, 0.1))], 0.035, MASSES[4], _WHITE)
    for joint, (kp, kv, force), limits in zip(record.joints, GAINS, LIMITS, strict=True):
        add_servo(spec, joint, joint, kp=kp, kv=kv, ctrl_range=limits, force_range=(-force, force))
    return wroll


def _hand(spec: mujoco.MjSpec, wroll: mujoco.MjsBody, robot: Robot) -> None:
    """Palm, hand motor joint, two fingers following it, the eef and tool sites, the camera."""
    (record,) = robot.arms
    palm = wroll.add_body(name=record.hand_frame, pos=list(PALM_ORIGIN), quat=[0, 0, 0, 1])
    palm.add_geom(
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[0.025, 0.045, 0.0125],
        pos=[0, 0, -0.03],
        rgba=list(_DARK),
        mass=0.3,
    )
    half = np.sqrt(0.5)
    palm.add_site(name=record.eef_frame, quat=[half, 0, 0, half], size=[0.005, 0, 0], group=4)
    palm.add_site(
        name=record.tcp_frame, pos=[0, 0, TCP_DEPTH], quat=[half, 0, 0, half],
        size=[0.005, 0, 0], group=4,
    )  # fmt: skip
    (motor_joint,) = record.gripper.joints
    hinge = mujoco.mjtJoint.mjJNT_HINGE
    motor = palm.add_body(name="hand_motor_dummy_link")
    motor.add_joint(
        name=motor_joint, type=hinge, axis=[1, 0, 0], range=list(HAND_RANGE), armature=0.001
    )
    motor.add_geom(
        type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.005, 0, 0], mass=0.01, contype=0,
        conaffinity=0, group=3,
    )  # fmt: skip
    fx, fy, fz = FINGER_ORIGIN
    for side, sign in (("l", -1.0), ("r", 1.0)):
        finger = palm.add_body(name=f"hand_{side}_proximal_link", pos=[fx, sign * fy, fz])
        joint = f"hand_{side}_proximal_joint"
        finger.add_joint(
            name=joint, type=hinge, axis=[-sign, 0, 0], range=list(HAND_RANGE), armature=0.001
        )
        hx, hy, hz = FINGER_HALF
        finger.add_geom(
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=[hx, hy, hz],
            pos=[-fx, 0.0, hz],
            rgba=list(_DARK),
            mass=0.05,
            friction=[1.5, 0.01, 0.001],
            condim=4,
        )
        spec.add_equality(
            type=mujoco.mjtEq.mjEQ_JOINT,
            name1=joint,
            name2=motor_joint,
            objtype=mujoco.mjtObj.mjOBJ_JOINT,
            data=[0, 1, 0, 0, 0] + [0] * 7,  # polycoef: finger = motor
            solref=[0.005, 1.0],
            solimp=[0.95, 0.99, 0.001, 0.5, 2.0],
        )
    kp, kv, force = HAND_GAINS
    add_servo(
        spec,
        motor_joint,
        motor_joint,
        kp=kp,
        kv=kv,
        ctrl_range=HAND_RANGE,
        force_range=(-force, force),
    )
    cam = record.hand_camera
    if cam is not None:
        palm.add_camera(
            name=cam.name, pos=list(cam.pose.pos), quat=list(cam.pose.quat), fovy=cam.fovy
        )


def build_hsr(robot: Robot) -> RobotModel:
    """The HSR: planar base, fixed torso and head (``head`` camera), arm, wrist F/T sensor, hand
    (``hand`` camera).

    Args:
        robot: The HSR record (:data:`rmb_lerobot.envs.robots.HSR`): joints, home, hand, base,
            frames and cameras.

    Returns:
        The model; no stand (the robot stands on the floor).

    Raises:
        ValueError: If the record has no base, not one arm of five joints, or no wrench frame.
    """
    if robot.base is None or len(robot.arms) != 1 or len(robot.arms[0].joints) != len(LIMITS):
        raise ValueError(f"{robot.name}: the HSR model has a mobile base and one 5-joint arm")
    (record,) = robot.arms
    if record.wrench_frame is None:
        raise ValueError(f"{robot.name}: the HSR model has a wrist F/T sensor")
    spec = new_arm_spec("hsr")
    # Elliptic friction cones and a high impratio hold a squeezed object without creep (the
    # 2F-85 model's settings, which the other robots' scenes take on).
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    spec.option.impratio = 10.0
    base = _planar_base(spec, robot)
    _head(base, robot)
    wroll = _arm(spec, base, robot)
    _hand(spec, wroll, robot)
    force, torque = add_ft_sensor(spec, "wrist_ft_sensor_frame", record.wrench_frame)
    for joint in (*record.joints, *record.gripper.joints):
        spec.joint(joint).armature = max(spec.joint(joint).armature, ARMATURE)
    # The arm and hand carry their own weight (see the module docstring).
    lift = spec.body("arm_lift_link")
    for body in (lift, *lift.find_all(mujoco.mjtObj.mjOBJ_BODY)):
        body.gravcomp = 1.0
    arm = ArmModel(
        record=record,
        arm_actuators=record.joints,
        gripper_actuator=record.gripper.joints[0],
        base_body="arm_lift_link",
        force_sensor=force,
        torque_sensor=torque,
        hand_camera=record.hand_camera.name if record.hand_camera else None,
    )
    cameras = {name: name for name in robot.cameras}
    return RobotModel("hsr", spec, (arm,), cameras, stand=None)

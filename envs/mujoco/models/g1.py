"""RMB's MuJoCo Unitree G1 upper body, from ``example-robot-data``'s G1 description.

The model is ``g1_description/urdf/g1_29dof_with_hand_rev_1_0.urdf`` (BSD-3, Unitree's URDF with
the three-finger hands; its STL meshes are most of RMB's byte for byte) loaded by MuJoCo's URDF
importer, then edited with :class:`mujoco.MjSpec` to be RMB's upper-body robot:

- the pelvis is fixed at the record's mount (RMB's floating base falls over; the task here is
  bimanual manipulation, not balance), and the legs', the waist's and the thumbs' base joints
  are removed, so those links are rigid (RMB drives the legs and waist to zero and has no thumb
  base joint);
- one position servo per arm joint and one per hand, named as their joints, as RMB's
  ``g1_config.xml``: kp 500, damping ratio 1, |force| <= 25 N m (shoulders, elbow, wrist roll),
  5 N m (wrist pitch, yaw), 2.8 N m (hand); arm joints with friction loss 0.3 N m as RMB's,
  fingers with light damping instead (:data:`HAND_DAMPING`); armature and limit stiffness
  differ from RMB's where stated (:data:`ARMATURE`, :data:`LIMIT_SOLREF`);
- the hand synergy: every finger joint follows ``<side>_hand_middle_0_joint`` through a joint
  equality (RMB's couplings: index and middle phalanges equal to it, the thumb's second joint
  its negative, the thumb's first ``(m + 0.5) / -1.5`` on the left, ``(m - 0.5) / -1.5`` on the
  right), so one command closes the hand. An episode starts with every finger joint at zero
  (the backend sets the driving joint only); the couplings take the thumb to the open hand's
  pose (its first joint to about -0.33 rad) within the first control step, above the bottles;
- sites: ``<side>_eef`` (the palm link's origin), ``<side>_grasp`` (where a 3 cm radius bottle
  sits in the closed hand, :data:`GRASP_OFFSET`), ``<side>_wrist_ft`` with a force and a torque
  sensor on the palm (RMB records no wrench for the G1; the sensors keep every arm alike);
- the ``head`` camera on ``torso_link`` at RMB's pose (the record's body camera).

What is approximate: collision shapes are the convex hulls MuJoCo makes of the URDF's meshes
(coarser than the real hand: the palm is a convex blob); inertias are the URDF's. RMB's model
differs in that its left thumb's first joint starts at -0.724 rad (the URDF: -0.611).
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np

from rmb_lerobot.envs.mujoco.meshes import DEFAULT_VISUAL_MESH_ERROR, simplify_visual_meshes
from rmb_lerobot.envs.mujoco.models.common import (
    ArmModel,
    RobotModel,
    add_render_twins,
    add_servo,
    load_erd_urdf,
)
from rmb_lerobot.envs.robots import Arm, Robot
from rmb_lerobot.envs.robots.g1 import HAND_JOINT, PELVIS

URDF = "g1_description/urdf/g1_29dof_with_hand_rev_1_0.urdf"
LEG_JOINTS = tuple(
    f"{side}_{joint}_joint"
    for side in ("left", "right")
    for joint in ("hip_pitch", "hip_roll", "hip_yaw", "knee", "ankle_pitch", "ankle_roll")
)
FIXED_JOINTS = (
    *LEG_JOINTS,
    "waist_yaw_joint",
    "waist_roll_joint",
    "waist_pitch_joint",
    "left_hand_thumb_0_joint",
    "right_hand_thumb_0_joint",
)
_GRAY = (0.7, 0.7, 0.7, 1.0)  # RMB's "metal" material
KP = 500.0
DAMPING_RATIO = 1.0
ARM_FORCES = (25.0, 25.0, 25.0, 25.0, 25.0, 5.0, 5.0)  # N m per ARM_JOINTS (g1_body.xml)
HAND_FORCE = 2.8  # N m (hand_middle_0_joint)
# Joint armature (kg m^2): RMB's 0.01 on the fingers; 0.05 on the arm joints, whose light
# distal links otherwise let the 25 N m servos drive them 0.5 rad through their limits when
# commanded across the range (the contract tests' random actions); 0.18 rad with these settings.
ARMATURE = 0.05
HAND_ARMATURE = 0.01
# Joint limits as stiff as the 4 ms step allows (time constant 2 steps; MuJoCo's default 0.02 s
# is soft against the servos' force on such light links).
LIMIT_SOLREF = (0.008, 1.0)
FRICTIONLOSS = 0.3  # N m, arm joints
# The fingers have no friction loss (RMB's 0.3 N m on each of the six coupled joints holds the
# 2.8 N m hand servo nearly still: the hand took seconds to close) and light damping instead,
# so the hand closes in about 0.6 s without ringing.
HAND_DAMPING = 0.1  # N m s / rad
# Where the held bottle's axis sits in the palm link frame when the hand closes on it (m);
# measured on the expert's grasps of the 3 cm radius bottles from above (the left hand; the
# right one is its mirror image); tests/envs/experts/test_bottles.py checks a held bottle's
# axis stays within 3 cm of it.
GRASP_OFFSET = (0.077, -0.05, 0.0)
FINGERS = (
    "hand_thumb_1_joint",
    "hand_thumb_2_joint",
    "hand_middle_1_joint",
    "hand_index_0_joint",
    "hand_index_1_joint",
)


def synergy(side: str) -> dict[str, tuple[float, float]]:
    """Per finger joint ``(a0, a1)``: MuJoCo's joint equality ``middle_0 = a0 + a1 * finger``
    (RMB's ``polycoef``), which makes every finger follow the hand's driving joint."""
    thumb_offset = -0.5 if side == "left" else 0.5
    couplings = (
        (thumb_offset, -1.5),  # thumb_1
        (0.0, -1.0),  # thumb_2
        (0.0, 1.0),  # middle_1
        (0.0, 1.0),  # index_0
        (0.0, 1.0),  # index_1
    )
    return {f"{side}_{name}": coef for name, coef in zip(FINGERS, couplings, strict=True)}


def finger_positions(side: str, hand: float) -> dict[str, float]:
    """Finger joint positions the synergy gives for hand value ``hand`` (the middle joint)."""
    return {joint: (hand - a0) / a1 for joint, (a0, a1) in synergy(side).items()}


def _add_servo(spec: mujoco.MjSpec, joint: str, force: float, ctrl: tuple[float, float]) -> None:
    act = add_servo(spec, joint, joint, kp=KP, kv=0.0, ctrl_range=ctrl, force_range=(-force, force))
    # A positive third bias parameter is a damping ratio, turned into kv when compiled (MJCF's
    # ``dampratio``, as RMB's ``<position dampratio="1">``).
    act.biasprm[2] = DAMPING_RATIO


def _add_hand(spec: mujoco.MjSpec, record: Arm) -> None:
    """The finger couplings, the grasp and eef sites of one hand."""
    side = record.name
    driver = f"{side}_{HAND_JOINT}"
    for finger, (a0, a1) in synergy(side).items():
        spec.add_equality(
            type=mujoco.mjtEq.mjEQ_JOINT,
            name1=driver,
            name2=finger,
            data=[a0, a1, 0, 0, 0] + [0.0] * 7,
            solref=[0.005, 1.0],
            solimp=[0.95, 0.99, 0.001, 0.5, 2.0],
        )
    palm = spec.body(record.hand_frame)
    grasp = np.array(GRASP_OFFSET) * (1.0, 1.0 if side == "left" else -1.0, 1.0)
    palm.add_site(name=record.eef_frame, size=[0.005, 0, 0], group=4)
    palm.add_site(name=record.tcp_frame, pos=grasp.tolist(), size=[0.005, 0, 0], group=4)


def build_g1(
    robot: Robot,
    *,
    visual_mesh_error: float = DEFAULT_VISUAL_MESH_ERROR,
    mesh_cache: Path | bool | None = True,
) -> RobotModel:
    """The G1 upper body: arms, hands with their synergy, head camera; pelvis at the mount.

    Args:
        robot: The G1 record (:data:`rmb_lerobot.envs.robots.G1`): arms ``left`` and
            ``right`` (joints, hand, frames, mount: both arms share the pelvis) and the
            ``head`` body camera.
        visual_mesh_error: Bound (m) of the simplification of the drawn meshes, as
            :func:`~rmb_lerobot.envs.mujoco.robot.build_robot_spec` (the URDF's meshes have
            360k triangles: too many for software rendering).
        mesh_cache: Where simplified meshes are cached.

    Returns:
        The model, arms in the record's order; the robot stands on the floor (no stand).

    Raises:
        ValueError: If the record's arms do not share one mount (they share the pelvis) or
            name no wrench frame.
    """
    mounts = {arm.mount for arm in robot.arms}
    if len(mounts) != 1:
        raise ValueError(f"{robot.name}: both G1 arms hang from the pelvis; got mounts {mounts}")
    if any(arm.wrench_frame is None for arm in robot.arms):
        raise ValueError(f"{robot.name}: the G1 model has a force/torque site on each palm")
    (pelvis_pose,) = mounts
    spec, urdf = load_erd_urdf(URDF)
    # Render twins first, always: the simplified-mesh cache is keyed by the URDF, not by edits.
    add_render_twins(spec, rgba=_GRAY)
    simplify_visual_meshes(spec, urdf, visual_mesh_error, cache=mesh_cache)
    spec.modelname = "g1"
    spec.compiler.degree = False
    spec.compiler.autolimits = True
    for name in FIXED_JOINTS:
        spec.delete(spec.joint(name))
    pelvis = spec.body(PELVIS)
    pelvis.pos = list(pelvis_pose.pos)
    pelvis.quat = list(pelvis_pose.quat)
    for joint in spec.joints:
        hand = "_hand_" in joint.name
        joint.armature = HAND_ARMATURE if hand else ARMATURE
        joint.solref_limit = list(LIMIT_SOLREF)
        joint.frictionloss = 0.0 if hand else FRICTIONLOSS
        joint.damping[0] = HAND_DAMPING if hand else 0.0

    arms = []
    for record in robot.arms:
        side = record.name
        for joint, force in zip(record.joints, ARM_FORCES, strict=True):
            _add_servo(spec, joint, force, tuple(spec.joint(joint).range))
        gripper = record.gripper.joints[0]
        _add_servo(spec, gripper, HAND_FORCE, record.gripper.command_range)
        _add_hand(spec, record)
        palm = spec.body(record.hand_frame)
        palm.add_site(name=record.wrench_frame, size=[0.005, 0, 0], group=4)
        force, torque = f"{side}_force", f"{side}_torque"
        for name, kind in (
            (force, mujoco.mjtSensor.mjSENS_FORCE),
            (torque, mujoco.mjtSensor.mjSENS_TORQUE),
        ):
            spec.add_sensor(
                name=name, type=kind, objtype=mujoco.mjtObj.mjOBJ_SITE, objname=record.wrench_frame
            )
        arms.append(
            ArmModel(
                record=record,
                arm_actuators=record.joints,
                gripper_actuator=gripper,
                base_body=PELVIS,
                force_sensor=force,
                torque_sensor=torque,
                hand_camera=None,
            )
        )
    cameras = {}
    for camera in robot.body_cameras:
        spec.body(camera.parent).add_camera(
            name=camera.name,
            pos=list(camera.pose.pos),
            quat=list(camera.pose.quat),
            fovy=camera.fovy,
        )
        cameras[camera.name] = camera.name
    return RobotModel("g1", spec, tuple(arms), cameras, stand=None)

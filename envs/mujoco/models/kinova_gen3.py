"""RMB's MuJoCo Kinova Gen3 (7 DoF): generated from Kinova's published kinematics + the 2F-85.

No installable package ships a Gen3 model (``example-robot-data``'s ``kinova_description`` is
the JACO; ``robosuite`` has Gen3 meshes but is a poor dependency: DESIGN 7.1), and RMB's model
files are not copied, so the arm is built here with :class:`mujoco.MjSpec`.

Sources:

- kinematics: the Gen3 7-DoF user guide's joint frame transforms, identical to Kinova's
  ``kortex_description`` (``gen3.xacro``) joint origins (:data:`JOINT_ORIGINS`: the base to
  joint 1 offset 156.43 mm, the half-arms' 210.38 mm, the forearm's 208.43 mm, the spherical
  wrist's 105.93 mm, the 5.375 / 6.375 / 0.175 mm lateral offsets, and the 61.525 mm from
  joint 7 to the tool flange); RMB's ``kinovagen3_body.xml`` has the same numbers;
- joint limits: user guide, joints 2, 4, 6 +-128.9, +-147.8, +-120.3 deg (RMB's actuator
  ``ctrlrange`` 2.2497, 2.5796, 2.0996 rad); joints 1, 3, 5, 7 turn without limit on the robot,
  here +-2 pi (RMB's actuator ``ctrlrange`` +-6.28);
- link masses: the user guide's (1.697 kg base, 1.377 shoulder, 1.164 per half-arm, 0.930
  forearm, 0.678 per wrist link, 0.500 bracelet with the vision module);
- servos: RMB's ``kinovagen3_config.xml`` classes ``large_actuator`` (joints 1-4: kp 2000,
  kv 400, |force| <= 105) and ``small_actuator`` (5-7: kp 500, kv 100, |force| <= 52);
- gripper: the UR5e's Robotiq 2F-85 (:mod:`~rmb_lerobot.envs.mujoco.models.robotiq_2f85`),
  on the tool flange with its fingers closing along the bracelet's x axis, as RMB's
  ``gripper_base`` (``kinovagen3_body.xml``);
- hand camera, mount, home: the record's (:data:`rmb_lerobot.envs.robots.KINOVA_GEN3`).

What is approximate: the links' shape (capsules of 45 mm radius for the large actuators, 35 mm
for the wrist, a cylinder for the bracelet; :mod:`~rmb_lerobot.envs.mujoco.models.generated`),
so what collides and what the cameras see is coarser than the real arm; their inertias (uniform
density over those shapes, not Kinova's inertia tensors); and the joints' armature
(:data:`ARMATURE`, which RMB's model does not have: the rod-cable scene's ``discrete``
integrator needs it, as the xArm7's and Panda's joints).
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np

from rmb_lerobot.envs.mujoco.meshes import DEFAULT_VISUAL_MESH_ERROR
from rmb_lerobot.envs.mujoco.models import robotiq_2f85
from rmb_lerobot.envs.mujoco.models.common import (
    RobotModel,
    StandBox,
    add_arm_servos,
    euler_quat,
)
from rmb_lerobot.envs.mujoco.models.generated import add_link_shapes, finish_2f85_arm, new_arm_spec
from rmb_lerobot.envs.robots import HandCamera, Robot

BASE_BODY = "base_link"
# Link bodies after the base, each turned by its joint (names as Kinova's and RMB's).
LINKS = (
    "shoulder_link",
    "half_arm_1_link",
    "half_arm_2_link",
    "forearm_link",
    "spherical_wrist_1_link",
    "spherical_wrist_2_link",
    "bracelet_link",
)
# Kinova's joint frame transforms (parent link frame -> child link frame): position (m) and
# roll about x (rad); each joint turns about its child frame's z axis.
JOINT_ORIGINS: tuple[tuple[tuple[float, float, float], float], ...] = (
    ((0.0, 0.0, 0.15643), np.pi),
    ((0.0, 0.005375, -0.12838), np.pi / 2),
    ((0.0, -0.21038, -0.006375), -np.pi / 2),
    ((0.0, 0.006375, -0.21038), np.pi / 2),
    ((0.0, -0.20843, -0.006375), -np.pi / 2),
    ((0.0, 0.00017505, -0.10593), np.pi / 2),
    ((0.0, -0.10593, -0.00017505), -np.pi / 2),
)
FLANGE_OFFSET = 0.061525  # m from joint 7's origin to the tool flange, along -z of bracelet_link
# Kinova's tool frame on bracelet_link: at the flange, turned by pi about x (z out of the arm).
TOOL_QUAT = (0.0, 1.0, 0.0, 0.0)
LIMITS = (2 * np.pi, 2.2497, 2 * np.pi, 2.5796, 2 * np.pi, 2.0996, 2 * np.pi)  # rad, +-
MASSES = (1.697, 1.377, 1.164, 1.164, 0.930, 0.678, 0.678, 0.500)  # kg: base, then LINKS
ACTUATORS = tuple(f"joint_{i}" for i in range(1, 8))  # RMB names its actuators as the joints
_GAINS = ((2000, 400, 105),) * 4 + ((500, 100, 52),) * 3
ARMATURE = 0.1  # kg m^2 per arm joint (see the module docstring)
LARGE_RADIUS, SMALL_RADIUS, BRACELET_RADIUS = 0.045, 0.035, 0.04
RMB_STAND = StandBox(pos=(-0.5, 0.0, 0.4), half_size=(0.22, 0.22, 0.4))  # env_kinovagen3_cable
_GRAY = (0.75294, 0.75294, 0.75294, 1.0)  # kinovagen3_config.xml class "visual"
_DARK = (0.2, 0.2, 0.2, 1.0)


def _build_arm(spec: mujoco.MjSpec, joints: tuple[str, ...]) -> None:
    """Base and the seven links, each drawn between its joint origin and the next one."""
    body = spec.worldbody.add_body(name=BASE_BODY)
    origin0 = JOINT_ORIGINS[0][0]
    add_link_shapes(
        body,
        [((0.0, 0.0, 0.0), origin0)],
        LARGE_RADIUS,
        MASSES[0],
        _GRAY,
        kind=mujoco.mjtGeom.mjGEOM_CYLINDER,
    )
    for i, (name, joint) in enumerate(zip(LINKS, joints, strict=True)):
        pos, roll = JOINT_ORIGINS[i]
        body = body.add_body(name=name, pos=list(pos), quat=euler_quat((roll, 0.0, 0.0)))
        body.add_joint(
            name=joint,
            type=mujoco.mjtJoint.mjJNT_HINGE,
            axis=[0, 0, 1],
            range=[-LIMITS[i], LIMITS[i]],
            armature=ARMATURE,
        )
        if i + 1 < len(LINKS):
            radius = LARGE_RADIUS if i < 4 else SMALL_RADIUS
            end = JOINT_ORIGINS[i + 1][0]
            add_link_shapes(body, [((0.0, 0.0, 0.0), end)], radius, MASSES[i + 1], _GRAY)
        else:  # the bracelet ends flat at the flange, where the gripper sits
            flange = (0.0, 0.0, -FLANGE_OFFSET)
            add_link_shapes(
                body,
                [((0.0, 0.0, 0.0), flange)],
                BRACELET_RADIUS,
                MASSES[i + 1],
                _GRAY,
                kind=mujoco.mjtGeom.mjGEOM_CYLINDER,
            )


def _add_hand_camera(body: mujoco.MjsBody, camera: HandCamera) -> None:
    """RMB's ``hand`` camera on the bracelet, and the vision module's housing behind its lens
    drawn as a box (render only; it ends 3.5 mm short of the lens, out of the camera's view)."""
    body.add_geom(
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[0.02, 0.012, 0.0125],
        pos=[0.0, -0.047, -0.0425],
        rgba=list(_DARK),
        contype=0,
        conaffinity=0,
        group=2,
    )
    body.add_camera(
        name=camera.name, pos=list(camera.pose.pos), quat=list(camera.pose.quat), fovy=camera.fovy
    )


def build_kinova_gen3(
    robot: Robot,
    *,
    visual_mesh_error: float = DEFAULT_VISUAL_MESH_ERROR,
    mesh_cache: Path | bool | None = True,
) -> RobotModel:
    """Kinova Gen3 + Robotiq 2F-85 + wrist F/T sensor + ``hand`` camera, on RMB's stand.

    Args:
        robot: The Kinova Gen3 record (:data:`rmb_lerobot.envs.robots.KINOVA_GEN3`): joints,
            home, gripper, frames, hand camera and mount.
        visual_mesh_error: Visual mesh simplification bound of the gripper's meshes (m), as
            :func:`~rmb_lerobot.envs.mujoco.robot.build_robot_spec`.
        mesh_cache: Where simplified meshes are cached.

    Returns:
        The model, on RMB's stand under the record's mount.

    Raises:
        ValueError: If the record has no wrench frame or hand camera (this model has both), or
            not seven joints.
    """
    (record,) = robot.arms
    if record.wrench_frame is None or record.hand_camera is None:
        raise ValueError(f"{robot.name}: the Kinova Gen3 model has a wrist F/T sensor and a camera")
    if len(record.joints) != len(LINKS):
        raise ValueError(
            f"{robot.name}: the Kinova Gen3 has 7 joints, the record names {record.joints}"
        )
    spec = new_arm_spec("kinova_gen3")  # env_kinovagen3_common.xml
    _build_arm(spec, record.joints)
    add_arm_servos(spec, record.joints, ACTUATORS, _GAINS)

    bracelet = spec.body(record.hand_frame)
    bracelet.add_site(
        name=record.eef_frame,
        pos=[0, 0, -FLANGE_OFFSET],
        quat=list(TOOL_QUAT),
        size=[0.005, 0, 0],
        group=4,
    )
    gripper_actuator = robotiq_2f85.attach_2f85(
        spec, record.eef_frame, visual_mesh_error=visual_mesh_error, mesh_cache=mesh_cache
    )
    # The bracelet touches the gripper housing at the flange (the mount is its child: excluded).
    spec.add_exclude(bodyname1=record.hand_frame, bodyname2=robotiq_2f85.BASE_BODY)
    _add_hand_camera(bracelet, record.hand_camera)
    return finish_2f85_arm(
        spec,
        record,
        model_name="kinova_gen3",
        base_body=BASE_BODY,
        arm_actuators=ACTUATORS,
        gripper_actuator=gripper_actuator,
        rmb_stand=RMB_STAND,
    )

"""RMB's MuJoCo FANUC CRX-5iA: generated from FANUC's published dimensions + the 2F-85.

No installable package ships a CRX-5iA model (``crx-kinematics`` has FK/IK code only:
facts wave3.md 5.2), and RMB's model files are not copied, so the arm is built here with
:class:`mujoco.MjSpec`.

Sources:

- kinematics: the CRX-5iA datasheet's dimensions (J2 185 mm above the base, 410 mm upper arm,
  430 mm forearm, 130 mm J5-J6 offset, 145 mm J6 to the faceplate; 994 mm reach) in the joint
  layout of RMB's ``assets/common/robots/crx5ia/crx5ia.urdf`` (J1 about z, J2 about y, J3 about
  -y, J4 about -x, J5 about -y, J6 about -x; all joints zero with the upper arm up and the
  forearm along +x): :data:`JOINTS`;
- joint limits: the datasheet's motion ranges as RMB's URDF gives them (J1 +-200 deg, J2
  +-179.9, J3 -68..+248, J4 +-190, J5 +-179.9, J6 +-225);
- servos: RMB's ``crx5ia_config.xml`` classes ``large_actuator`` (J1-J3: kp 2000, kv 400,
  |force| <= 160) and ``small_actuator`` (J4-J6: kp 500, kv 100, |force| <= 40);
- gripper: the UR5e's Robotiq 2F-85 (:mod:`~rmb_lerobot.envs.mujoco.models.robotiq_2f85`) on
  the faceplate, turned as RMB's ``base_mount`` (``crx5ia_body.xml``: z along J6's axis);
- F/T site on the gripper's mount (RMB's ``force_sensor`` site); no hand camera (RMB has none);
- mount, home: the record's (:data:`rmb_lerobot.envs.robots.CRX5IA`).

What is approximate: the links' shape (capsules and cylinders of 40-80 mm radius,
:mod:`~rmb_lerobot.envs.mujoco.models.generated`; the real arm's links are offset sideways from
the joint axes, which changes neither the kinematics nor the joint layout, only what collides);
the link masses (:data:`MASSES`: the datasheet gives 25 kg for the whole arm, split here by the
links' size) and their inertias (uniform density over those shapes); and the joints' armature
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
)
from rmb_lerobot.envs.mujoco.models.generated import add_link_shapes, finish_2f85_arm, new_arm_spec
from rmb_lerobot.envs.robots import Robot

BASE_BODY = "base_link"
J2_HEIGHT, UPPER_ARM, FOREARM, WRIST_OFFSET, FACEPLATE = 0.185, 0.41, 0.43, 0.13, 0.145  # m

Vec3 = tuple[float, float, float]
# Per joint: its link body, the body's position in its parent (m), the joint axis, the limits
# (rad) and the link's shape (segments in the body frame, radius).
JOINTS: tuple[tuple[str, Vec3, Vec3, tuple[float, float]], ...] = (
    ("J1_link", (0.0, 0.0, J2_HEIGHT), (0, 0, 1), (-3.49066, 3.49066)),
    ("J2_link", (0.0, 0.0, 0.0), (0, 1, 0), (-3.13985, 3.13985)),
    ("J3_link", (0.0, 0.0, UPPER_ARM), (0, -1, 0), (-1.18682, 4.32842)),
    ("J4_link", (0.0, 0.0, 0.0), (-1, 0, 0), (-3.31613, 3.31613)),
    ("J5_link", (FOREARM, 0.0, 0.0), (0, -1, 0), (-3.13985, 3.13985)),
    ("J6_link", (0.0, -WRIST_OFFSET, 0.0), (-1, 0, 0), (-3.92699, 3.92699)),
)
# Shapes per link body (segments, radius): the J1 housing around J2's axis, the upper arm, the
# elbow housing around J3's axis, the forearm, the J5-J6 offset, the J6 housing to the faceplate.
_SHAPES: dict[str, tuple[tuple[tuple[Vec3, Vec3], ...], float]] = {
    "J1_link": ((((0.0, -0.08, 0.0), (0.0, 0.08, 0.0)),), 0.075),
    "J2_link": ((((0.0, 0.0, 0.08), (0.0, 0.0, UPPER_ARM - 0.07)),), 0.06),
    "J3_link": ((((0.0, -0.06, 0.0), (0.0, 0.06, 0.0)),), 0.06),
    "J4_link": ((((0.07, 0.0, 0.0), (FOREARM - 0.05, 0.0, 0.0)),), 0.05),
    "J5_link": ((((0.0, 0.04, 0.0), (0.0, -WRIST_OFFSET + 0.045, 0.0)),), 0.045),
}
_J6_RADIUS = 0.045  # the J6 housing: a cylinder ending flat at the faceplate
BASE_RADIUS = 0.08
# kg; the datasheet's 25 kg split by link size (approximate, see the module docstring).
MASSES = {"base": 4.0, "J1_link": 5.0, "J2_link": 5.5, "J3_link": 3.0, "J4_link": 3.5}
MASSES |= {"J5_link": 2.0, "J6_link": 2.0}
ACTUATORS = tuple(f"act{i}" for i in range(1, 7))  # crx5ia_config.xml
_GAINS = ((2000, 400, 160),) * 3 + ((500, 100, 40),) * 3
ARMATURE = 0.1  # kg m^2 per arm joint (see the module docstring)
# The faceplate turned so its z axis is J6's outward axis (+x of J6_link): pi/2 about y, as
# RMB's base_mount quaternion (-1, 0, -1, 0).
FACEPLATE_QUAT = (np.sqrt(0.5), 0.0, np.sqrt(0.5), 0.0)
RMB_STAND = StandBox(pos=(-0.5, 0.0, 0.4), half_size=(0.22, 0.22, 0.4))  # env_crx5ia_cable.xml
_WHITE, _BLACK = (0.99, 0.99, 0.99, 1.0), (0.1, 0.1, 0.1, 1.0)  # crx5ia_config.xml materials


def _build_arm(spec: mujoco.MjSpec, joints: tuple[str, ...], hand_frame: str) -> None:
    """Base, the six links and the faceplate body ``hand_frame``."""
    body = spec.worldbody.add_body(name=BASE_BODY)
    cylinder = mujoco.mjtGeom.mjGEOM_CYLINDER
    base_top = (0.0, 0.0, J2_HEIGHT - 0.075)
    add_link_shapes(
        body, [((0.0, 0.0, 0.0), base_top)], BASE_RADIUS, MASSES["base"], _BLACK, kind=cylinder
    )
    for joint, (name, pos, axis, limits) in zip(joints, JOINTS, strict=True):
        body = body.add_body(name=name, pos=list(pos))
        body.add_joint(
            name=joint,
            type=mujoco.mjtJoint.mjJNT_HINGE,
            axis=list(axis),
            range=list(limits),
            armature=ARMATURE,
        )
        if name in _SHAPES:
            segments, radius = _SHAPES[name]
            add_link_shapes(body, segments, radius, MASSES[name], _WHITE)
    add_link_shapes(
        body,
        [((-0.045, 0.0, 0.0), (FACEPLATE, 0.0, 0.0))],
        _J6_RADIUS,
        MASSES["J6_link"],
        _BLACK,
        kind=cylinder,
    )
    body.add_body(name=hand_frame, pos=[FACEPLATE, 0.0, 0.0], quat=list(FACEPLATE_QUAT))


def build_crx5ia(
    robot: Robot,
    *,
    visual_mesh_error: float = DEFAULT_VISUAL_MESH_ERROR,
    mesh_cache: Path | bool | None = True,
) -> RobotModel:
    """CRX-5iA + Robotiq 2F-85 + wrist F/T sensor, on RMB's stand.

    Args:
        robot: The CRX-5iA record (:data:`rmb_lerobot.envs.robots.CRX5IA`): joints, home,
            gripper, frames and mount.
        visual_mesh_error: Visual mesh simplification bound of the gripper's meshes (m), as
            :func:`~rmb_lerobot.envs.mujoco.robot.build_robot_spec`.
        mesh_cache: Where simplified meshes are cached.

    Returns:
        The model, on RMB's stand under the record's mount.

    Raises:
        ValueError: If the record has no wrench frame, has a hand camera (RMB's CRX-5iA has
            none) or does not name six joints.
    """
    (record,) = robot.arms
    if record.wrench_frame is None or record.hand_camera is not None:
        raise ValueError(
            f"{robot.name}: the CRX-5iA model has a wrist F/T sensor and no hand camera"
        )
    if len(record.joints) != len(JOINTS):
        raise ValueError(
            f"{robot.name}: the CRX-5iA has 6 joints, the record names {record.joints}"
        )
    spec = new_arm_spec("crx5ia")  # env_crx5ia_common.xml
    _build_arm(spec, record.joints, record.hand_frame)
    add_arm_servos(spec, record.joints, ACTUATORS, _GAINS)

    flange = spec.body(record.hand_frame)
    flange.add_site(name=record.eef_frame, size=[0.005, 0, 0], group=4)
    gripper_actuator = robotiq_2f85.attach_2f85(
        spec, record.eef_frame, visual_mesh_error=visual_mesh_error, mesh_cache=mesh_cache
    )
    # The J6 housing touches the gripper housing at the faceplate.
    spec.add_exclude(bodyname1=JOINTS[-1][0], bodyname2=robotiq_2f85.BASE_BODY)
    spec.add_exclude(bodyname1=JOINTS[-1][0], bodyname2=robotiq_2f85.MOUNT_BODY)
    return finish_2f85_arm(
        spec,
        record,
        model_name="crx5ia",
        base_body=BASE_BODY,
        arm_actuators=ACTUATORS,
        gripper_actuator=gripper_actuator,
        rmb_stand=RMB_STAND,
    )

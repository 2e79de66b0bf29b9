"""RMB's MuJoCo xArm7: example-robot-data's xArm7 arm + the xArm gripper rebuilt in code.

Sources (RMB = RoboManipBaselines commit 8535948, paths under
``robo_manip_baselines/envs/``):

- arm: example-robot-data ``xarm_description/urdf/xarm7.urdf`` (UFACTORY xarm_ros2,
  BSD-3-Clause). Its link meshes are byte-identical to RMB's ``link_base``, ``link1..7``
  (RMB draws ``end_tool.stl`` on link7 instead of ``link7.stl``); its kinematics, inertials,
  joint ranges, damping (10/10/5/5/5/2/2) and friction loss (1) are RMB's
  ``assets/mujoco/robots/xarm7/xarm7_body.xml`` / ``xarm7_config.xml``'s; the joints' armature
  (:data:`ARMATURE`) is not: RMB's has none, and its wrist cannot move without;
- gripper: :mod:`~rmb_lerobot.envs.mujoco.models.xarm_gripper` (RMB's mechanism and command);
- actuators: ``xarm7_config.xml`` lines 36-47 and 92-98 (classes size1/2/3);
- hand camera: ``xarm7_body.xml`` lines 104-108 (RMB's D435 mount drawn as boxes);
- F/T site: ``xarm7_body.xml`` lines 44-45 (on the gripper base, rotated 90 deg about z);
- mount: ``assets/mujoco/envs/xarm7/env_xarm7_cable.xml`` line 36: ``xarm7_root_frame`` at
  (-0.22, 0, 0.74), on RMB's xArm table whose top is at z 0.74 (line 29: 0.721 + 0.019);
- home: ``mujoco/xarm7/MujocoXarm7CableEnv.py`` line 20 (also PushT's); gripper open (0).

Load-time fixes of the URDF: see :func:`~rmb_lerobot.envs.mujoco.models.common.load_erd_urdf`;
the colliding link meshes get render-only twins so that the visual mesh simplification applies.
"""

from __future__ import annotations

from pathlib import Path

import mujoco

from rmb_lerobot.envs.mujoco.meshes import DEFAULT_VISUAL_MESH_ERROR, simplify_visual_meshes
from rmb_lerobot.envs.mujoco.models import xarm_gripper
from rmb_lerobot.envs.mujoco.models.common import (
    ArmModel,
    RobotModel,
    add_arm_servos,
    add_ft_sensor,
    add_render_twins,
    euler_quat,
    load_erd_urdf,
    mount,
)
from rmb_lerobot.envs.robots import HandCamera, Robot

URDF = "xarm_description/urdf/xarm7.urdf"
BASE_BODY = "link_base"
ACTUATORS = tuple(f"act{i}" for i in range(1, 8))
RMB_TABLE_TOP_Z = 0.74
# xarm7_config.xml lines 36-46: (kp, kv, |force|) of classes size1 (joints 1-2), size2 (3-5),
# size3 (6-7); ctrlrange = the joint range (lines 35, 93-97).
_GAINS = ((1500, 150, 50),) * 2 + ((1000, 100, 30),) * 3 + ((800, 80, 20),) * 2
# kg m^2 per arm joint (the motors' reflected inertia). RMB's xArm7 has none; then the wrist
# servo (kp 800 N m/rad, |force| <= 20, on ~0.0016 kg m^2 of link 7 + gripper) chatters at its
# force limit and does not move, under implicitfast as under discrete (measured: joint 7 moved
# 0.005 rad of a 0.5 rad step in 40 control steps; with 0.1 it is within 1.5 mrad after 20).
# 0.1 is what RMB's UR5e (Menagerie) and Panda joints have.
ARMATURE = 0.1
# xarm7_body.xml line 43: the gripper base is link7 turned by pi about z.
_GRIPPER_MOUNT_QUAT = (0.0, 0.0, 0.0, 1.0)
_WHITE, _GRAY = (1.0, 1.0, 1.0, 1.0), (0.753, 0.753, 0.753, 1.0)  # xarm7_config.xml lines 7-8


def _add_hand_camera(spec: mujoco.MjSpec, camera: HandCamera) -> None:
    """RMB's ``hand_camera_link`` on link7 (xarm7_body.xml lines 104-108). Its D435 + stand
    mesh (RMB's own) is drawn as boxes sized from the collision mesh's extents (measured:
    camera x 0.055..0.080, y -0.0455..0.0455, z 0..0.028; plate z 0..0.003). The visual
    camera box stops below the lens (z 0.0237) so the camera never sees its own housing."""
    body = spec.body("link7").add_body(name="hand_camera_link")
    box = mujoco.mjtGeom.mjGEOM_BOX
    visual = {"contype": 0, "conaffinity": 0, "group": 2, "rgba": list(_GRAY)}
    body.add_geom(type=box, size=[0.0125, 0.0455, 0.0115], pos=[0.0675, 0, 0.0115], **visual)
    body.add_geom(type=box, size=[0.051, 0.0375, 0.0015], pos=[0.013, 0, 0.0015], **visual)
    body.add_geom(type=box, size=[0.0125, 0.0455, 0.014], pos=[0.0675, 0, 0.014], group=3)
    body.add_camera(
        name=camera.name, pos=list(camera.pose.pos), quat=list(camera.pose.quat), fovy=camera.fovy
    )


def build_xarm7(
    robot: Robot,
    *,
    visual_mesh_error: float = DEFAULT_VISUAL_MESH_ERROR,
    mesh_cache: Path | bool | None = True,
) -> RobotModel:
    """xArm7 + xArm gripper + wrist F/T sensor + ``hand`` camera, base at the record's mount.

    RMB stands the arm on its table, 0.22 m behind the table centre (the record's mount:
    :data:`rmb_lerobot.envs.robots.XARM7`); on a table whose top is at ``z``, mount it at
    ``(-0.22, 0, z)``.

    Args:
        robot: The xArm7 record: joints, home, gripper, frames, hand camera and mount.
        visual_mesh_error: Visual mesh simplification bound (m), as
            :func:`~rmb_lerobot.envs.mujoco.robot.build_robot_spec`.
        mesh_cache: Where simplified meshes are cached.

    Returns:
        The model (no stand: RMB puts the arm on its table).

    Raises:
        ValueError: If the record has no wrench frame or hand camera (this model has both).
    """
    (record,) = robot.arms
    if record.wrench_frame is None or record.hand_camera is None:
        raise ValueError(f"{robot.name}: the xArm7 model has a wrist F/T sensor and a hand camera")
    spec, urdf = load_erd_urdf(URDF)
    spec.modelname = "xarm7"
    # Twins first, always: the simplified-mesh cache is keyed by the URDF, not by spec edits.
    add_render_twins(spec, rgba=_WHITE)
    for geom in spec.body("link7").geoms:
        if geom.group == 2:
            geom.rgba = list(_GRAY)  # RMB's end tool is gray
    simplify_visual_meshes(spec, urdf, visual_mesh_error, cache=mesh_cache)
    spec.option.timestep = 0.004  # env_xarm7_common.xml line 3
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.compiler.autolimits = True

    add_arm_servos(spec, record.joints, ACTUATORS, _GAINS)
    for joint in record.joints:
        spec.joint(joint).armature = ARMATURE
    link7 = spec.body(record.hand_frame)
    link7.add_site(name=record.eef_frame, size=[0.005, 0, 0], group=4)  # RMB's IK frame: joint 7's
    xarm_gripper.add_xarm_gripper(
        spec, link7, record.gripper, record.tcp_frame, quat=_GRIPPER_MOUNT_QUAT
    )
    force, torque = add_ft_sensor(
        spec,
        xarm_gripper.ROOT_BODY,
        record.wrench_frame,
        quat=tuple(euler_quat((0.0, 0.0, 1.5708))),
    )
    _add_hand_camera(spec, record.hand_camera)
    mount(spec, BASE_BODY, record.root_frame, record.mount.pos, record.mount.quat)

    arm = ArmModel(
        record=record,
        arm_actuators=ACTUATORS,
        gripper_actuator=xarm_gripper.ACTUATOR,
        base_body=BASE_BODY,
        force_sensor=force,
        torque_sensor=torque,
        hand_camera=record.hand_camera.name,
    )
    camera = record.hand_camera.name
    return RobotModel("xarm7", spec, (arm,), {camera: camera}, stand=None)

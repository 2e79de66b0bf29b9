"""How MuJoCo builds each robot record: one model builder per robot name, checked against it.

A builder takes the robot's record (:class:`~rmb_lerobot.envs.robots.Robot`: joints, gripper,
home, frames, cameras, mount) and returns a
:class:`~rmb_lerobot.envs.mujoco.models.common.RobotModel`: the composed spec and, per arm, the
record with the names only MuJoCo has (actuators, base body, sensors, hand camera). The model
files also carry names (joints, gripper joints, frames) and the gripper's command range:
:func:`check_model` proves that a compiled model has every name the record gives and the
record's gripper range, so the two can never drift apart silently.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from pathlib import Path
from typing import Any

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
from rmb_lerobot.envs.robots import Robot

MESH_OPTIONS = ("visual_mesh_error", "mesh_cache")

# RMB's stand under the single UR5e: 0.66 m square, up to the arm's mount height (0.8 m).
_STAND_HALF_SIZE = (0.33, 0.33, 0.4)


def build_ur5e(
    robot: Robot,
    *,
    visual_mesh_error: float = DEFAULT_VISUAL_MESH_ERROR,
    mesh_cache: Path | bool | None = True,
) -> RobotModel:
    """RMB's UR5e + Robotiq 2F-85 (:data:`~rmb_lerobot.envs.mujoco.robot.UR5E_2F85`).

    Args:
        robot: The single-arm UR5e record (:data:`rmb_lerobot.envs.robots.UR5E` or a copy
            with another mount or home).
        visual_mesh_error: Visual mesh simplification bound (m), as
            :func:`~rmb_lerobot.envs.mujoco.robot.build_robot_spec`.
        mesh_cache: Where simplified meshes are cached.

    Returns:
        The model, standing on RMB's stand under the arm's mount.
    """
    (arm_record,) = robot.arms
    files = UR5E_2F85
    spec = build_robot_spec(
        files, arm_record, visual_mesh_error=visual_mesh_error, mesh_cache=mesh_cache
    )
    camera = arm_record.hand_camera.name if arm_record.hand_camera else None
    arm = ArmModel(
        record=arm_record,
        arm_actuators=files.arm_actuators,
        gripper_actuator=files.gripper_actuator,
        base_body=files.arm_base_body,
        force_sensor=FORCE_SENSOR,
        torque_sensor=TORQUE_SENSOR,
        hand_camera=camera,
    )
    mount_x, mount_y, _ = arm_record.mount.pos
    stand = StandBox(pos=(mount_x, mount_y, 0.4), half_size=_STAND_HALF_SIZE)
    return RobotModel("ur5e", spec, (arm,), {camera: camera} if camera else {}, stand)


def _builder(module: str, function: str, mesh_options: bool = True) -> Callable[..., RobotModel]:
    """A builder that imports its model module when first called (the xArm7 and Panda need
    example-robot-data); ``mesh_options=False``: the model has no mesh options (the Panda's
    coarse collision meshes are drawn as they are)."""

    def build(robot: Robot, **options: Any) -> RobotModel:
        if not mesh_options:
            options = {k: v for k, v in options.items() if k not in MESH_OPTIONS}
        models = importlib.import_module(f"rmb_lerobot.envs.mujoco.models.{module}")
        return getattr(models, function)(robot, **options)

    return build


MUJOCO_BUILDERS: dict[str, Callable[..., RobotModel]] = {
    "ur5e": build_ur5e,
    "ur5e_dual": _builder("dual_ur5e", "build_dual_ur5e"),
    "xarm7": _builder("xarm7", "build_xarm7"),
    "panda": _builder("panda", "build_panda", mesh_options=False),
    "kinova_gen3": _builder("kinova_gen3", "build_kinova_gen3"),
    "crx5ia": _builder("crx5ia", "build_crx5ia"),
    "g1": _builder("g1", "build_g1"),
    "aloha": _builder("aloha", "build_aloha"),
    "hsr": _builder("hsr", "build_hsr", mesh_options=False),
}
"""Robot short name -> its MuJoCo model builder, called with the robot's record and keyword
options (``visual_mesh_error``, ``mesh_cache``). Every builder takes the robot's facts (joints,
gripper, home, mount, frames, cameras) from the record it is given; :func:`check_model` proves
the compiled model has them."""


def _missing(model: mujoco.MjModel, kind: mujoco.mjtObj, names: tuple[str, ...]) -> list[str]:
    return [name for name in names if mujoco.mj_name2id(model, kind, name) < 0]


def _is_frame(model: mujoco.MjModel, name: str) -> bool:
    """A frame of the record is a site or a body of the MuJoCo model."""
    return any(
        mujoco.mj_name2id(model, kind, name) >= 0
        for kind in (mujoco.mjtObj.mjOBJ_SITE, mujoco.mjtObj.mjOBJ_BODY)
    )


def _arm_problems(arm: ArmModel, compiled: mujoco.MjModel) -> list[str]:
    record, obj = arm.record, mujoco.mjtObj
    problems = [
        f"no {what} {name!r}"
        for what, kind, names in (
            ("joint", obj.mjOBJ_JOINT, record.joints + record.gripper.joints),
            ("actuator", obj.mjOBJ_ACTUATOR, (*arm.arm_actuators, arm.gripper_actuator)),
            ("body", obj.mjOBJ_BODY, (arm.base_body,)),
            ("sensor", obj.mjOBJ_SENSOR, (arm.force_sensor, arm.torque_sensor)),
            ("camera", obj.mjOBJ_CAMERA, (arm.hand_camera,) if arm.hand_camera else ()),
        )
        for name in _missing(compiled, kind, names)
    ]
    frames = (record.root_frame, record.eef_frame, record.tcp_frame, record.hand_frame)
    wrench = (record.wrench_frame,) if record.wrench_frame else ()
    problems += [f"no frame {name!r}" for name in frames + wrench if not _is_frame(compiled, name)]
    if not _missing(compiled, obj.mjOBJ_ACTUATOR, (arm.gripper_actuator,)):
        built = tuple(float(v) for v in compiled.actuator(arm.gripper_actuator).ctrlrange)
        if built != tuple(float(v) for v in record.gripper.command_range):
            problems.append(
                f"gripper actuator {arm.gripper_actuator!r} range {built}, record "
                f"{record.gripper.command_range}"
            )
    return problems


def check_model(robot: Robot, model: RobotModel, compiled: mujoco.MjModel) -> None:
    """Check that a built model is the record's: its arms are the record's arms, and the
    compiled scene has every joint, frame, actuator, sensor and camera they name, with the
    record's gripper command range.

    Args:
        robot: The record the model was built from.
        model: What the builder returned.
        compiled: The compiled scene (or robot) model.

    Raises:
        ValueError: Naming every disagreement.
    """
    problems = []
    if len(model.arms) != len(robot.arms):
        problems.append(f"{len(model.arms)} arms, the record has {len(robot.arms)}")
    for i, (arm, record) in enumerate(zip(model.arms, robot.arms, strict=False)):
        if arm.record != record:
            problems.append(f"arm {i} was built from another record ({arm.record.name!r})")
        problems += [f"arm {i}: {problem}" for problem in _arm_problems(arm, compiled)]
    if tuple(model.cameras) != robot.cameras:
        problems.append(f"cameras: model {tuple(model.cameras)}, record {robot.cameras}")
    if problems:
        raise ValueError(
            f"MuJoCo model {model.name!r} disagrees with robot record {robot.name!r}: "
            + "; ".join(problems)
        )


def build_robot_model(robot: Robot, **options: Any) -> RobotModel:
    """The robot's MuJoCo model, built from its record.

    Args:
        robot: The robot record.
        **options: Builder options (``visual_mesh_error``, ``mesh_cache``).

    Returns:
        The model; check it with :func:`check_model` once the scene is compiled.

    Raises:
        ValueError: If MuJoCo has no model for this robot.
    """
    if robot.name not in MUJOCO_BUILDERS:
        raise ValueError(
            f"robot {robot.name!r} has no MuJoCo model; MuJoCo builds: {sorted(MUJOCO_BUILDERS)}"
        )
    return MUJOCO_BUILDERS[robot.name](robot, **options)

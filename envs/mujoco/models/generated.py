"""Arm links drawn from simple shapes, for robots whose model no installable package ships.

A link is a few capsules or cylinders between points of its body frame (joint origins, the
flange), all of one radius. Its mass (the manufacturer's figure where published) is spread
over them by volume, and MuJoCo computes the inertia from the shapes: a uniform-density
approximation of the real link, close in mass and centre of mass, not in the finer inertia
terms. The geoms draw and collide; their contact bits let them touch the world and the
gripper's props but not each other (:data:`ARM_CONTYPE`, :data:`ARM_CONAFFINITY`, as the
Panda's links).
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np

from rmb_lerobot.envs.mujoco.models import robotiq_2f85
from rmb_lerobot.envs.mujoco.models.common import (
    ArmModel,
    RobotModel,
    StandBox,
    add_ft_sensor,
    mount,
)
from rmb_lerobot.envs.robots import Arm

# The links hit anything of contype 1 (the default), never each other.
ARM_CONTYPE, ARM_CONAFFINITY = 2, 1

Point = tuple[float, float, float]


def _volume(kind: mujoco.mjtGeom, radius: float, length: float) -> float:
    body = np.pi * radius**2 * length
    if kind == mujoco.mjtGeom.mjGEOM_CAPSULE:
        return body + 4.0 / 3.0 * np.pi * radius**3
    return body


def add_link_shapes(
    body: mujoco.MjsBody,
    segments: Sequence[tuple[Point, Point]],
    radius: float,
    mass: float,
    rgba: Sequence[float],
    *,
    kind: mujoco.mjtGeom = mujoco.mjtGeom.mjGEOM_CAPSULE,
) -> list[mujoco.MjsGeom]:
    """Add one shape per ``(start, end)`` segment (body frame, m) carrying ``mass`` in all.

    Args:
        body: The link's body.
        segments: Axis end points of each shape; zero-length segments are refused.
        radius: Radius of every shape (m).
        mass: The link's mass (kg), spread over the shapes by volume.
        rgba: Colour.
        kind: ``mjGEOM_CAPSULE`` (rounded ends) or ``mjGEOM_CYLINDER`` (flat ends, for a link
            ending at a flange whose neighbour must not overlap it).

    Returns:
        The geoms added.

    Raises:
        ValueError: A segment of zero length, or a non-positive radius or mass.
    """
    if radius <= 0 or mass <= 0:
        raise ValueError(f"link {body.name!r}: radius {radius} and mass {mass} must be > 0")
    lengths = [float(np.linalg.norm(np.subtract(b, a))) for a, b in segments]
    if not segments or min(lengths) <= 0:
        raise ValueError(f"link {body.name!r}: every segment needs two distinct end points")
    volumes = [_volume(kind, radius, length) for length in lengths]
    total = sum(volumes)
    geoms = []
    for (start, end), volume in zip(segments, volumes, strict=True):
        geom = body.add_geom(
            type=kind,
            fromto=[*start, *end],
            size=[radius, 0.0, 0.0],
            mass=mass * volume / total,
            rgba=list(rgba),
            contype=ARM_CONTYPE,
            conaffinity=ARM_CONAFFINITY,
        )
        geoms.append(geom)
    return geoms


def new_arm_spec(model_name: str) -> mujoco.MjSpec:
    """An empty spec with the settings RMB's generated-arm scenes share: radians, autolimits,
    RMB's 4 ms timestep and the implicit-fast integrator (``env_<robot>_common.xml``)."""
    spec = mujoco.MjSpec()
    spec.modelname = model_name
    spec.compiler.autolimits = True
    spec.compiler.degree = False  # joint ranges in radians (MjSpec's default is degrees)
    spec.option.timestep = 0.004
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    return spec


def finish_2f85_arm(
    spec: mujoco.MjSpec,
    record: Arm,
    *,
    model_name: str,
    base_body: str,
    arm_actuators: tuple[str, ...],
    gripper_actuator: str,
    rmb_stand: StandBox,
) -> RobotModel:
    """The common tail of a generated arm carrying the 2F-85: the wrist F/T sensor on the
    gripper's mount, the arm mounted under the record's root frame, and the model on RMB's
    stand (its x, y under the record's mount).

    Args:
        spec: The spec with the arm, its servos and the attached 2F-85.
        record: The arm's record (frames, mount, hand camera).
        model_name: The robot model's name.
        base_body: The arm's base body, mounted under ``record.root_frame``.
        arm_actuators: The arm's actuator names, in joint order.
        gripper_actuator: The 2F-85's actuator (from :func:`robotiq_2f85.attach_2f85`).
        rmb_stand: RMB's stand box for this robot (its height and size are used).

    Returns:
        The single-arm robot model; the hand camera, if the record has one, is rendered under
        its own name.

    Raises:
        ValueError: If the record has no wrench frame.
    """
    if record.wrench_frame is None:
        raise ValueError(f"{model_name}: the arm {record.name!r} needs a wrench frame")
    force, torque = add_ft_sensor(spec, robotiq_2f85.MOUNT_BODY, record.wrench_frame)
    mount(spec, base_body, record.root_frame, record.mount.pos, record.mount.quat)
    camera = record.hand_camera.name if record.hand_camera else None
    arm = ArmModel(
        record=record,
        arm_actuators=arm_actuators,
        gripper_actuator=gripper_actuator,
        base_body=base_body,
        force_sensor=force,
        torque_sensor=torque,
        hand_camera=camera,
    )
    x, y, _ = record.mount.pos
    stand = StandBox(pos=(x, y, rmb_stand.pos[2]), half_size=rmb_stand.half_size)
    cameras = {camera: camera} if camera else {}
    return RobotModel(model_name, spec, (arm,), cameras, stand=stand)

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

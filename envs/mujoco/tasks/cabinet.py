"""MuJoCo scene of RMB's Cabinet (:mod:`rmb_lerobot.envs.tasks.cabinet`): the static shell, the
sliding door and the hinged lid, shared by both variants."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from rmb_lerobot.envs.mujoco.tasks.base import MujocoTaskScene
from rmb_lerobot.envs.tasks.cabinet import (
    CABINET,
    DOOR_HALF_THICKNESS,
    HANDLE,
    HANDLE_DEPTH,
    HANDLE_HALF_HEIGHT,
    HANDLE_HALF_THICKNESS,
    HANDLE_POS,
    HINGE,
    HINGE_POS,
    LID,
    LID_THICKNESS,
    NOTCH_HALF_WIDTH,
    NOTCH_Z,
    SLIDE,
    SLIDE_DOOR,
    SLIDE_POS,
    SLIDE_RANGE,
    CabinetHingeTask,
    CabinetSlideTask,
    CabinetTask,
)

if TYPE_CHECKING:
    from rmb_lerobot.envs.mujoco.backend import MujocoBackend

_COLOURS = {
    "base": (0.5, 0.5, 0.5, 1.0),
    "lower": (0.9, 0.6, 0.1, 1.0),
    "upper": (0.1, 0.6, 0.8, 1.0),
    "slide": (0.9, 0.3, 0.7, 1.0),
    "handle": (0.6, 0.0, 0.4, 1.0),
    "lid": (0.7, 0.8, 0.1, 1.0),
}


def _box(
    body: mujoco.MjsBody,
    size: Sequence[float],
    pos: Sequence[float],
    colour: str,
    name: str = "",
) -> None:
    body.add_geom(
        name=name,
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=list(size),
        pos=list(pos),
        rgba=list(_COLOURS[colour]),
    )


def build_cabinet(spec: mujoco.MjSpec, pos: np.ndarray) -> mujoco.MjsBody:
    """Add RMB's cabinet at ``pos`` (world): static shell, sliding door, hinged lid."""
    cabinet = spec.worldbody.add_body(name=CABINET, pos=list(pos))
    # Lower compartment: floor, sides, back, fixed front panel behind the sliding door's path.
    _box(cabinet, (0.1, 0.15, 0.005), (0.0, 0.0, 0.005), "base")
    for y in (0.155, -0.155):
        _box(cabinet, (0.1, 0.005, 0.08), (0.0, y, 0.08), "base")
    _box(cabinet, (0.005, 0.15, 0.08), (0.095, 0.0, 0.08), "base")
    _box(cabinet, (0.005, 0.075, 0.075), (-0.085, 0.075, 0.085), "lower")
    # Upper compartment: floor, sides, back, front wall with a notch under the lid's front edge.
    _box(cabinet, (0.095, 0.15, 0.005), (0.0, 0.0, 0.165), "base")
    for y in (0.155, -0.155):
        _box(cabinet, (0.1, 0.005, 0.06), (0.0, y, 0.22), "base")
    _box(cabinet, (0.005, 0.15, 0.06), (0.095, 0.0, 0.22), "base")
    notch_lo, notch_hi = NOTCH_Z
    _box(
        cabinet, (0.005, 0.15, (notch_lo - 0.16) / 2), (-0.095, 0.0, (notch_lo + 0.16) / 2), "upper"
    )
    side_half = (0.15 - NOTCH_HALF_WIDTH) / 2
    for sign in (1.0, -1.0):
        _box(
            cabinet,
            (0.005, side_half, (notch_hi - notch_lo) / 2),
            (-0.095, sign * (NOTCH_HALF_WIDTH + side_half), (notch_lo + notch_hi) / 2),
            "upper",
        )

    door = cabinet.add_body(name=SLIDE_DOOR, pos=list(SLIDE_POS))
    door.add_joint(
        name=SLIDE,
        type=mujoco.mjtJoint.mjJNT_SLIDE,
        axis=[0, 1, 0],
        range=list(SLIDE_RANGE),
        armature=1e-5,
        limited=mujoco.mjtLimited.mjLIMITED_TRUE,
    )
    _box(door, (DOOR_HALF_THICKNESS, 0.075, 0.075), (0.0, -0.075, 0.085), "slide")
    _box(
        door,
        (HANDLE_DEPTH / 2, HANDLE_HALF_THICKNESS, HANDLE_HALF_HEIGHT),
        HANDLE_POS,
        "handle",
        name=HANDLE,
    )

    lid = cabinet.add_body(name=LID, pos=list(HINGE_POS))
    lid.add_joint(
        name=HINGE,
        type=mujoco.mjtJoint.mjJNT_HINGE,
        axis=[0, 1, 0],
        range=[0.0, np.pi],
        armature=1e-5,
        limited=mujoco.mjtLimited.mjLIMITED_TRUE,
    )
    _box(lid, (0.1, 0.16, LID_THICKNESS / 2), (-0.095, 0.0, LID_THICKNESS / 2), "lid")

    # The door and the lid rest exactly on the shell; MuJoCo does not filter contacts between a
    # static body and its children, so without these the joints would rub or jam.
    for moving in (SLIDE_DOOR, LID):
        spec.add_exclude(bodyname1=CABINET, bodyname2=moving)
    return cabinet


class CabinetScene[T: CabinetTask](MujocoTaskScene[T]):
    """The cabinet of both variants, moved by the world's offset, both joints closed at start."""

    def build(self, spec: mujoco.MjSpec, sim: MujocoBackend) -> None:
        build_cabinet(spec, self.task.cabinet_nominal_pos)

    def apply_world(self, sim: MujocoBackend, offset: np.ndarray) -> None:
        sim.model.body(CABINET).pos = self.task.cabinet_nominal_pos + offset

    def reset_objects(self, sim: MujocoBackend) -> None:
        for joint in (HINGE, SLIDE):
            sim.data.joint(joint).qpos[:] = 0.0
            sim.data.joint(joint).qvel[:] = 0.0


class CabinetHingeScene(CabinetScene[CabinetHingeTask]):
    """The cabinet scene of :class:`~rmb_lerobot.envs.tasks.cabinet.CabinetHingeTask`."""


class CabinetSlideScene(CabinetScene[CabinetSlideTask]):
    """The cabinet scene of :class:`~rmb_lerobot.envs.tasks.cabinet.CabinetSlideTask`."""

"""How the PyBullet backend builds a task's props: one scene builder per task, found by name.

A :class:`PybulletTaskScene` is the PyBullet half of a simulator-free
:class:`~rmb_lerobot.envs.tasks.base.Task`: it adds the task's bodies to the backend's client
(:meth:`~rmb_lerobot.envs.pybullet.backend.PybulletBackend.add_body` names them, so success
tests and experts find them by name, and says which ones the fingertip sensors see, as RMB's
``rgb_tactiles.add_body``), places them for a world, and resets them at episode start. Every
hook but :meth:`~PybulletTaskScene.build` is optional. Props are made of PyBullet's primitive
shapes in code (:func:`add_box`): no model file is copied from another repository.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
import pybullet as p

from rmb_lerobot.envs.simulators import scene_builder_for
from rmb_lerobot.envs.tasks.base import Task

if TYPE_CHECKING:
    from rmb_lerobot.envs.pybullet.backend import PybulletBackend


class PybulletTaskScene[T: Task]:
    """The PyBullet construction of one task (``self.task``: its neutral record)."""

    def __init__(self, task: T) -> None:
        self.task = task

    def build(self, sim: PybulletBackend) -> None:
        """Add the task's bodies (with :meth:`PybulletBackend.add_body`)."""
        raise NotImplementedError

    def apply_world(self, sim: PybulletBackend, offset: np.ndarray) -> None:
        """Place the objects for the episode's world (``self.task.world_idx``), shifted by
        ``offset`` (3,); the robot is at home already."""


def add_box(
    client: int,
    half_extents: Sequence[float],
    position: Sequence[float],
    *,
    quat_xyzw: Sequence[float] = (0.0, 0.0, 0.0, 1.0),
    mass: float = 0.0,
    rgba: Sequence[float] = (0.6, 0.6, 0.6, 1.0),
    friction: float | None = None,
) -> int:
    """A box body (``mass`` 0: fixed in the world); returns its body id."""
    return add_compound(
        client,
        [(half_extents, (0.0, 0.0, 0.0))],
        position,
        quat_xyzw=quat_xyzw,
        mass=mass,
        rgba=rgba,
        friction=friction,
    )


def add_compound(
    client: int,
    boxes: Sequence[tuple[Sequence[float], Sequence[float]]],
    position: Sequence[float],
    *,
    quat_xyzw: Sequence[float] = (0.0, 0.0, 0.0, 1.0),
    mass: float = 0.0,
    rgba: Sequence[float] = (0.6, 0.6, 0.6, 1.0),
    friction: float | None = None,
) -> int:
    """One rigid body of several boxes, each ``(half_extents, offset)`` in the body frame (e.g.
    an open container: a floor and four walls); returns its body id."""
    halves = [list(map(float, half)) for half, _ in boxes]
    offsets = [list(map(float, offset)) for _, offset in boxes]
    collision = p.createCollisionShapeArray(
        shapeTypes=[p.GEOM_BOX] * len(boxes),
        halfExtents=halves,
        collisionFramePositions=offsets,
        physicsClientId=client,
    )
    visual = p.createVisualShapeArray(
        shapeTypes=[p.GEOM_BOX] * len(boxes),
        halfExtents=halves,
        visualFramePositions=offsets,
        rgbaColors=[list(rgba)] * len(boxes),
        physicsClientId=client,
    )
    body = p.createMultiBody(
        baseMass=mass,
        baseCollisionShapeIndex=collision,
        baseVisualShapeIndex=visual,
        basePosition=list(map(float, position)),
        baseOrientation=list(map(float, quat_xyzw)),
        physicsClientId=client,
    )
    if friction is not None:
        p.changeDynamics(body, -1, lateralFriction=friction, physicsClientId=client)
    return body


_MODULE = "rmb_lerobot.envs.pybullet.tasks"

PYBULLET_TASK_SCENES: dict[str, str] = {
    "grasp": f"{_MODULE}.grasp:GraspScene",
    "insert": f"{_MODULE}.insert:InsertScene",
    "spoon": f"{_MODULE}.spoon:SpoonScene",
}
"""Task name -> ``"module:Class"`` of its PyBullet scene builder (imported when first used)."""


def pybullet_scene_for(task: Task) -> PybulletTaskScene:
    """The PyBullet scene builder of ``task`` (see ``scene_builder_for``).

    Raises:
        ValueError: PyBullet has no scene for this task (the error names the ones it has).
    """
    return scene_builder_for(PYBULLET_TASK_SCENES, task, "PyBullet")

"""How the MuJoCo backend builds a task's props: one scene builder per task, found by name.

A :class:`MujocoTaskScene` is the MuJoCo half of a simulator-free
:class:`~rmb_lerobot.envs.tasks.base.Task`: it adds the task's bodies to the scene spec, moves
them for a world, and sets their state at episode start. The backend passes itself into each
hook (as dm_control's composer passes ``physics``): ``sim.robot`` (the record),
``sim.robot_model`` (its MuJoCo names), ``sim.workspace``, and ``sim.model`` / ``sim.data``
once compiled. Every hook is optional: a task whose props need no per-world or per-episode
work leaves them out.

:data:`MUJOCO_TASK_SCENES` maps a task name to its builder, the way
:data:`~rmb_lerobot.envs.mujoco.robots.MUJOCO_BUILDERS` maps a robot name to its model: adding
a MuJoCo task adds one row here, never an edit of the backend or the neutral task.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from rmb_lerobot.envs.simulators import scene_builder_for
from rmb_lerobot.envs.tasks.base import Task

if TYPE_CHECKING:
    import mujoco

    from rmb_lerobot.envs.mujoco.backend import MujocoBackend


class MujocoTaskScene[T: Task]:
    """The MuJoCo construction of one task (``self.task``: its neutral record and constants)."""

    def __init__(self, task: T) -> None:
        self.task = task

    def build(self, spec: mujoco.MjSpec, sim: MujocoBackend) -> None:
        """Add the task's bodies, equalities and contact exclusions to the scene spec (the
        model is not compiled yet)."""

    def apply_world(self, sim: MujocoBackend, offset: np.ndarray) -> None:
        """Move the task's objects by ``offset`` (3,) from their nominal placement (in
        ``sim.model``, right after ``mj_resetData``)."""

    def reset_objects(self, sim: MujocoBackend) -> None:
        """Set the objects' state in ``sim.data`` at episode start (the robot is already at
        home, kinematics computed)."""


_MODULE = "rmb_lerobot.envs.mujoco.tasks"

MUJOCO_TASK_SCENES: dict[str, str] = {
    "bottles": f"{_MODULE}.bottles:BottlesScene",
    "cabinet_hinge": f"{_MODULE}.cabinet:CabinetHingeScene",
    "cabinet_slide": f"{_MODULE}.cabinet:CabinetSlideScene",
    "cable": f"{_MODULE}.cable:CableScene",
    "cloth": f"{_MODULE}.cloth:ClothScene",
    "door": f"{_MODULE}.door:DoorScene",
    "handover": f"{_MODULE}.handover:HandoverScene",
    "insert": f"{_MODULE}.insert:InsertScene",
    "particle": f"{_MODULE}.particle:ParticleScene",
    "pick": f"{_MODULE}.pick:PickScene",
    "pusht": f"{_MODULE}.pusht:PushTScene",
    "ring": f"{_MODULE}.ring:RingScene",
    "tidyup": f"{_MODULE}.tidyup:TidyUpScene",
    "toolbox": f"{_MODULE}.toolbox:ToolboxScene",
}
"""Task name -> ``"module:Class"`` of its MuJoCo scene builder (imported when first used)."""


def mujoco_scene_for(task: Task) -> MujocoTaskScene:
    """The MuJoCo scene builder of ``task`` (see ``scene_builder_for``).

    Raises:
        ValueError: MuJoCo has no scene for this task (the error names the ones it has).
    """
    return scene_builder_for(MUJOCO_TASK_SCENES, task, "MuJoCo")

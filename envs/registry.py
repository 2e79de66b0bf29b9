"""The one table of RMB environments, and every name derived from it.

Each entry names a task (``insert``) on a robot (``ur5e``); from that come RMB's environment
name (``MujocoUR5eInsert``), the gymnasium id (``rmb_lerobot/MujocoUR5eInsert-v0``) and the
LeRobot env type (``rmb_ur5e_insert``). Nothing here imports MuJoCo: ``import rmb_lerobot``
registers the gymnasium ids through this table cheaply, and the task classes are imported only
when an env is made.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Any

import gymnasium as gym

GYM_NAMESPACE = "rmb_lerobot"
GYM_VERSION = "v0"
LEROBOT_TYPE_PREFIX = "rmb_"

# Robot short name -> how RMB spells it in environment class names.
ROBOTS = {"ur5e": "UR5e"}


@dataclass(frozen=True)
class EnvEntry:
    """One RMB environment: a task on a robot in a simulator."""

    task: str  # short task name, e.g. "cabinet_hinge"
    task_class: str  # "module:Class" of the Task
    expert_class: str  # "module:Class" of its scripted expert
    robot: str = "ur5e"
    simulator: str = "Mujoco"

    @property
    def rmb_env_name(self) -> str:
        """RMB's environment class name without the ``Env`` suffix."""
        camel = "".join(part.capitalize() for part in self.task.split("_"))
        return f"{self.simulator}{ROBOTS[self.robot]}{camel}"

    @property
    def gym_id(self) -> str:
        return f"{GYM_NAMESPACE}/{self.rmb_env_name}-{GYM_VERSION}"

    @property
    def lerobot_type(self) -> str:
        return f"{LEROBOT_TYPE_PREFIX}{self.robot}_{self.task}"

    def load_task_class(self) -> type:
        return _load(self.task_class)

    def load_expert_class(self) -> type:
        return _load(self.expert_class)


def _load(target: str) -> Any:
    module, _, name = target.partition(":")
    return getattr(importlib.import_module(module), name)


def _entry(task: str, task_class: str, expert_class: str) -> EnvEntry:
    tasks, experts = "rmb_lerobot.envs.tasks", "rmb_lerobot.envs.experts"
    module = task.split("_")[0]  # cabinet_hinge and cabinet_slide share a module
    return EnvEntry(task, f"{tasks}.{module}:{task_class}", f"{experts}.{module}:{expert_class}")


ENVS: dict[str, EnvEntry] = {
    entry.task: entry
    for entry in (
        _entry("cabinet_hinge", "CabinetHingeTask", "CabinetHingeExpert"),
        _entry("cabinet_slide", "CabinetSlideTask", "CabinetSlideExpert"),
        _entry("cable", "CableTask", "CableExpert"),
        _entry("cloth", "ClothTask", "ClothExpert"),
        _entry("door", "DoorTask", "DoorExpert"),
        _entry("insert", "InsertTask", "InsertExpert"),
        _entry("particle", "ParticleTask", "ParticleExpert"),
        _entry("pick", "PickTask", "PickExpert"),
        _entry("ring", "RingTask", "RingExpert"),
        _entry("toolbox", "ToolboxTask", "ToolboxExpert"),
    )
}
"""Every environment by short task name: the source of truth for all env names."""


def entry_for(name: str) -> EnvEntry:
    """Look an env up by short task name, RMB env name, gymnasium id or LeRobot type."""
    for entry in ENVS.values():
        if name in (entry.task, entry.rmb_env_name, entry.gym_id, entry.lerobot_type):
            return entry
    known = ", ".join(sorted(e.rmb_env_name for e in ENVS.values()))
    raise ValueError(f"unknown RMB environment {name!r}; known: {known}")


def make_env(task: str, max_episode_steps: int | None = None, **kwargs: Any) -> gym.Env:
    """gymnasium entry point: the task's :class:`RmbEnv` inside a ``TimeLimit``.

    The time limit comes from the task (``Task.max_episode_steps``) unless given, so the table
    need not import the task to register it.
    """
    from rmb_lerobot.envs.base import RmbEnv

    entry = entry_for(task)
    env = RmbEnv(entry.load_task_class()(), **kwargs)
    limit = max_episode_steps if max_episode_steps is not None else env.task.max_episode_steps
    return gym.wrappers.TimeLimit(env, max_episode_steps=limit)


def register_gym_envs() -> list[str]:
    """Register every table entry with gymnasium (idempotent); returns the ids."""
    ids = []
    for entry in ENVS.values():
        if entry.gym_id not in gym.registry:
            gym.register(
                id=entry.gym_id,
                entry_point=f"{__name__}:make_env",
                kwargs={"task": entry.task},
                disable_env_checker=True,
            )
        ids.append(entry.gym_id)
    return ids

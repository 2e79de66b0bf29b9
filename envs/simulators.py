"""The simulators (and real hardware) an env can run on: one record each.

A :class:`Simulator` names its backend class and that backend's typed options dataclass by
``"module:Class"`` (imported only when an env is made, so ``import rmb_lerobot`` stays free of
every simulator), RMB's spelling in environment names (``MujocoUR5eInsert``,
``TactoSawyerGrasp``), its part in LeRobot type names and its nominal control period, from
which the frame rate of env types and datasets follows. The registry
(:mod:`rmb_lerobot.envs.registry`) composes envs from these records; the env core never
chooses a backend.
"""

from __future__ import annotations

import importlib
import importlib.util
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from rmb_lerobot.envs.backend import Backend
    from rmb_lerobot.envs.robots import Robot
    from rmb_lerobot.envs.tasks.base import Task


def load_target(target: str) -> Any:
    """The object a ``"module:name"`` string names (imports the module)."""
    module, _, name = target.partition(":")
    return getattr(importlib.import_module(module), name)


def frames_per_second(control_dt: float) -> int:
    """RMB's integer frame rate of a control period: ``int(1 / dt)`` (31 for MuJoCo's 0.032 s,
    33 for PyBullet's 0.03 s), robust to the period's float error (0.02 s gives 50, not 49)."""
    return int(round(1.0 / control_dt, 6))


@dataclass(frozen=True)
class Simulator:
    """A simulator: its RMB spelling, its part in LeRobot type names, and its backend."""

    name: str
    rmb_name: str  # RMB's prefix of environment names, e.g. "Mujoco"
    type_prefix: str  # inserted after "rmb_" in LeRobot types ("" for MuJoCo, RMB's default)
    backend: str  # "module:Class" of its Backend
    options: str  # "module:Class" of the backend's options dataclass
    control_dt: float  # seconds per env step with default options
    requires: str | None = None  # the module the backend needs, and the extra that installs it
    extra: str | None = None

    @property
    def fps(self) -> int:
        """Frames per second of env types and recorded datasets (:func:`frames_per_second`)."""
        return frames_per_second(self.control_dt)

    def backend_class(self) -> type[Backend]:
        """The backend class (imports the simulator).

        Raises:
            ImportError: the simulator is not installed (the message names the extra).
        """
        if self.requires is not None and importlib.util.find_spec(self.requires) is None:
            raise ImportError(
                f"{self.rmb_name} envs need {self.requires!r}, which is not installed: "
                f"pip install 'lerobot_env_rmb[{self.extra}]'"
            )
        return load_target(self.backend)

    def options_class(self) -> type:
        return load_target(self.options)

    def split_options(self, kwargs: dict[str, Any]) -> tuple[Any, dict[str, Any]]:
        """``kwargs`` split into this backend's options (an instance of :attr:`options`) and the
        rest (for the env core)."""
        options_class = self.options_class()
        names = {f.name for f in fields(options_class)}
        options = options_class(**{k: v for k, v in kwargs.items() if k in names})
        return options, {k: v for k, v in kwargs.items() if k not in names}


SIMULATORS: dict[str, Simulator] = {
    sim.name: sim
    for sim in (
        Simulator(
            "mujoco",
            "Mujoco",
            "",
            "rmb_lerobot.envs.mujoco.backend:MujocoBackend",
            "rmb_lerobot.envs.mujoco.options:MujocoOptions",
            0.004 * 8,  # RMB: timestep 0.004 s, frame_skip 8
        ),
        Simulator(
            "pybullet",
            "Tacto",  # RMB's TACTO envs: TactoSawyerGraspEnv, ...
            "pybullet_",
            "rmb_lerobot.envs.pybullet.backend:PybulletBackend",
            "rmb_lerobot.envs.pybullet.options:PybulletOptions",
            0.005 * 6,  # RMB: timestep 0.005 s, 6 substeps
            requires="pybullet",
            extra="pybullet",
        ),
        Simulator(
            "real",
            "Real",  # RMB's real envs: RealUR5eDemoEnv, RealXarm7DemoEnv, ...
            "real_",
            "rmb_lerobot.envs.real.backend:RealBackend",
            "rmb_lerobot.envs.real.options:RealOptions",
            0.02,  # RMB's RealEnvBase.dt: 50 Hz
        ),
    )
}
"""Simulator name -> its record."""


def simulator_for(name: str) -> Simulator:
    """The record of simulator ``name``; the error names the known ones."""
    try:
        return SIMULATORS[name]
    except KeyError:
        raise ValueError(f"unknown simulator {name!r}; known: {sorted(SIMULATORS)}") from None


def scene_builder_for(table: Mapping[str, str], task: Task, simulator: str) -> Any:
    """A task's scene builder from a simulator's table (task name -> ``"module:Class"``),
    made with the task.

    Raises:
        ValueError: the table has no scene for this task (the error names the ones it has).
    """
    target = table.get(task.name)
    if target is None:
        raise ValueError(
            f"task {task.name!r} has no {simulator} scene; {simulator} builds: "
            f"{', '.join(sorted(table))}"
        )
    return load_target(target)(task)


def _camel(name: str) -> str:
    return "".join(part.capitalize() for part in name.split("_"))


def rmb_env_name(simulator: str, robot: Robot, task: str) -> str:
    """RMB's environment class name without ``Env``: ``MujocoUR5eInsert``."""
    return f"{simulator_for(simulator).rmb_name}{robot.rmb_name}{_camel(task)}"

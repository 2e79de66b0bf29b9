"""The one table of environments, and every name derived from it.

Each entry is a task (``insert``) on a robot (``ur5e``) in a simulator (``mujoco``). From the
robot record (:mod:`rmb_lerobot.envs.robots`), the simulator and the task name come RMB's
environment name (``MujocoUR5eInsert``), the ``env`` attribute RMB writes into episodes
(``MujocoUR5eInsertEnv``), the gymnasium id (``rmb_lerobot/MujocoUR5eInsert-v0``), the LeRobot
env type (``rmb_ur5e_insert``), the ``robot_type`` of converted datasets (``ur5e``) and the
camera names. Nothing here imports a simulator: ``import rmb_lerobot`` registers the gymnasium
ids through this table cheaply, and the task classes are imported only when an env is made.

Short task names (``insert``) name the task on RMB's UR5e in MuJoCo, as they always have; other
robots' entries are named ``<robot>_<task>`` (``xarm7_cable``).
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass, field, fields
from typing import TYPE_CHECKING, Any

import gymnasium as gym

from rmb_lerobot.envs.robots import ROBOTS, Robot, robot_for
from rmb_lerobot.envs.simulators import SIMULATORS, load_target, rmb_env_name, simulator_for
from rmb_lerobot.envs.workspace import (
    ALOHA_TABLE,
    DUAL_TABLE,
    G1_TABLE,
    HSR_FLOOR,
    RMB_TABLE,
    TACTO_FLOOR,
    TACTO_SPOON_FLOOR,
    XARM_TABLE,
    Workspace,
)

if TYPE_CHECKING:
    from rmb_lerobot.envs.base import RmbEnv
    from rmb_lerobot.envs.tasks.base import Task

GYM_NAMESPACE = "rmb_lerobot"
GYM_VERSION = "v0"
LEROBOT_TYPE_PREFIX = "rmb_"
DEFAULT_ROBOT = "ur5e"  # the robot a bare task name means (RMB's own default)


@dataclass(frozen=True)
class EnvEntry:
    """One environment: a task on a robot in a simulator, in a workspace."""

    simulator: str  # key of SIMULATORS, e.g. "mujoco"
    robot: str  # key of rmb_lerobot.envs.robots.ROBOTS, e.g. "ur5e"
    task: str  # short task name, e.g. "cabinet_hinge"
    task_class: str  # "module:Class" of the Task
    expert_class: str  # "module:Class" of its scripted expert
    workspace: Workspace = field(default=RMB_TABLE)

    def __post_init__(self) -> None:
        if self.simulator not in SIMULATORS:
            raise ValueError(f"unknown simulator {self.simulator!r}; known: {sorted(SIMULATORS)}")
        if self.robot not in ROBOTS:
            raise ValueError(f"unknown robot {self.robot!r}; known: {sorted(ROBOTS)}")

    @property
    def robot_record(self) -> Robot:
        return ROBOTS[self.robot]

    @property
    def name(self) -> str:
        """The short name: the task for RMB's UR5e in MuJoCo, else ``[simulator_]robot_task``."""
        if self.simulator == "mujoco" and self.robot == DEFAULT_ROBOT:
            return self.task
        return self.lerobot_type.removeprefix(LEROBOT_TYPE_PREFIX)

    @property
    def rmb_env_name(self) -> str:
        """RMB's environment class name without the ``Env`` suffix, e.g. ``MujocoUR5eInsert``."""
        return rmb_env_name(self.simulator, self.robot_record, self.task)

    @property
    def env_attr(self) -> str:
        """The ``env`` attribute of recorded episodes (RMB's gymnasium spec name)."""
        return f"{self.rmb_env_name}Env"

    @property
    def gym_id(self) -> str:
        return f"{GYM_NAMESPACE}/{self.rmb_env_name}-{GYM_VERSION}"

    @property
    def lerobot_type(self) -> str:
        sim = SIMULATORS[self.simulator]
        return f"{LEROBOT_TYPE_PREFIX}{sim.type_prefix}{self.robot}_{self.task}"

    @property
    def robot_type(self) -> str:
        """LeRobot's ``robot_type`` of datasets recorded in this env."""
        return self.robot

    @property
    def num_worlds(self) -> int:
        """How many worlds (``world_idx`` values) the task has here (imports the neutral
        task module, which imports no simulator)."""
        return self.load_task_class()(self.workspace).num_worlds

    @property
    def fps(self) -> int:
        """Frames per second of this env's LeRobot type and converted datasets: its simulator's
        control period (31 for MuJoCo, 33 for PyBullet)."""
        return SIMULATORS[self.simulator].fps

    @property
    def cameras(self) -> tuple[str, ...]:
        """Every camera of the env: the workspace's fixed ones, then the robot's, then its
        fingertip tactile image sensors (RMB's ``rgb_tactile_names``, recorded as cameras)."""
        robot = self.robot_record
        return (*self.workspace.camera_names, *robot.cameras, *robot.tactile_sensors)

    def make(self, **kwargs: Any) -> RmbEnv:
        """This entry's env core, without time limit (keyword arguments: :func:`compose`'s)."""
        task = self.load_task_class()(self.workspace)
        return compose(task, self.robot_record, self.simulator, **kwargs)

    def load_task_class(self) -> type:
        return load_target(self.task_class)

    def load_expert_class(self) -> type:
        return load_target(self.expert_class)


_POSITIONAL = ("self", "task", "backend")


def compose(
    task: Task, robot: Robot | str = DEFAULT_ROBOT, simulator: str = "mujoco", **kwargs: Any
) -> RmbEnv:
    """An env core: ``task`` on ``robot`` in ``simulator``'s backend.

    Args:
        task: The task, placed in its workspace.
        robot: The robot record or its short name.
        simulator: Key of :data:`~rmb_lerobot.envs.simulators.SIMULATORS`; its record names
            the backend class and that backend's options dataclass.
        **kwargs: The backend's options (fields of its options dataclass, e.g. MuJoCo's
            ``image_size``, ``frame_skip``, ``tactile``) and the env core's
            (:class:`~rmb_lerobot.envs.base.RmbEnv`: ``action_mode``, ``cameras``, ...).

    Returns:
        The :class:`~rmb_lerobot.envs.base.RmbEnv`.

    Raises:
        ValueError: an unknown simulator or robot, or a bad option.
        TypeError: a keyword neither the backend nor the env core takes.
    """
    from rmb_lerobot.envs.base import RmbEnv

    sim = simulator_for(simulator)
    robot = robot_for(robot) if isinstance(robot, str) else robot
    options, env_kwargs = sim.split_options(kwargs)
    accepted = [n for n in inspect.signature(RmbEnv.__init__).parameters if n not in _POSITIONAL]
    unknown = sorted(set(env_kwargs) - set(accepted))
    if unknown:
        backend_options = [f.name for f in fields(sim.options_class())]
        raise TypeError(
            f"{simulator} envs take no option {', '.join(unknown)}; backend options: "
            f"{', '.join(backend_options)}; env options: {', '.join(accepted)}"
        )
    backend = sim.backend_class()(task, robot, task.workspace, options)
    try:
        return RmbEnv(task, backend, **env_kwargs)
    except BaseException:
        backend.close()
        raise


def _entry(
    task: str,
    task_class: str,
    expert_class: str,
    robot: str = DEFAULT_ROBOT,
    workspace: Workspace = RMB_TABLE,
    expert_module: str | None = None,
) -> EnvEntry:
    """A MuJoCo entry whose task and expert live in ``tasks/<module>.py``/``experts/<module>.py``
    (the task name up to its first ``_``: cabinet_hinge and cabinet_slide share a module), or
    the expert in ``experts/<expert_module>.py``."""
    tasks, experts = "rmb_lerobot.envs.tasks", "rmb_lerobot.envs.experts"
    module = task.split("_")[0]
    return EnvEntry(
        "mujoco",
        robot,
        task,
        f"{tasks}.{module}:{task_class}",
        f"{experts}.{expert_module or module}:{expert_class}",
        workspace,
    )


def _tacto_entry(task: str, task_class: str, expert_class: str, workspace: Workspace) -> EnvEntry:
    """A PyBullet entry of RMB's TACTO Sawyer tasks: task ``tasks/tacto_<task>.py``, expert
    ``experts/tacto_<task>.py``."""
    return EnvEntry(
        "pybullet",
        "sawyer",
        task,
        f"rmb_lerobot.envs.tasks.tacto_{task}:{task_class}",
        f"rmb_lerobot.envs.experts.tacto_{task}:{expert_class}",
        workspace,
    )


ENVS: dict[str, EnvEntry] = {
    entry.name: entry
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
        # RMB's other MuJoCo robots: the xArm7 on its own table, the Panda on the UR5e's table,
        # two UR5e arms on one stand.
        _entry("cable", "CableTask", "CableExpert", robot="xarm7", workspace=XARM_TABLE),
        _entry("ring", "RingTask", "RingExpert", robot="xarm7", workspace=XARM_TABLE),
        _entry("pusht", "PushTTask", "PushTExpert", robot="xarm7", workspace=XARM_TABLE),
        _entry("cable", "CableTask", "CableExpert", robot="panda"),
        # Arms generated from their makers' kinematics (no package ships them), on the Panda's
        # stand by the UR5e's table, as RMB places them.
        _entry("cable", "CableTask", "CableExpert", robot="kinova_gen3"),
        _entry("cable", "CableTask", "CableExpert", robot="crx5ia"),
        _entry("bottles", "BottlesTask", "BottlesExpert", robot="g1", workspace=G1_TABLE),
        _entry("handover", "HandoverTask", "HandoverExpert", robot="aloha", workspace=ALOHA_TABLE),
        _entry(
            "cable",
            "CableTask",
            "AlohaCableExpert",
            robot="aloha",
            workspace=ALOHA_TABLE,
            expert_module="aloha_cable",
        ),
        # The mobile HSR on the floor (generated from Toyota's published kinematics).
        _entry("tidyup", "TidyUpTask", "TidyUpExpert", robot="hsr", workspace=HSR_FLOOR),
        _entry(
            "cable",
            "CableTask",
            "DualCableExpert",
            robot="ur5e_dual",
            workspace=DUAL_TABLE,
            expert_module="dual_cable",
        ),
        # RMB's PyBullet TACTO envs: the Sawyer with DIGIT fingertip sensors.
        _tacto_entry("grasp", "TactoGraspTask", "TactoGraspExpert", TACTO_FLOOR),
        _tacto_entry("insert", "TactoInsertTask", "TactoInsertExpert", TACTO_FLOOR),
        _tacto_entry("spoon", "TactoSpoonTask", "TactoSpoonExpert", TACTO_SPOON_FLOOR),
    )
}
"""Every simulated environment by short name (:attr:`EnvEntry.name`): the source of truth for
names. Each has a scripted expert and a success test (the env contract tests run them all)."""

_REAL_DEMO = "rmb_lerobot.envs.real.task:RealDemoTask"
_NO_EXPERT = "rmb_lerobot.envs.real.task:NoExpert"

REAL_ENVS: dict[str, EnvEntry] = {
    entry.name: entry
    for entry in (
        EnvEntry("real", robot, "demo", _REAL_DEMO, _NO_EXPERT)
        for robot in ("ur5e", "xarm7", "ur5e_dual")
    )
}
"""RMB's real envs (``RealUR5eDemo``, ``RealXarm7Demo``, ``RealUR5eDualDemo``) by short name
(``real_ur5e_demo``): a real robot (or its twins, ``driver: sim``) with the neutral demo task,
no expert and no success test; kept apart from :data:`ENVS` so that nothing iterating the
simulated envs starts a robot."""


def _all_entries() -> list[EnvEntry]:
    return [*ENVS.values(), *REAL_ENVS.values()]


def entry_for(name: str) -> EnvEntry:
    """Look an env up by short name, RMB env name (with or without ``Env``), gymnasium id or
    LeRobot type."""
    for entry in _all_entries():
        if name in (entry.name, entry.rmb_env_name, entry.env_attr, entry.gym_id):
            return entry
        if name == entry.lerobot_type:
            return entry
    known = ", ".join(sorted(e.rmb_env_name for e in _all_entries()))
    raise ValueError(f"unknown RMB environment {name!r}; known: {known}")


def entry_for_env_attr(env: object) -> EnvEntry | None:
    """The entry whose episodes carry this ``env`` attribute, matched exactly; else None."""
    if not isinstance(env, str):
        return None
    return next((e for e in ENVS.values() if e.env_attr == env), None)


def robot_for_env_attr(env: object) -> Robot | None:
    """The robot of an episode's ``env`` attribute, matched exactly: our envs' attributes
    (:attr:`EnvEntry.env_attr`) and the original RMB's (:attr:`Robot.rmb_envs`); else None.

    Never by substring: ``MujocoUR5eDualCableEnv`` is a dual-arm robot, not a UR5e.
    """
    if not isinstance(env, str):
        return None
    entry = entry_for_env_attr(env)
    if entry is not None:
        return entry.robot_record
    return next((r for r in ROBOTS.values() if env in r.rmb_envs), None)


def make_env(task: str, max_episode_steps: int | None = None, **kwargs: Any) -> gym.Env:
    """gymnasium entry point: the entry's :class:`RmbEnv` inside a ``TimeLimit``.

    The time limit comes from the task (``Task.max_episode_steps``) unless given, so the table
    need not import the task to register it.
    """
    env = entry_for(task).make(**kwargs)
    limit = max_episode_steps if max_episode_steps is not None else env.task.max_episode_steps
    return gym.wrappers.TimeLimit(env, max_episode_steps=limit)


def register_gym_envs() -> list[str]:
    """Register every table entry (simulated and real) with gymnasium (idempotent); returns
    the ids."""
    ids = []
    for entry in _all_entries():
        if entry.gym_id not in gym.registry:
            gym.register(
                id=entry.gym_id,
                entry_point=f"{__name__}:make_env",
                kwargs={"task": entry.name},
                disable_env_checker=True,
            )
        ids.append(entry.gym_id)
    return ids

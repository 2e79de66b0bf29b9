"""Robots as data: one simulator-neutral record per robot, one module per robot.

The record types (:class:`Robot`, :class:`Arm`, :class:`Gripper`, ...) live in
:mod:`rmb_lerobot.envs.robots.common`; each robot's record lives in its own module
(``envs/robots/<robot>.py``, mirroring its MuJoCo builder ``envs/mujoco/models/<robot>.py``).
This package re-exports them all, so ``from rmb_lerobot.envs.robots import UR5E`` works, and
keeps :data:`ROBOTS`, the registry of every record by short name. A new robot is one new module
with its record plus one entry in ``_RECORDS`` below.
"""

from __future__ import annotations

from rmb_lerobot.envs.robots.aloha import ALOHA
from rmb_lerobot.envs.robots.common import (
    Arm,
    BodyCamera,
    Gripper,
    GripperKind,
    HandCamera,
    MobileBase,
    Pose,
    Robot,
    mounted,
)
from rmb_lerobot.envs.robots.crx5ia import CRX5IA
from rmb_lerobot.envs.robots.dual_ur5e import UR5E_DUAL
from rmb_lerobot.envs.robots.g1 import G1
from rmb_lerobot.envs.robots.hsr import HSR
from rmb_lerobot.envs.robots.kinova_gen3 import KINOVA_GEN3
from rmb_lerobot.envs.robots.panda import PANDA
from rmb_lerobot.envs.robots.sawyer import SAWYER
from rmb_lerobot.envs.robots.ur5e import UR5E
from rmb_lerobot.envs.robots.xarm7 import XARM7

__all__ = [
    "ALOHA",
    "CRX5IA",
    "G1",
    "HSR",
    "KINOVA_GEN3",
    "PANDA",
    "ROBOTS",
    "SAWYER",
    "UR5E",
    "UR5E_DUAL",
    "XARM7",
    "Arm",
    "BodyCamera",
    "Gripper",
    "GripperKind",
    "HandCamera",
    "MobileBase",
    "Pose",
    "Robot",
    "mounted",
    "robot_for",
]

_RECORDS: tuple[Robot, ...] = (
    UR5E,
    UR5E_DUAL,
    XARM7,
    PANDA,
    SAWYER,
    KINOVA_GEN3,
    CRX5IA,
    G1,
    HSR,
    ALOHA,
)

ROBOTS: dict[str, Robot] = {robot.name: robot for robot in _RECORDS}
"""Every robot by short name."""


def robot_for(name: str) -> Robot:
    """A robot record by short name; the error lists the known ones."""
    try:
        return ROBOTS[name]
    except KeyError:
        raise ValueError(f"unknown robot {name!r}; known: {', '.join(sorted(ROBOTS))}") from None

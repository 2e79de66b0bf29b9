"""The LeRobot keys of the real-arm plugins, from the robot records.

Per arm, in RMB's joint-vector order: ``<joint>.pos`` for each arm joint, then
``gripper.pos`` (the gripper in its command units, 0 open .. 255 closed); the dual UR5e
prefixes one arm's keys ``left_`` and the other's ``right_``, as LeRobot's bimanual robots do.
Observation and action use the same names, and no other key ends in ``.pos`` / ``.vel``:
``lerobot-rollout`` feeds a policy only those keys (and cameras) and returns the arm to the
``.pos`` values it started at.

With ``action_space: ee_velocity`` the action is instead, per arm, the end-effector twist
``ee_x.vel`` .. ``ee_yaw.vel`` (m/s, rad/s in the arm's base frame) and ``gripper.pos``
(:mod:`.ee_action`); they end in ``.vel`` as LeKiwi's base velocities do, so
``lerobot-rollout`` keeps them. The observation is the same in both action spaces.
"""

from __future__ import annotations

import numpy as np

from rmb_lerobot import lerobot_names as N
from rmb_lerobot.envs.real.lerobot_devices.config import (
    ACTION_SPACES,
    EE_VELOCITY_ACTIONS,
    JOINT_ACTIONS,
    ROBOT_TYPES,
)
from rmb_lerobot.envs.robots import UR5E, Robot, robot_for

GRIPPER_KEY = N.GRIPPER_POS_NAME
EE_VELOCITY_KEYS = N.EE_VELOCITY_NAMES
"""The twist keys of an ``ee_velocity`` action: linear (m/s), then angular (rad/s)."""
DUAL_SIDES = ("left", "right")


def single_arm_record(robot_type: str) -> Robot:
    """The single-arm record an arm of ``robot_type`` is driven as.

    Args:
        robot_type: ``rmb_ur5e``, ``rmb_xarm7`` or ``rmb_ur5e_dual`` (each of its arms is a
            UR5e).

    Returns:
        The robot record.

    Raises:
        ValueError: Unknown robot type.
    """
    if robot_type not in ROBOT_TYPES:
        raise ValueError(f"unknown robot type {robot_type!r}; known: {sorted(ROBOT_TYPES)}")
    return UR5E if robot_type == "rmb_ur5e_dual" else robot_for(ROBOT_TYPES[robot_type])


def arm_keys(record: Robot) -> tuple[str, ...]:
    """The keys of one single-arm record: ``<joint>.pos`` per arm joint, then the gripper.

    Args:
        record: A single-arm robot record.

    Returns:
        The keys, in joint-vector order.
    """
    (arm,) = record.arms
    return (*(f"{joint}.pos" for joint in arm.joints), GRIPPER_KEY)


def arm_action_keys(record: Robot, action_space: str = JOINT_ACTIONS) -> tuple[str, ...]:
    """The action keys of one single-arm record in an action space.

    Args:
        record: A single-arm robot record.
        action_space: ``joint`` or ``ee_velocity``.

    Returns:
        ``joint``: :func:`arm_keys`; ``ee_velocity``: the twist keys, then ``gripper.pos``.

    Raises:
        ValueError: Unknown action space.
    """
    if action_space not in ACTION_SPACES:
        raise ValueError(f"action_space must be one of {ACTION_SPACES}, got {action_space!r}")
    if action_space == EE_VELOCITY_ACTIONS:
        return (*EE_VELOCITY_KEYS, GRIPPER_KEY)
    return arm_keys(record)


def action_keys(robot_type: str, action_space: str = JOINT_ACTIONS) -> tuple[str, ...]:
    """Every action key of a robot type, in joint-vector order.

    Args:
        robot_type: ``rmb_ur5e``, ``rmb_xarm7`` or ``rmb_ur5e_dual``.
        action_space: ``joint`` or ``ee_velocity`` (every arm alike).

    Returns:
        The keys (with ``joint``, the observation's joint keys are the same).
    """
    keys = arm_action_keys(single_arm_record(robot_type), action_space)
    if robot_type == "rmb_ur5e_dual":
        return tuple(f"{side}_{key}" for side in DUAL_SIDES for key in keys)
    return keys


def home_vector(robot_type: str) -> np.ndarray:
    """The joint vector a fresh twin of ``robot_type`` stands at (per arm: joints, gripper).

    Args:
        robot_type: ``rmb_ur5e``, ``rmb_xarm7`` or ``rmb_ur5e_dual``.

    Returns:
        The single-arm record's home command, once per arm.
    """
    home = single_arm_record(robot_type).home_command()
    return np.tile(home, 2) if robot_type == "rmb_ur5e_dual" else home

"""Action modes: sizes, bounds and commands, for one arm and for two (no simulator needed)."""

import dataclasses

import numpy as np
import pytest

from rmb_lerobot.envs.actions import ACTION_MODES, CommandState, make_action_mode
from rmb_lerobot.envs.robots import UR5E, Robot
from rmb_lerobot.pose import apply_relative_pose

DUAL = Robot(
    "ur5e_dual",
    "UR5eDual",
    tuple(
        dataclasses.replace(UR5E.arms[0], name=side, hand_camera=None) for side in ("left", "right")
    ),
)
LIMITS_6 = (np.full(6, -np.pi), np.array([np.pi] * 5 + [np.inf]))  # last joint unlimited


def _ik_log():
    calls = []

    def ik(arm, target, q_init):
        calls.append((arm, target.copy(), q_init.copy()))
        return np.full(6, 0.1 * (arm + 1))

    return ik, calls


@pytest.mark.parametrize(("robot", "sizes"), [(UR5E, (7, 10, 7)), (DUAL, (14, 20, 14))])
def test_sizes_follow_the_robot(robot, sizes):
    limits = [LIMITS_6] * len(robot.arms)
    assert tuple(make_action_mode(m, robot, limits).size for m in ACTION_MODES) == sizes


def test_joint_mode_clips_to_the_limits_and_the_gripper_range():
    mode = make_action_mode("joint", DUAL, [LIMITS_6, LIMITS_6])
    assert mode.space.high[5] == pytest.approx(2 * np.pi)  # unlimited joint: +-2 pi
    assert mode.space.high[6] == 255.0 and mode.space.low[13] == 0.0
    action = np.array([9.0] * 6 + [300.0] + [-9.0] * 6 + [-5.0])
    command = mode.to_command(action, CommandState(np.zeros(14), (), None))
    assert command[:6] == pytest.approx([np.pi] * 5 + [2 * np.pi])  # the space's bounds
    assert command[6] == 255.0 and command[13] == 0.0
    assert command[7:12] == pytest.approx([-np.pi] * 5)


def test_eef_modes_solve_each_arm_from_its_own_pose():
    """Poses for all arms first, then one gripper per arm (RMB's key order)."""
    ik, calls = _ik_log()
    mode = make_action_mode("eef_rel", DUAL, [LIMITS_6, LIMITS_6])
    current = np.arange(14.0)
    poses = (np.array([0.1, 0, 0.5, 1, 0, 0, 0]), np.array([0.2, 0, 0.5, 1, 0, 0, 0]))
    action = np.array([0.01, 0, 0, 0, 0, 0, 0, 0.02, 0, 0, 0, 0, 100.0, 200.0])
    command = mode.to_command(action, CommandState(current, poses, ik))
    assert [arm for arm, _, _ in calls] == [0, 1]
    assert calls[0][1] == pytest.approx(apply_relative_pose(poses[0], action[:6]))
    assert calls[1][1] == pytest.approx(apply_relative_pose(poses[1], action[6:12]))
    assert calls[1][2] == pytest.approx(current[7:13])  # arm 1 starts from its own joints
    assert command.tolist() == [0.1] * 6 + [100.0] + [0.2] * 6 + [200.0]


def test_bad_actions_are_refused_with_the_reason():
    mode = make_action_mode("eef_abs", UR5E, [LIMITS_6])
    state = CommandState(np.zeros(7), (np.array([0, 0, 0, 1.0, 0, 0, 0]),), None)
    with pytest.raises(ValueError, match=r"'eef_abs' action must have shape \(10,\), got \(7,\)"):
        mode.to_command(np.zeros(7), state)
    with pytest.raises(ValueError, match="non-finite"):
        mode.to_command(np.full(10, np.nan), state)
    with pytest.raises(ValueError, match="degenerate 6-D rotation"):
        mode.to_command(np.array([0, 0, 0, 1, 0, 0, 2, 0, 0, 0.0]), state)
    with pytest.raises(ValueError, match="action_mode must be one of"):
        make_action_mode("torque", UR5E, [LIMITS_6])

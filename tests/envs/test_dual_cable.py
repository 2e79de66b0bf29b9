"""The dual-UR5e Cable env and its two-arm expert (``ur5e_dual_cable``).

The generic promises (start pose, determinism, random actions, expert success in joint and
eef_rel, env checker, LeRobot type) are in ``test_contract.py``. Here: the 14-D action that a
two-arm expert assembles means, per arm, the target it was given (in every action mode), both
arms do the work in an expert episode, and the success rule is RMB's single-arm Cable rule.
"""

from __future__ import annotations

import numpy as np
import pytest

from rmb_lerobot.envs.experts.dual_cable import DualCableExpert, LeftCableArm, RightCableArm
from rmb_lerobot.envs.experts.multi_arm import MultiArmExpert
from rmb_lerobot.envs.registry import ENVS
from rmb_lerobot.envs.tasks.cable import CABLE_END, CableTask

NAME = "ur5e_dual_cable"
GRIPPERS = (40.0, 200.0)  # left, right: distinct, so a swapped layout shows
ACTION_SIZES = {"joint": 2 * (6 + 1), "eef_abs": 2 * 9 + 2, "eef_rel": 2 * 6 + 2}
ARM_OFFSETS = (  # rad, added to each arm's start pose: distinct small moves per arm
    np.array([0.05, -0.04, 0.06, 0.0, 0.03, -0.05]),
    np.array([-0.06, 0.03, -0.05, 0.04, 0.0, 0.05]),
)


@pytest.fixture(scope="module")
def make_env():
    envs = {}

    def get(mode: str):
        if mode not in envs:
            envs[mode] = ENVS[NAME].make(cameras=(), action_mode=mode)
        return envs[mode]

    yield get
    for env in envs.values():
        env.close()


@pytest.mark.parametrize("mode", ["joint", "eef_abs", "eef_rel"])
def test_per_arm_targets_become_per_arm_commands(make_env, mode):
    """Each arm's eef target and gripper value, assembled into one action, commands exactly that
    arm: joints that reach the target, its own gripper value (left first, as the robot record
    orders the 14-D joint vector)."""
    env = make_env(mode)
    env.reset(seed=0, options={"world_idx": 0})
    expert = DualCableExpert(env)
    expert.reset()
    slices = env.robot.joint_slices()
    starts = [env.command[joints] for joints, _ in slices]
    wanted = [q + offset for q, offset in zip(starts, ARM_OFFSETS, strict=True)]
    targets = [(env.sim.fk(i, q), g) for i, (q, g) in enumerate(zip(wanted, GRIPPERS, strict=True))]

    action = expert.assemble(targets)
    # joint: per arm 6 joints + gripper; eef: per arm its pose part (9 or 6), then 2 grippers
    assert action.shape == env.action_space.shape == (ACTION_SIZES[mode],)
    command = env.command_from_action(action)
    for (joints, gripper), q, g in zip(slices, wanted, GRIPPERS, strict=True):
        np.testing.assert_allclose(command[joints], q, atol=2e-3)
        assert command[gripper] == pytest.approx(g)


def test_arms_must_be_given_in_the_robots_order(make_env):
    env = make_env("joint")
    with pytest.raises(ValueError, match="arm_index 0"):
        MultiArmExpert(env, (RightCableArm(env), LeftCableArm(env)))


def test_success_rule_is_rmbs_single_arm_cable_rule(make_env):
    """RMB has no reward for MujocoUR5eDualCable; the env uses the single-arm Cable task and
    its rule (cable through the gap into the S, end box past pole 2 and below the pole line)."""
    env = make_env("joint")
    assert type(env.task) is CableTask
    env.reset(seed=0, options={"world_idx": 0})
    assert not env.task.is_success(env.sim)  # the cable starts straight, not routed


def test_both_arms_work_in_an_expert_episode(make_env):
    """The right arm holds the box first, the left arm after the handover; each carries it a
    good way (an arm only parked would fail this)."""
    env = make_env("joint")
    expert = DualCableExpert(env)
    env.reset(seed=3, options={"world_idx": 3, "random_shift": 0.03})
    expert.reset()
    carried = {arm.arm.name: 0.0 for arm in expert.arms}
    holder_order = []
    last_box = env.sim.body_pose(CABLE_END)[0]
    for _ in range(env.task.max_episode_steps):
        *_, terminated, _, _ = env.step(expert())
        box = env.sim.body_pose(CABLE_END)[0]
        for arm in expert.arms:
            closed = env.measured_joint_pos()[arm.gripper_index] > 0.5 * arm.closed_gripper
            if closed and np.linalg.norm(arm.measured_tool() - box) < 0.03:
                carried[arm.arm.name] += float(np.linalg.norm(box - last_box))
                if not holder_order or holder_order[-1] != arm.arm.name:
                    holder_order.append(arm.arm.name)
        last_box = box
        if terminated:
            break
    assert holder_order == ["right", "left"]
    assert carried["right"] > 0.3 and carried["left"] > 0.3, carried

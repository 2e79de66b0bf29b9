"""The G1 Bottles expert: both hands grasp their bottle from above and lift it, in the joint
and the relative end-effector action modes, over several seeds with a random bottle shift."""

import numpy as np
import pytest

from rmb_lerobot.envs.experts.bottles import BottleArm, BottlesExpert, hand_rotation
from rmb_lerobot.envs.experts.carry import CarryPhase
from rmb_lerobot.envs.registry import ENVS
from rmb_lerobot.envs.tasks.bottles import BOTTLES

SEEDS = range(5)


@pytest.fixture(scope="module", params=["joint", "eef_rel"])
def env(request):
    env = ENVS["g1_bottles"].make(action_mode=request.param, cameras=())
    yield env
    env.close()


def run(env, expert, seed: int):
    """One episode with a 3 cm random shift; returns (success, steps taken)."""
    env.reset(seed=seed, options={"random_shift": 0.03})
    expert.reset()
    steps, terminated = 0, False
    while not terminated and steps < env.task.max_episode_steps:
        _, _, terminated, _, info = env.step(expert(None))
        steps += 1
    return info["is_success"], steps


def test_the_expert_lifts_both_bottles(env):
    expert = BottlesExpert(env)
    outcomes = [run(env, expert, seed) for seed in SEEDS]
    assert all(success for success, _ in outcomes), outcomes
    # Both hands hold their bottle: the lift ends the episode well before its limit.
    assert max(steps for _, steps in outcomes) < env.task.max_episode_steps // 2
    for arm, bottle in zip(expert.arms, BOTTLES, strict=True):
        assert arm.phase in (CarryPhase.LIFT, CarryPhase.CARRY) and arm.bottle == bottle
        held = env.sim.data.body(bottle).xpos
        grasp = env.sim.data.site(arm.arm.tcp_frame).xpos
        assert np.linalg.norm(held[:2] - grasp[:2]) < 0.03  # the bottle is in this hand


def test_neither_hand_lifts_before_both_hold(env):
    expert = BottlesExpert(env)
    env.reset(seed=0)
    expert.reset()
    tops = []
    for _ in range(env.task.max_episode_steps):
        env.step(expert(None))
        holding = [arm.holding for arm in expert.arms]
        if not all(holding):
            tops.append([env.sim.data.body(b).xpos[2] for b in BOTTLES])
        else:
            break
    start = env.task.workspace.table.top_z
    assert np.max(np.abs(np.array(tops) - start)) < 0.01  # still standing when both hold


def test_hands_turn_palm_down_as_mirror_images():
    left, right = hand_rotation(0).as_matrix(), hand_rotation(1).as_matrix()
    # The left palm faces its -y axis, the right its +y axis: both face down.
    assert left[2, 1] > 0.9 and right[2, 1] < -0.9
    np.testing.assert_allclose(right, np.diag([1, -1, 1]) @ left @ np.diag([1, -1, 1]), atol=1e-12)
    assert BottleArm.grip_depth < 0.07  # grips the bottle's top half

"""The two-arm Handover expert on ALOHA: the left arm picks, hands over, the right arm places.

Success over a few seeds per action mode (the 100-episode rates are in benchmarks/RESULTS.md),
and that the episode really is a handover: each arm held the object at some point, and the
left had let go before it was set down.
"""

from __future__ import annotations

import numpy as np
import pytest

from rmb_lerobot.envs.experts.carry import CarryPhase
from rmb_lerobot.envs.experts.handover import HandoverExpert
from rmb_lerobot.envs.registry import ENVS
from rmb_lerobot.envs.tasks.handover import MAT1, MAT2, OBJECT


@pytest.fixture(scope="module")
def make_env():
    envs = {}

    def get(mode: str):
        if mode not in envs:
            envs[mode] = ENVS["aloha_handover"].make(cameras=(), action_mode=mode)
        return envs[mode]

    yield get
    for env in envs.values():
        env.close()


@pytest.mark.parametrize("mode", ["joint", "eef_rel"])
@pytest.mark.parametrize("episode", [0, 3, 5])
def test_expert_hands_the_object_over_and_sets_it_on_mat2(make_env, mode, episode):
    env = make_env(mode)
    expert = HandoverExpert(env)
    obs, _ = env.reset(seed=episode, options={"world_idx": episode % 6, "random_shift": 0.03})
    expert.reset()
    start = env.sim.data.body(OBJECT).xpos.copy()
    held_by, released_before_success = set(), False
    for _ in range(env.task.max_episode_steps):
        obs, _, terminated, _, info = env.step(expert(obs))
        for name, arm in (("left", expert.left), ("right", expert.right)):
            if arm.phase in (CarryPhase.LIFT, CarryPhase.CARRY):
                held_by.add(name)
        if terminated:
            released_before_success = expert.left.phase is CarryPhase.RETREAT
            break
    assert info["is_success"]
    assert held_by == {"left", "right"} and released_before_success
    # Carried across the table: from mat 1 to over mat 2 (the two are 0.5-0.7 m apart).
    obj = env.sim.data.body(OBJECT).xpos[:2]
    mat1, mat2 = (env.sim.data.body(mat).xpos[:2] for mat in (MAT1, MAT2))
    assert np.linalg.norm(obj - mat2) < 0.02 and np.linalg.norm(obj - mat1) > 0.4
    assert np.linalg.norm(start[:2] - mat1) < 1e-6


def test_expert_refuses_a_robot_without_two_arms():
    env = ENVS["toolbox"].make(cameras=())
    try:
        with pytest.raises(ValueError, match="drives two arms; robot 'ur5e' has 1"):
            HandoverExpert(env)
    finally:
        env.close()

"""RMB's HSR TidyUp: the scene, RMB's reward (0.5 per bottle in its own container) and the
scripted expert that drives the base between the bottles and the containers."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from rmb_lerobot.envs.registry import entry_for
from rmb_lerobot.envs.tasks.tidyup import BOTTLES, CONTAINERS, TidyUpTask

ENTRY = entry_for("hsr_tidyup")


@pytest.fixture(scope="module")
def env():
    env = ENTRY.make(cameras=(), render_mode=None)
    yield env
    env.close()


def place(env, bottle: str, xyz) -> None:
    """Put a bottle's origin at ``xyz``, upright and at rest."""
    joint = env.sim.data.joint(f"{bottle}_freejoint")
    joint.qpos[:3] = xyz
    joint.qpos[3:] = (1.0, 0.0, 0.0, 0.0)
    joint.qvel[:] = 0.0
    mujoco.mj_forward(env.sim.model, env.sim.data)


def test_names_and_worlds_are_rmbs():
    assert ENTRY.rmb_env_name == "MujocoHsrTidyup" and ENTRY.lerobot_type == "rmb_hsr_tidyup"
    assert ENTRY.robot_type == "hsr" and ENTRY.cameras == ("front", "hand", "head")
    task = TidyUpTask()
    np.testing.assert_allclose(task.world_offsets[:, 1], [-0.06, -0.03, 0.0, 0.03, 0.06, 0.09])
    np.testing.assert_allclose(task.world_offsets[:, [0, 2]], 0.0)


@pytest.mark.parametrize("world_idx", [0, 5])
def test_the_bottles_stand_where_rmb_puts_them(env, world_idx):
    env.reset(seed=0, options={"world_idx": world_idx})
    dy = env.task.world_offsets[world_idx][1]
    for _ in range(10):
        env.step(env.command.astype(np.float32))
    scene = env.sim.scene
    for bottle, y in zip(BOTTLES, (0.08, -0.08), strict=True):
        pos, rot = scene.body_pose(bottle)
        np.testing.assert_allclose(pos[:2], (0.7, y + dy), atol=1e-3)
        assert abs(pos[2]) < 2e-3 and rot[2, 2] > 0.999  # standing on the floor
    for container, x in zip(CONTAINERS, (1.0, 1.2), strict=True):
        np.testing.assert_allclose(scene.body_pose(container)[0], (x, 0.0, 0.0))
    assert env.task.reward(scene) == 0.0 and not env.task.is_success(scene)


def test_reward_is_half_per_bottle_in_its_own_container(env):
    env.reset(seed=0, options={"world_idx": 2})
    scene, task = env.sim.scene, env.task
    place(env, "bottle1", (1.0, 0.05, 0.011))  # in container 1
    assert task.reward(scene) == 0.5 and not task.is_success(scene)
    place(env, "bottle2", (1.0, -0.05, 0.011))  # in container 1 too: not its own
    assert task.reward(scene) == 0.5
    place(env, "bottle2", (1.2, -0.05, 0.011))
    assert task.reward(scene) == 1.0 and task.is_success(scene)
    place(env, "bottle1", (1.0, 0.05, 0.2))  # held above its container: not in it
    assert task.reward(scene) == 0.5 and not task.is_success(scene)


@pytest.mark.parametrize("mode", ["joint", "eef_rel"])
def test_expert_drives_and_tidies_both_bottles(mode):
    """A few seeds and worlds, each with a random shift: both bottles end in their containers,
    the base having driven there and back (its velocity part of every action)."""
    env = ENTRY.make(cameras=(), render_mode=None, action_mode=mode)
    expert = ENTRY.load_expert_class()(env)
    try:
        for seed, world in ((0, 0), (1, 5)):
            obs, _ = env.reset(seed=seed, options={"world_idx": world, "random_shift": 0.02})
            expert.reset()
            travelled, info = 0.0, {"is_success": False}
            for _ in range(env.task.max_episode_steps):
                action = expert(obs)
                assert action.shape == env.action_space.shape  # base velocity last
                travelled += np.linalg.norm(action[-3:-1]) * env.control_dt
                obs, _, terminated, _, info = env.step(action)
                if terminated:
                    break
            assert info["is_success"], (mode, seed, world)
            assert travelled > 1.5  # to the containers and back
    finally:
        env.close()

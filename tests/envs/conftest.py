"""Shared env fixtures: building the scene costs about a second, so envs are module-scoped."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from rmb_lerobot.envs.base import RmbEnv
from rmb_lerobot.envs.registry import compose
from rmb_lerobot.envs.tasks.insert import InsertTask


@pytest.fixture(scope="module")
def physics_env():
    """Insert env without cameras (physics only)."""
    env = compose(InsertTask(), cameras=())
    yield env
    env.close()


@pytest.fixture(scope="module")
def camera_env():
    """Insert env with two small cameras and depth."""
    env = compose(InsertTask(), cameras=("front", "hand"), image_size=(64, 48), depth=True)
    yield env
    env.close()


@pytest.fixture
def make_env():
    """``make_env(task, **kwargs)``: a physics-only ``RmbEnv`` for one test, closed afterwards
    (for envs a module-scoped fixture cannot share, e.g. another action mode)."""
    envs = []

    def make(task, **kwargs) -> RmbEnv:
        envs.append(compose(task, cameras=(), **kwargs))
        return envs[-1]

    yield make
    for env in envs:
        env.close()


def _assert_not_diverged(env: RmbEnv) -> None:
    """The state is finite and, in MuJoCo, did not hit a divergent acceleration on the way:
    MuJoCo then resets the state itself (finite again, the divergence hidden) and only counts
    it in ``data.warning``, which ``env.reset`` clears. Other backends: the measured joint
    state is finite."""
    assert np.all(np.isfinite(env.measured_joint_pos())) and np.all(
        np.isfinite(env.measured_joint_vel())
    )
    if env.simulator != "mujoco":
        return
    assert np.all(np.isfinite(env.sim.data.qpos)) and np.all(np.isfinite(env.sim.data.qvel))
    diverged = env.sim.data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number
    assert diverged == 0, f"MuJoCo reset a divergent state {diverged} time(s)"


def _run_expert(env: RmbEnv, expert_class: type, episode: int, **options) -> dict:
    expert = expert_class(env)
    options = {"world_idx": episode % env.task.num_worlds, "random_shift": 0.03, **options}
    obs, _ = env.reset(seed=episode, options=options)
    expert.reset()
    info = {}
    for _ in range(env.task.max_episode_steps):
        obs, _, terminated, _, info = env.step(expert(obs))
        _assert_not_diverged(env)
        if terminated:
            break
    return info


@pytest.fixture
def run_expert():
    """``run_expert(env, ExpertClass, episode, **options) -> info``: one expert episode as the
    benchmarks run it (seed ``episode``, world ``episode % num_worlds``, 3 cm random shift;
    ``options`` add or override reset options), until the task ends; returns the last step's
    info."""
    return _run_expert


def _random_actions(env: RmbEnv, steps: int = 1000, seed: int = 0):
    env.action_space.seed(seed)
    for step in range(steps):
        env.step(env.action_space.sample())
        _assert_not_diverged(env)
        yield step


@pytest.fixture
def random_actions():
    """``for _ in random_actions(env, steps=1000, seed=0)``: steps the (already reset) env with
    seeded uniformly random actions, checking the state stays finite and never diverged, and
    yields after each step so that a stability test can watch the simulation as it goes.

    Uniform joint targets over the whole joint range swing the simulated UR5e at up to ~30
    rad/s per joint and ~11 m/s at the tool (a real one stops at 3.1 rad/s): a stress test.
    Which objects get hit, and how, is chaotic (CPUs differ in MuJoCo's last bits), so a
    stability test checks its invariants over several seeds and worlds, never one rollout."""
    return _random_actions

"""Teleoperation fixtures: envs are built once per module (about 2 s each), a recorded episode
once per session."""

from __future__ import annotations

import numpy as np
import pytest

from rmb_lerobot.envs.registry import entry_for
from rmb_lerobot.episode import EpisodeWriter

RECORDED_STEPS = 25


@pytest.fixture(scope="module")
def cable_env():
    """RMB's UR5e cable env with one small camera (images end up in the episodes)."""
    env = entry_for("cable").make(cameras=("front",), image_size=(48, 32), depth=False)
    yield env
    env.close()


@pytest.fixture(scope="module")
def dual_env():
    """The dual UR5e cable env, physics only."""
    env = entry_for("ur5e_dual_cable").make(cameras=())
    yield env
    env.close()


@pytest.fixture(scope="session")
def recorded_episode(tmp_path_factory):
    """An episode recorded the way ``rmb-collect`` records one (``rmb_step_data`` of each
    command before ``step``): a smooth joint motion with the gripper closing, in world 1."""
    env = entry_for("cable").make(cameras=(), depth=False)
    path = tmp_path_factory.mktemp("log") / "MujocoUR5eCable_world1_000.rmb"
    try:
        env.reset(seed=3, options={"world_idx": 1})
        home = env.command
        writer = EpisodeWriter(path, {**env.rmb_attrs(), "demo_name": path.stem})
        for t in range(RECORDED_STEPS):
            command = home.copy()
            command[:6] += (
                0.2
                * np.sin(np.linspace(0, np.pi, RECORDED_STEPS)[t])
                * np.array([1, -0.5, 0.5, 0.3, 0.2, 1.0])
            )
            command[6] = 255.0 * t / (RECORDED_STEPS - 1)
            writer.append(env.rmb_step_data(command))
            env.step(command)
        writer.close()
    finally:
        env.close()
    return path

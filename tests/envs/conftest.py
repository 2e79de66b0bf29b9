"""Shared env fixtures: building the scene costs about a second, so envs are module-scoped."""

from __future__ import annotations

import pytest
from rmb_lerobot.envs.base import RmbEnv
from rmb_lerobot.envs.tasks.insert import InsertTask


@pytest.fixture(scope="module")
def physics_env():
    """Insert env without cameras (physics only)."""
    env = RmbEnv(InsertTask(), cameras=())
    yield env
    env.close()


@pytest.fixture(scope="module")
def camera_env():
    """Insert env with two small cameras and depth."""
    env = RmbEnv(InsertTask(), cameras=("front", "hand"), image_size=(64, 48), depth=True)
    yield env
    env.close()

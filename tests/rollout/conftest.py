"""Doubles for the rollout server: a small instruction-taking env and a policy that records the
task it was given. Both are real implementations of the interfaces the server uses (gymnasium's
``Env``, :class:`~rmb_lerobot.rollout.RolloutPolicy`); the socket is always a real one."""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import ClassVar

import gymnasium as gym
import numpy as np
import pytest

from rmb_lerobot.rollout import RolloutServer

KNOWN = ("Put the banana in the blue basket.", "Put the apple in the black basket.")
BANANA, APPLE = KNOWN


class _ResetOptions:
    """Like our envs' ``task``: the reset options the env takes."""

    reset_options = ("instruction",)


class PushEnv(gym.Env):
    """A block pushed along a line: each action adds its value to the position; the episode
    succeeds (and terminates) once the position reaches ``goal``. Like Pick, ``reset`` takes an
    ``instruction`` option, refuses unknown ones and makes it the ``task_description``."""

    metadata: ClassVar[dict] = {"render_modes": []}

    def __init__(self, goal: float = 3.0):
        self.goal = goal
        self.task = _ResetOptions()
        self.observation_space = gym.spaces.Dict(
            {"agent_pos": gym.spaces.Box(-np.inf, np.inf, (1,), dtype=np.float32)}
        )
        self.action_space = gym.spaces.Box(-1.0, 1.0, (1,), dtype=np.float32)
        self.position = 0.0
        self.task_description = ""
        self.resets: list[dict] = []

    def _obs(self) -> dict:
        return {"agent_pos": np.array([self.position], dtype=np.float32)}

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        options = dict(options or {})
        instruction = options.get("instruction")
        if instruction is not None and instruction not in KNOWN:
            raise ValueError(f"unknown instruction {instruction!r}; one of {KNOWN}")
        self.resets.append({"seed": seed, **options})
        self.task_description = instruction or KNOWN[0]
        self.position = 0.0
        return self._obs(), {"is_success": False}

    def step(self, action):
        self.position += float(np.asarray(action).reshape(-1)[0])
        success = self.position >= self.goal
        return self._obs(), float(success), success, False, {"is_success": success}


class RecordingPolicy:
    """Pushes (+1) when the instruction mentions a banana, else holds (0); records the task
    and observation of every call."""

    def __init__(self):
        self.calls: list[tuple[str, float]] = []
        self.resets = 0

    def reset(self) -> None:
        self.resets += 1

    def act(self, observation, instruction: str) -> np.ndarray:
        self.calls.append((instruction, float(observation["agent_pos"][0])))
        return np.array([1.0 if "banana" in instruction else 0.0], dtype=np.float32)


def push_env(max_steps: int = 20, goal: float = 3.0) -> gym.Env:
    return gym.wrappers.TimeLimit(PushEnv(goal), max_episode_steps=max_steps)


@pytest.fixture
def make_push_env():
    """``make_push_env(max_steps=20, goal=3.0)``: a :class:`PushEnv` in a ``TimeLimit``."""
    return push_env


@pytest.fixture
def policy() -> RecordingPolicy:
    return RecordingPolicy()


@pytest.fixture
def sock_path(tmp_path_factory) -> Path:
    """A short path for a Unix socket (sun_path holds about 107 bytes)."""
    import tempfile

    directory = Path(tempfile.mkdtemp(prefix="rmbr"))
    yield directory / "r.sock"
    for child in directory.iterdir():
        child.unlink()
    directory.rmdir()


@pytest.fixture
def serving():
    """``with serving(env, policy, address, **kwargs) as server``: a bound server whose
    ``serve()`` runs in a thread; leaving the block stops it, joins it and closes the socket."""

    @contextlib.contextmanager
    def _serving(env, policy, address, **kwargs) -> Iterator[RolloutServer]:
        server = RolloutServer(env, policy, address, **kwargs)
        with server:
            thread = threading.Thread(target=server.serve, daemon=True)
            thread.start()
            try:
                yield server
            finally:
                server.stop()
                thread.join(timeout=10)
                assert not thread.is_alive(), "serve() did not return after stop()"

    return _serving

"""Record RMB episodes on a real robot (or its twins) with the same writer as the sim envs.

:func:`record_episode` runs one episode of a real env under a command stream (a teleoperator,
a replayed episode, a policy: anything mapping an observation to an action) and writes every
key RMB records (joints, velocities, gripper, eef poses, wrench, RGB + depth + fovy) with
:class:`~rmb_lerobot.episode.EpisodeWriter`. The writer works in a temporary sibling and moves
the episode into place only when it is complete: a fault (a refused command, a lost
connection, a protective stop, a stale arm, Ctrl-C) stops the arms (the device does that),
discards the temporary and re-raises, so the episode is left out, never half written.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from rmb_lerobot.envs.base import RmbEnv
from rmb_lerobot.episode import EpisodeWriter

Policy = Callable[[dict[str, Any]], np.ndarray]
"""An observation -> the next action (RMB's command vector in joint mode)."""


def record_episode(
    env: RmbEnv,
    policy: Policy,
    path: str | Path,
    *,
    steps: int | None = None,
    seed: int | None = None,
    options: Mapping[str, Any] | None = None,
    depth_codec: str = "rmb-videoio",
    overwrite: bool = False,
) -> Path:
    """Reset the env, run ``policy`` for ``steps`` steps, write the episode atomically.

    Args:
        env: A real env (:func:`~rmb_lerobot.envs.real.config.make_real_env`), unwrapped.
        policy: Observation -> action.
        path: ``NAME.rmb`` or ``NAME.hdf5``.
        steps: How many steps (default: the task's ``max_episode_steps``).
        seed: Reset seed.
        options: Reset options.
        depth_codec: Depth codec of the compact format.
        overwrite: Replace an existing episode.

    Returns:
        The episode's path.

    Raises:
        ValueError: The action mode refused an action (non-finite, wrong shape): episode left
            out, arms stopped.
        SafetyError: The safety layer refused a command (episode left out, arms stopped).
        DriverError: An arm failed (episode left out, arms stopped).
        KeyboardInterrupt: Ctrl-C (episode left out, arms stopped).
    """
    path = Path(path)
    obs, _ = env.reset(seed=seed, options=dict(options or {}))
    attrs = {**env.rmb_attrs(), "demo_name": path.stem}
    writer = EpisodeWriter(path, attrs, depth_codec=depth_codec, overwrite=overwrite)
    try:
        for _ in range(env.task.max_episode_steps if steps is None else steps):
            action = policy(obs)
            writer.append(env.rmb_step_data(action))
            obs, *_ = env.step(action)
        end_episode = getattr(env.sim, "end_episode", None)
        if end_episode is not None:
            end_episode()
        return writer.close()
    except BaseException:
        stop = getattr(env.sim, "stop", None)
        try:
            if stop is not None:
                stop()  # also where the env refused the action before it reached the arm
        finally:
            writer.abort()
        raise

"""rmb_lerobot: RoboManipBaselines data, environments and policies for LeRobot.

The public entry points for RMB episodes are available here::

    import rmb_lerobot
    with rmb_lerobot.open_episode("demo.rmb") as ep:
        ep["front_rgb_image"][0]

They are imported lazily, so ``import rmb_lerobot`` (which LeRobot's plugin discovery does on
every CLI start) stays cheap until episode I/O is actually used. Importing the package registers
the RMB environments with gymnasium (``gymnasium.make("rmb_lerobot/MujocoUR5eInsert-v0")``);
MuJoCo itself is only imported when an env is made.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

__version__ = "0.1.0"

_LAZY = {
    "Episode": "rmb_lerobot.episode",
    "EpisodeFormat": "rmb_lerobot.episode",
    "EpisodeWriter": "rmb_lerobot.episode",
    "find_episodes": "rmb_lerobot.episode",
    "open_episode": "rmb_lerobot.episode",
    "switch_format": "rmb_lerobot.episode",
    "MissingKeyError": "rmb_lerobot.errors",
    "RmbFormatError": "rmb_lerobot.errors",
}
__all__ = [
    "Episode",
    "EpisodeFormat",
    "EpisodeWriter",
    "MissingKeyError",
    "RmbFormatError",
    "find_episodes",
    "open_episode",
    "switch_format",
]

if TYPE_CHECKING:  # what static type checkers and IDEs see
    from rmb_lerobot.episode import (
        Episode,
        EpisodeFormat,
        EpisodeWriter,
        find_episodes,
        open_episode,
        switch_format,
    )
    from rmb_lerobot.errors import MissingKeyError, RmbFormatError


def _register_gym_envs() -> None:
    from rmb_lerobot.envs.registry import register_gym_envs

    register_gym_envs()


_register_gym_envs()


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(importlib.import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'rmb_lerobot' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *_LAZY])

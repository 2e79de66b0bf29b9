"""rmb_lerobot: RoboManipBaselines data, environments and policies for LeRobot.

The public entry points for RMB episodes are re-exported here::

    import rmb_lerobot
    with rmb_lerobot.open_episode("demo.rmb") as ep:
        ep["front_rgb_image"][0]
"""

from rmb_lerobot.episode import (
    Episode,
    EpisodeFormat,
    EpisodeWriter,
    find_episodes,
    open_episode,
    switch_format,
)
from rmb_lerobot.errors import MissingKeyError, RmbFormatError

__version__ = "0.1.0"

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

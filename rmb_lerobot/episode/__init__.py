"""The RMB episode format: reader, streaming writer, and variant switching."""

from rmb_lerobot.episode.layout import EpisodeFormat, episode_format
from rmb_lerobot.episode.reader import Episode, find_episodes, open_episode
from rmb_lerobot.episode.switch import switch_format
from rmb_lerobot.episode.timing import control_rate
from rmb_lerobot.episode.writer import EpisodeWriter, ForwardKinematics

__all__ = [
    "Episode",
    "EpisodeFormat",
    "EpisodeWriter",
    "ForwardKinematics",
    "control_rate",
    "episode_format",
    "find_episodes",
    "open_episode",
    "switch_format",
]

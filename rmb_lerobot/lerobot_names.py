"""LeRobot feature names for RMB data: what env observations and dataset columns are called.

The env types' ``features_map`` targets and the converters' dataset keys both come from here,
so ``lerobot-train --env.type=rmb_...`` evaluates on a converted dataset without a rename map.
"""

from __future__ import annotations

from lerobot.utils.constants import ACTION, OBS_IMAGES, OBS_STATE

STATE = OBS_STATE  # "observation.state": the concatenated state keys (default: joint positions)
ACTION_KEY = ACTION  # "action"

# Raw env observation keys (LeRobot's env contract) -> dataset keys.
ENV_STATE_KEY = "agent_pos"
ENV_PIXELS_KEY = "pixels"


def image_key(camera: str) -> str:
    """``front`` -> ``observation.images.front`` (an RGB camera feature)."""
    return f"{OBS_IMAGES}.{camera}"


def env_pixels_key(camera: str) -> str:
    """``front`` -> ``pixels/front``, the nested env observation key LeRobot flattens."""
    return f"{ENV_PIXELS_KEY}/{camera}"

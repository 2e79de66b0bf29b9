"""LeRobot feature names for RMB data: what env observations and dataset columns are called.

The env types' ``features_map`` targets and the converters' dataset keys both come from here,
so ``lerobot-train --env.type=rmb_...`` evaluates on a converted dataset without a rename map.
"""

from __future__ import annotations

from lerobot.utils.constants import ACTION, OBS_IMAGES, OBS_STATE, OBS_STR

from rmb_lerobot import keys as K

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


# ---------------------------------------------------------------- real-arm robot plugins
# Action and observation names of the ``rmb_ur5e`` / ``rmb_xarm7`` LeRobot robots (their
# datasets come from ``lerobot-record``): joints and the gripper end in ``.pos``; with
# ``action_space: ee_velocity`` the action is the end-effector twist (m/s, rad/s in the arm's
# base frame) and the gripper. ``rmb-convert from-lerobot`` reads these names.
GRIPPER_POS_NAME = "gripper.pos"
EE_VELOCITY_NAMES = (
    "ee_x.vel",
    "ee_y.vel",
    "ee_z.vel",
    "ee_roll.vel",
    "ee_pitch.vel",
    "ee_yaw.vel",
)

# ---------------------------------------------------------------- converted datasets
# LeRobot's robots name a camera's depth stream ``<camera>_depth`` (e.g. so_follower), so a
# depth camera becomes ``observation.images.<camera>_depth``, flagged ``is_depth_map``.
DEPTH_CAMERA_SUFFIX = "_depth"

# RMB keys that are neither state nor action keep their own column: measured keys under
# ``observation.``, command keys under ``action.`` (``measured_eef_pose`` ->
# ``observation.eef_pose``, ``command_joint_pos_rel`` -> ``action.joint_pos_rel``); ``time`` and
# ``reward`` keep their RMB names, outside both namespaces, so policies never take them as inputs.
_SOURCE_PREFIXES = {K.MEASURED: OBS_STR + ".", K.COMMAND: ACTION + "."}

# Files a converted dataset carries next to LeRobot's own metadata.
RMB_METADATA_PATH = "meta/rmb.json"  # per-episode RMB attributes, key mapping, true frame rate
GR00T_MODALITY_PATH = "meta/modality.json"  # GR00T's description of the state/action layout


def depth_image_key(camera: str) -> str:
    """``front`` -> ``observation.images.front_depth`` (a depth camera feature)."""
    return image_key(camera + DEPTH_CAMERA_SUFFIX)


def camera_of_image_key(key: str) -> str | None:
    """``observation.images.front`` -> ``front``; None for keys outside ``observation.images``."""
    prefix = f"{OBS_IMAGES}."
    return key.removeprefix(prefix) if key.startswith(prefix) else None


def rmb_feature_key(rmb_key: str) -> str:
    """The dataset column of an RMB key kept as its own feature (see the rule above).

    Keys outside the catalogue keep their own name.
    """
    spec = K.KEYS.get(rmb_key)
    if spec is None or spec.source is None:
        return rmb_key
    return _SOURCE_PREFIXES[spec.source] + rmb_key.removeprefix(spec.source + "_")


def rmb_key_of_feature(feature: str) -> str | None:
    """Inverse of :func:`rmb_feature_key`; None when the column is no RMB key."""
    for source, prefix in _SOURCE_PREFIXES.items():
        if feature.startswith(prefix):
            candidate = f"{source}_{feature.removeprefix(prefix)}"
            return candidate if candidate in K.KEYS else None
    return feature if feature in K.KEYS and K.KEYS[feature].source is None else None

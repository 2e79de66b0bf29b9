"""Which RMB key each feature of a LeRobotDataset becomes (``rmb-convert from-lerobot``).

Resolution order, per part, first match wins:

1. explicit overrides (``--state-keys``, ``--action-keys``, ``--camera-map``, ``--key-map``);
2. ``meta/rmb.json`` of a dataset made by ``rmb-convert to-lerobot`` (exact inverse);
3. self-describing names: state/action names ``<rmb key>.<component>`` split the vector;
4. defaults for any LeRobot dataset (e.g. one made by ``lerobot-record``):

   - ``observation.state`` -> ``measured_joint_pos``; ``action`` -> ``command_joint_pos``
     (a vector may split into several keys given as ``KEY:DIM``; the last may omit ``:DIM``);
     an ``rmb_ur5e`` / ``rmb_xarm7`` end-effector action (``ee_x.vel`` .. ``ee_yaw.vel``,
     ``gripper.pos``) -> ``command_eef_vel`` + ``command_gripper_joint_pos``; any other
     action with velocity names (``*.vel``) is refused unless ``--action-keys`` says what it is;
   - ``observation.images.<cam>`` -> ``<cam>_rgb_image``; a depth feature (``is_depth_map``)
     ``observation.images.<cam>_depth`` -> ``<cam>_depth_image``;
   - ``observation.<q>`` / ``action.<q>`` -> ``measured_<q>`` / ``command_<q>`` when that is an
     RMB key; ``time``, ``reward`` as such; LeRobot's ``next.reward`` -> ``reward``;
   - RMB's ``time`` from LeRobot's ``timestamp`` when no ``time`` feature exists.

Features mapped to nothing are reported and skipped. Absolute eef poses in a state/action vector
are the 9-number policy view and are turned back into ``(x, y, z, qw, qx, qy, qz)``.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from lerobot.utils.constants import DEFAULT_FEATURES, REWARD

from rmb_lerobot import keys as K
from rmb_lerobot import lerobot_names as N
from rmb_lerobot.converters.components import split_by_prefix

logger = logging.getLogger(__name__)

KeyDims = tuple[tuple[str, int | None], ...]  # RMB keys a vector splits into, with their sizes


@dataclass(frozen=True)
class MappingOverrides:
    """User overrides of the default mapping (all optional)."""

    state_keys: tuple[str, ...] = ()  # "KEY" or "KEY:DIM", in vector order
    action_keys: tuple[str, ...] = ()
    cameras: Mapping[str, str] = field(default_factory=dict)  # image feature -> camera name
    keys: Mapping[str, str] = field(default_factory=dict)  # other feature -> RMB key


@dataclass(frozen=True)
class KeyMapping:
    """The resolved mapping of one dataset."""

    state: KeyDims
    action: KeyDims
    images: Mapping[str, str]  # image/video feature -> RMB image key
    features: Mapping[str, str]  # other feature -> RMB key (used before state/action splits)

    def cameras(self) -> list[str]:
        return list(dict.fromkeys(K.camera_of(key) for key in self.images.values()))


def parse_key_dims(items: Sequence[str]) -> KeyDims:
    """``["measured_joint_pos:6", "measured_gripper_joint_pos"]`` -> key/size pairs."""
    parsed = []
    for i, item in enumerate(items):
        key, _, dim = item.partition(":")
        if not dim and i < len(items) - 1:
            raise ValueError(f"{item!r}: every key but the last needs a size, as KEY:DIM")
        parsed.append((key, int(dim) if dim else None))
    return tuple(parsed)


def _vector(
    feature: str, features: Mapping[str, dict], override: Sequence[str], keys: Sequence[str] | None
) -> KeyDims:
    if override:
        return parse_key_dims(override)
    names = list(features.get(feature, {}).get("names") or [])
    by_prefix = split_by_prefix(names) if names else None
    if by_prefix is not None and (keys is None or [k for k, _ in by_prefix] == list(keys)):
        return tuple(by_prefix)
    if keys and len(keys) == 1:
        return ((keys[0], None),)
    if feature == N.ACTION_KEY and any(name.endswith(".vel") for name in names):
        return _velocity_action(names)
    return ((K.MEASURED_JOINT_POS if feature == N.STATE else K.COMMAND_JOINT_POS, None),)


def _velocity_action(names: Sequence[str]) -> KeyDims:
    """An action of velocities is no joint command: the end-effector twist of our real-arm
    robots, or an error that says how to name it."""
    if list(names) == [*N.EE_VELOCITY_NAMES, N.GRIPPER_POS_NAME]:
        return ((K.COMMAND_EEF_VEL, len(N.EE_VELOCITY_NAMES)), (K.COMMAND_GRIPPER_JOINT_POS, 1))
    raise ValueError(
        f"action names {list(names)} hold velocities ('.vel'), so the action is not "
        f"{K.COMMAND_JOINT_POS!r}; say which RMB keys it splits into with --action-keys "
        f"KEY:DIM ... (e.g. {K.COMMAND_EEF_VEL}:6 {K.COMMAND_GRIPPER_JOINT_POS}:1 per arm in "
        "vector order; the keys must be contiguous)"
    )


def _default_image_key(feature: str, is_depth: bool) -> str:
    camera = N.camera_of_image_key(feature) or feature.rsplit(".", 1)[-1]
    if is_depth:
        return K.depth_image_key(camera.removesuffix(N.DEPTH_CAMERA_SUFFIX))
    return K.rgb_image_key(camera)


def resolve_mapping(
    features: Mapping[str, dict],
    depth_keys: Sequence[str],
    rmb_meta: Mapping[str, Any] | None,
    overrides: MappingOverrides | None = None,
) -> KeyMapping:
    """The mapping for a dataset with LeRobot ``features`` (see the module docstring)."""
    overrides = overrides or MappingOverrides()
    rmb_meta = rmb_meta or {}
    images: dict[str, str] = {}
    for feature, ft in features.items():
        if ft.get("dtype") not in ("video", "image"):
            continue
        is_depth = feature in depth_keys
        if feature in overrides.cameras:
            camera = overrides.cameras[feature]
            images[feature] = K.depth_image_key(camera) if is_depth else K.rgb_image_key(camera)
        else:
            images[feature] = rmb_meta.get("images", {}).get(feature) or _default_image_key(
                feature, is_depth
            )

    mapped: dict[str, str] = {}
    skipped = []
    for feature in features:
        if feature in images or feature in (N.STATE, N.ACTION_KEY) or feature in DEFAULT_FEATURES:
            continue
        key = (
            overrides.keys.get(feature)
            or rmb_meta.get("features", {}).get(feature)
            or N.rmb_key_of_feature(feature)
            or (K.REWARD if feature == REWARD else None)
        )
        if key is None:
            skipped.append(feature)
        elif key not in mapped.values():
            mapped[feature] = key
    if skipped:
        logger.warning("features without an RMB key, not converted (see --key-map): %s", skipped)

    state = _vector(N.STATE, features, overrides.state_keys, rmb_meta.get("state_keys"))
    action = _vector(N.ACTION_KEY, features, overrides.action_keys, rmb_meta.get("action_keys"))
    return KeyMapping(state=state, action=action, images=images, features=mapped)

"""Check an episode's HDF5 attributes before they are copied into ``meta/rmb.json``.

Tools read them back from there (DP3 builds point clouds from ``<camera>_depth_image_fovy`` and
``<camera>_depth_image_pose``, ``from-lerobot`` restores the episodes from them), so a bad value
must stop the conversion with the file and attribute named, not travel on: every attribute RMB
defines is checked against what RMB writes, and any other attribute must at least be a plain JSON
value (strings, finite numbers, booleans and lists of them).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from rmb_lerobot import keys as K
from rmb_lerobot.errors import RmbFormatError
from rmb_lerobot.pointcloud import checked_camera_pose

FOVY_RANGE = (0.0, 180.0)  # degrees, both ends excluded
_STRING_ATTRS = (K.ATTR_TASK_DESC, K.ATTR_DEMO_NAME, K.ATTR_ENV, K.ATTR_VERSION, K.ATTR_FORMAT)


class _Bad(ValueError):
    """An attribute value that is not what was expected (message says what was)."""


def _plain(value: Any) -> Any:
    """numpy scalars/arrays as Python values and lists."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, tuple):
        return list(value)
    return value


def _string(value: Any) -> str:
    if not isinstance(value, str):
        raise _Bad("expected a string")
    return value


def _string_list(value: Any) -> list[str]:
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise _Bad("expected a list of strings")
    return value


def _integer(value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise _Bad("expected an integer")
    return int(value)


def _fovy(value: Any) -> float:
    low, high = FOVY_RANGE
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise _Bad(f"expected the vertical field of view in degrees, in ({low:g}, {high:g})")
    fovy = float(value)
    if not (math.isfinite(fovy) and low < fovy < high):
        raise _Bad(f"expected the vertical field of view in degrees, in ({low:g}, {high:g})")
    return fovy


def _camera_pose(value: Any) -> list[list[float]]:
    try:
        return checked_camera_pose(value, "the pose")
    except ValueError as error:
        raise _Bad(f"expected a 4x4 world-from-camera transform: {error}") from None


def _json_value(value: Any) -> Any:
    if isinstance(value, list):
        return [_json_value(v) for v in value]
    if isinstance(value, str | bool | numbers.Integral):
        return value if isinstance(value, str | bool) else int(value)
    if isinstance(value, numbers.Real):
        if not math.isfinite(float(value)):
            raise _Bad("expected a finite number")
        return float(value)
    raise _Bad("expected a string, a finite number, a boolean or a list of them")


def _checker(name: str):
    if name in _STRING_ATTRS:
        return _string
    if name in K.STRING_LIST_ATTRS:
        return _string_list
    if name == K.ATTR_WORLD_IDX:
        return _integer
    if name.endswith(K.FOVY_ATTR_SUFFIX):
        return _fovy
    if name.endswith(K.DEPTH_IMAGE_SUFFIX + K.CAMERA_POSE_ATTR_SUFFIX):
        return _camera_pose
    return _json_value


def checked_attrs(attrs: Mapping[str, Any], path: str | Path) -> dict[str, Any]:
    """``attrs`` as JSON values, or :class:`RmbFormatError` naming the file and attribute."""
    checked = {}
    for name, value in attrs.items():
        plain = _plain(value)
        try:
            checked[name] = _checker(name)(plain)
        except _Bad as exc:
            raise RmbFormatError(
                f"attribute {name!r} is {plain!r}: {exc}", path=path, key=name
            ) from None
    return checked

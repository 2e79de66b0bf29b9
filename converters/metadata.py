"""``meta/rmb.json``: what LeRobot's metadata has no place for.

LeRobot's ``info.json`` is parsed into a fixed dataclass (unknown fields are dropped with a
warning), so RMB's episode attributes live in their own file next to it, uploaded with the
dataset: per episode the source file and every HDF5 attribute (env, world_idx, demo_name,
task_desc, camera_names, ``<camera>_depth_image_fovy``, ...), plus the dataset-wide key mapping
(which RMB keys make up ``observation.state`` and ``action``, which feature holds which RMB key),
the robot layout and the true frame rate. :mod:`.lerobot_to_rmb` reads it back.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

from rmb_lerobot import lerobot_names as N
from rmb_lerobot.converters.plan import ConversionPlan
from rmb_lerobot.episode.digest import ATTR_VIDEO_SHA256

SCHEMA_VERSION = 1


def _jsonable(value: Any) -> Any:
    """HDF5 attribute values (numpy scalars/arrays) as JSON values."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    return value


def _rate(rate: Fraction) -> dict[str, Any]:
    return {"hz": float(rate), "fraction": f"{rate.numerator}/{rate.denominator}"}


def rmb_metadata(plan: ConversionPlan) -> dict[str, Any]:
    """The content of ``meta/rmb.json`` for a finished conversion."""
    schema = plan.schema
    layout = schema.layout
    return {
        "schema_version": SCHEMA_VERSION,
        "env": plan.env,
        "robot_layout": {
            "num_joints": layout.num_joints,
            "num_grippers": layout.num_grippers,
            "num_eefs": layout.num_eefs,
        },
        "rate": {
            "source": _rate(plan.source_rate),
            "dataset": _rate(plan.rate),
            "skip": plan.skip,
        },
        "state_keys": list(schema.state_keys),
        "action_keys": list(schema.action_keys),
        "features": {N.rmb_feature_key(key): key for key in schema.extra_keys},
        "images": dict(schema.image_keys()),
        "episodes": [
            {
                "episode_index": index,
                "source": ep.path.name,
                "length": ep.length,
                "measured_rate_hz": ep.measured_rate,
                "attrs": {
                    name: _jsonable(value)
                    for name, value in ep.attrs.items()
                    if name != ATTR_VIDEO_SHA256  # the source's files, not the dataset's
                },
            }
            for index, ep in enumerate(plan.episodes)
        ],
    }


def write_rmb_metadata(root: Path, plan: ConversionPlan) -> Path:
    path = Path(root) / N.RMB_METADATA_PATH
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(rmb_metadata(plan), indent=2, allow_nan=False) + "\n")
    return path


def read_rmb_metadata(root: Path) -> Mapping[str, Any] | None:
    """The ``meta/rmb.json`` of a dataset, or None for datasets from other sources."""
    path = Path(root) / N.RMB_METADATA_PATH
    if not path.is_file():
        return None
    return json.loads(path.read_text())

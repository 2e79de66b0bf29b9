"""``meta/modality.json``: GR00T's map of the concatenated state/action vectors.

GR00T (Isaac-GR00T's LeRobot flavour) reads LeRobot datasets plus this file, which splits
``observation.state`` and ``action`` into named groups by index range, names the camera videos
and points the language annotation at the task index. Joint keys split into ``arm`` and
``gripper`` (GR00T's own embodiment configs use these groups); other keys are one group each,
named after the quantity. Depth videos are not listed: GR00T's video modality is RGB.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from rmb_lerobot import keys as K
from rmb_lerobot import lerobot_names as N
from rmb_lerobot.converters.schema import DatasetSchema, uses_policy_view

TASK_ANNOTATION = "human.task_description"
_TASK_INDEX = "task_index"  # LeRobot's per-frame task column


def _groups(schema: DatasetSchema, keys: tuple[str, ...], source: str, is_action: bool) -> dict:
    groups: dict[str, dict[str, Any]] = {}
    start = 0

    def add(name: str, size: int, key: str, **extra: Any) -> None:
        nonlocal start
        unique, n = name, 2
        while unique in groups:
            unique, n = f"{name}_{n}", n + 1
        group = {"start": start, "end": start + size, "original_key": source, **extra}
        if is_action:
            group["absolute"] = not K.is_relative_key(key)
        groups[unique] = group
        start += size

    grippers = schema.layout.num_grippers
    for key in keys:
        dim = schema.dims[key]
        spec = K.KEYS.get(key)
        quantity = spec.quantity.value if spec is not None and spec.quantity else key
        if spec is not None and spec.quantity is K.Quantity.JOINT_POS and 0 < grippers < dim:
            add("arm", dim - grippers, key)
            add("gripper", grippers, key)
        elif uses_policy_view(key):
            for eef in range(dim // 7):
                suffix = "" if dim == 7 else f"_{eef}"
                add(f"{quantity}_position{suffix}", 3, key)
                add(f"{quantity}_rotation{suffix}", 6, key, rotation_type="rotation_6d")
        else:
            add(quantity, dim, key)
    return groups


def modality(schema: DatasetSchema) -> dict[str, Any]:
    """The content of ``meta/modality.json`` for a dataset with ``schema``."""
    return {
        "state": _groups(schema, schema.state_keys, N.STATE, is_action=False),
        "action": _groups(schema, schema.action_keys, N.ACTION_KEY, is_action=True),
        "video": {camera: {"original_key": N.image_key(camera)} for camera in schema.cameras},
        "annotation": {TASK_ANNOTATION: {"original_key": _TASK_INDEX}},
    }


def write_modality(root: Path, schema: DatasetSchema) -> Path:
    path = Path(root) / N.GR00T_MODALITY_PATH
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(modality(schema), indent=2) + "\n")
    return path

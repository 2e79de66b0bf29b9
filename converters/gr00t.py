"""``meta/modality.json``: GR00T's map of the concatenated state/action vectors.

GR00T (Isaac-GR00T's LeRobot flavour) reads LeRobot datasets plus this file, which splits
``observation.state`` and ``action`` into named groups by index range, names the camera videos
and points the language annotation at the task index. Joint keys split into ``arm`` and
``gripper`` (GR00T's own embodiment configs use these groups); other keys are one group each,
named after the quantity. Depth videos are not listed: GR00T's video modality is RGB.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from rmb_lerobot import keys as K
from rmb_lerobot import lerobot_names as N
from rmb_lerobot.converters.schema import DatasetSchema, uses_policy_view

TASK_ANNOTATION = "human.task_description"
_TASK_INDEX = "task_index"  # LeRobot's per-frame task column


def _groups(
    schema: DatasetSchema,
    keys: tuple[str, ...],
    source: str,
    is_action: bool,
    arm_names: Sequence[str] | None,
) -> dict:
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

    arms = schema.layout.arm_groups()
    for key in keys:
        dim = schema.dims[key]
        spec = K.KEYS.get(key)
        quantity = spec.quantity.value if spec is not None and spec.quantity else key
        is_joints = spec is not None and spec.quantity is K.Quantity.JOINT_POS
        if is_joints and dim == schema.layout.num_joints and 0 < schema.layout.num_grippers < dim:
            for i, (joints, grippers) in enumerate(arms):
                add(_group_name("arm", i, len(arms), arm_names), len(joints), key)
                add(_group_name("gripper", i, len(arms), arm_names), len(grippers), key)
        elif uses_policy_view(key):
            for i in range(dim // 7):
                for part, size, extra in (
                    ("position", 3, {}),
                    ("rotation", 6, {"rotation_type": "rotation_6d"}),
                ):
                    name = _group_name(f"{quantity}_{part}", i, dim // 7, arm_names)
                    add(name, size, key, **extra)
        else:
            add(quantity, dim, key)
    return groups


def _group_name(base: str, arm: int, count: int, arm_names: Sequence[str] | None) -> str:
    """``base`` for one arm; of several, prefixed by the robot's arm name (``left_arm``,
    ``right_gripper``: GR00T's bimanual convention) or, without names, ``<base>_<arm>``."""
    if count == 1:
        return base
    if arm_names is not None and len(arm_names) == count:
        return f"{arm_names[arm]}_{base}"
    return f"{base}_{arm}"


def modality(schema: DatasetSchema, arm_names: Sequence[str] | None = None) -> dict[str, Any]:
    """The content of ``meta/modality.json`` for a dataset with ``schema``; ``arm_names``
    (the robot record's, in joint-vector order) name a multi-arm robot's groups."""
    return {
        "state": _groups(schema, schema.state_keys, N.STATE, False, arm_names),
        "action": _groups(schema, schema.action_keys, N.ACTION_KEY, True, arm_names),
        "video": {camera: {"original_key": N.image_key(camera)} for camera in schema.cameras},
        "annotation": {TASK_ANNOTATION: {"original_key": _TASK_INDEX}},
    }


def write_modality(
    root: Path, schema: DatasetSchema, arm_names: Sequence[str] | None = None
) -> Path:
    path = Path(root) / N.GR00T_MODALITY_PATH
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(modality(schema, arm_names), indent=2) + "\n")
    return path

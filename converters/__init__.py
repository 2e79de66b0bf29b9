"""Conversions between RMB episodes and LeRobotDataset v3 (``rmb-convert``).

- :func:`to_lerobot`: RMB episodes -> one LeRobotDataset (``rmb-convert to-lerobot``).
- :func:`from_lerobot`: any local LeRobotDataset v3 -> RMB episodes (``rmb-convert from-lerobot``).
- :func:`push_dataset`: upload a converted dataset with LeRobot's ``push_to_hub``.

Imported lazily: ``import rmb_lerobot.converters`` does not import LeRobot's dataset code.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

_LAZY = {
    "ConvertOptions": "rmb_lerobot.converters.plan",
    "MappingOverrides": "rmb_lerobot.converters.lerobot_mapping",
    "from_lerobot": "rmb_lerobot.converters.from_lerobot",
    "push_dataset": "rmb_lerobot.converters.hub",
    "to_lerobot": "rmb_lerobot.converters.to_lerobot",
}
__all__ = ["ConvertOptions", "MappingOverrides", "from_lerobot", "push_dataset", "to_lerobot"]

if TYPE_CHECKING:
    from rmb_lerobot.converters.from_lerobot import from_lerobot
    from rmb_lerobot.converters.hub import push_dataset
    from rmb_lerobot.converters.lerobot_mapping import MappingOverrides
    from rmb_lerobot.converters.plan import ConvertOptions
    from rmb_lerobot.converters.to_lerobot import to_lerobot


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(importlib.import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'rmb_lerobot.converters' has no attribute {name!r}")

"""Conversions between RMB episodes and LeRobotDataset v3 (``rmb-convert``).

- :func:`to_lerobot`: RMB episodes -> one LeRobotDataset (``rmb-convert to-lerobot``).
- :func:`from_lerobot`: any local LeRobotDataset v3 -> RMB episodes (``rmb-convert from-lerobot``).
- :func:`push_dataset`: upload a converted dataset with LeRobot's ``push_to_hub``.

Imported lazily: ``import rmb_lerobot.converters`` does not import LeRobot's dataset code.
No lazy name may also be a submodule name: importing a submodule sets the package attribute
of that name to the module, which would then shadow the function (hence the modules
:mod:`.rmb_to_lerobot` and :mod:`.lerobot_to_rmb` for the two functions).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

_LAZY = {
    "ConvertOptions": "rmb_lerobot.converters.plan",
    "MappingOverrides": "rmb_lerobot.converters.lerobot_mapping",
    "from_lerobot": "rmb_lerobot.converters.lerobot_to_rmb",
    "push_dataset": "rmb_lerobot.converters.hub",
    "to_lerobot": "rmb_lerobot.converters.rmb_to_lerobot",
}
__all__ = ["ConvertOptions", "MappingOverrides", "from_lerobot", "push_dataset", "to_lerobot"]

if TYPE_CHECKING:
    from rmb_lerobot.converters.hub import push_dataset
    from rmb_lerobot.converters.lerobot_mapping import MappingOverrides
    from rmb_lerobot.converters.lerobot_to_rmb import from_lerobot
    from rmb_lerobot.converters.plan import ConvertOptions
    from rmb_lerobot.converters.rmb_to_lerobot import to_lerobot


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(importlib.import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'rmb_lerobot.converters' has no attribute {name!r}")

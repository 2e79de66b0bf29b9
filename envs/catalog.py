"""Task and expert classes by short name, loaded from the env table.

The table itself is :data:`rmb_lerobot.envs.registry.ENVS` (names only, no MuJoCo import);
this module imports every task and expert, for scripts and tests that iterate over them.
"""

from __future__ import annotations

from rmb_lerobot.envs.registry import ENVS

TASKS = {name: entry.load_task_class() for name, entry in ENVS.items()}
EXPERTS = {name: entry.load_expert_class() for name, entry in ENVS.items()}

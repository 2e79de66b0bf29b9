"""Tasks and their scripted experts by short name: the table scripts and tests iterate over."""

from __future__ import annotations

from rmb_lerobot.envs.experts.cabinet import CabinetHingeExpert, CabinetSlideExpert
from rmb_lerobot.envs.experts.door import DoorExpert
from rmb_lerobot.envs.experts.insert import InsertExpert
from rmb_lerobot.envs.experts.toolbox import ToolboxExpert
from rmb_lerobot.envs.tasks.cabinet import CabinetHingeTask, CabinetSlideTask
from rmb_lerobot.envs.tasks.door import DoorTask
from rmb_lerobot.envs.tasks.insert import InsertTask
from rmb_lerobot.envs.tasks.toolbox import ToolboxTask

TASKS = {
    "insert": InsertTask,
    "door": DoorTask,
    "toolbox": ToolboxTask,
    "cabinet_hinge": CabinetHingeTask,
    "cabinet_slide": CabinetSlideTask,
}
EXPERTS = {
    "insert": InsertExpert,
    "door": DoorExpert,
    "toolbox": ToolboxExpert,
    "cabinet_hinge": CabinetHingeExpert,
    "cabinet_slide": CabinetSlideExpert,
}

"""Scripted expert for the Insert task: bring the held peg above the hole, then lower it in."""

from __future__ import annotations

from enum import Enum

import numpy as np

from rmb_lerobot.envs.experts.base import ScriptedExpert, Waypoint
from rmb_lerobot.envs.tasks.insert import HOLE, HOLE_DEPTH, PEG, PEG_HALF_LENGTH


class Phase(Enum):
    ABOVE = "above"
    INSERT = "insert"


class InsertExpert(ScriptedExpert):
    """Tool point: the peg's lower end. Phases: align above the hole, then descend."""

    clearance = 0.03  # peg end above the hole's rim while aligning (m)
    align_tol = 0.002  # xy alignment before descending (m)
    final_height = 0.004  # peg end above the hole floor at the end (m)

    def on_reset(self) -> None:
        self.phase = Phase.ABOVE
        eef_pos, eef_rot = self.eef_world()
        self._offset = eef_rot.inv().apply(self.measured_tool() - eef_pos)
        self._rot = eef_rot  # keep the peg vertical, as it starts

    def tool_offset(self) -> np.ndarray:
        return self._offset

    def measured_tool(self) -> np.ndarray:
        peg, rot = self.scene.body_pose(PEG)
        axis = rot[:, 2]
        ends = (peg + PEG_HALF_LENGTH * axis, peg - PEG_HALF_LENGTH * axis)
        return min(ends, key=lambda end: end[2]).copy()

    def waypoint(self) -> Waypoint:
        hole = self.scene.body_pose(HOLE)[0]
        gripper = self.env.home_command[self.gripper_index]
        above = np.array([hole[0], hole[1], hole[2] + HOLE_DEPTH + self.clearance])
        if self.phase is Phase.ABOVE:
            if self.reached(above, self.align_tol, xy_only=True) and self.reached(above, 0.01):
                self.phase = Phase.INSERT
            else:
                return Waypoint(above, self._rot, gripper)
        inside = np.array([hole[0], hole[1], hole[2] + self.final_height])
        return Waypoint(inside, self._rot, gripper)

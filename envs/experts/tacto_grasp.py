"""Scripted expert for TactoSawyerGrasp: pinch the box between the DIGIT pads and lift it."""

from __future__ import annotations

from enum import Enum

import numpy as np

from rmb_lerobot.envs.experts.base import GripperExpert, Waypoint
from rmb_lerobot.envs.tasks.tacto_grasp import BOX, BOX_HALF_SIZE


class Phase(Enum):
    ABOVE = "above"
    DESCEND = "descend"
    CLOSE = "close"
    LIFT = "lift"


class TactoGraspExpert(GripperExpert):
    """Tool point: the pinch point between the pads. Phases: above the box with the gripper
    open, down until the pads straddle the box's upper half, close (the pads squeeze its 3 cm
    side, as the hand starts), lift to ``lift_z`` and hold still there."""

    approach_height = 0.06  # pinch point above the box top before descending (m)
    grasp_below_top = 0.025  # pinch point below the box's top face when closing (m)
    lift_z = 0.2  # pinch point height to hold the box at (m); success needs its centre > 0.1
    grasp_speed = 0.05  # m/s for the last centimetres of the descent

    def on_reset(self) -> None:
        super().on_reset()
        self.phase = Phase.ABOVE
        self._rot = self.eef_world()[1]  # keep the hand as it starts: pads across the box's y

    def _grasp_point(self) -> np.ndarray:
        box = self.scene.body_pose(BOX)[0]
        top = box[2] + BOX_HALF_SIZE[2]
        return np.array([box[0], box[1], top - self.grasp_below_top])

    def waypoint(self) -> Waypoint:
        self._track_tool_speed()
        if self.phase is Phase.ABOVE:
            grasp = self._grasp_point()
            target = grasp + np.array([0.0, 0.0, self.approach_height + self.grasp_below_top])
            if self.reached(target, 0.01):
                self.phase = Phase.DESCEND
            return Waypoint(target, self._rot, self.open_gripper)
        if self.phase is Phase.DESCEND:
            grasp = self._grasp_point()
            if self._arrived(grasp, 0.004):
                self.phase = Phase.CLOSE
                self._count = 0
                self._grasp = grasp.copy()
            return Waypoint(self._slowly(grasp, self.grasp_speed), self._rot, self.open_gripper)
        if self.phase is Phase.CLOSE:
            if self._gripper_settled():
                self.phase = Phase.LIFT
            return Waypoint(self._grasp, self._rot, self.closed_gripper)
        target = np.array([*self._grasp[:2], self.lift_z])
        return Waypoint(target, self._rot, self.closed_gripper)

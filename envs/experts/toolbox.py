"""Scripted expert for the Toolbox task: grasp the handle from above, carry the box, set it down.

The gripper points down with its fingers closing across the handle bar (horizontal,
perpendicular to the bar), descends until the pinch point is on the bar's axis, closes, lifts
the box clear of the table, carries it over the mat and lowers it until it rests there, then
lets go and backs off upwards. While carrying, the targets are placed so that the *box* (not
the hand) ends up centred on the mat: the measured offset between the pinch point and the
toolbox origin is added to the mat's position, which absorbs any slip or swing of the box in
the grasp. The lowering target is frozen once the box hangs still over the mat, so the hand
does not chase the box when it touches down; the last centimetres to the bar and to the mat
are covered slowly, which keeps the integral correction from overshooting the grasp height.
"""

from __future__ import annotations

from enum import Enum

import numpy as np
from scipy.spatial.transform import Rotation

from rmb_lerobot.envs.experts.base import GripperExpert, Waypoint, top_down_rotation
from rmb_lerobot.envs.tasks.toolbox import HANDLE, MAT, MAT_TOP, TOOLBOX


class Phase(Enum):
    ABOVE = "above"
    DESCEND = "descend"
    CLOSE = "close"
    LIFT = "lift"
    CARRY = "carry"
    LOWER = "lower"
    RELEASE = "release"
    RETREAT = "retreat"


class ToolboxExpert(GripperExpert):
    """Tool point: the gripper's pinch point."""

    approach_height = 0.08  # pre-grasp height of the pinch point above the bar (m)
    grasp_depth = 0.0  # pinch point below the bar's axis when closing (m)
    carry_clearance = 0.06  # toolbox bottom above the mat top while carrying (m)
    place_height = 0.0005  # toolbox bottom above the mat top at the end of lowering (m)
    grasp_speed, place_speed = 0.05, 0.03  # m/s: the last ``slow_zone`` to the bar, the mat

    def on_reset(self) -> None:
        super().on_reset()
        self.phase = Phase.ABOVE
        self._grasp = np.zeros(3)  # pinch target while closing
        self._place = np.zeros(3)  # pinch target while lowering onto the mat
        self._release = np.zeros(3)  # pinch target while opening
        _, eef_rot = self.eef_world()
        self._rot = self._grasp_rotation(eef_rot)

    def _grasp_rotation(self, current: Rotation) -> Rotation:
        """Fingers across the handle bar (perpendicular to its axis in the horizontal plane)."""
        bar_axis = self.scene.geom_pose(HANDLE)[1][:, 1]
        return top_down_rotation(np.cross([0.0, 0.0, 1.0], bar_axis), current)

    # ------------------------------------------------------------------ helpers
    def _over_mat(self, bottom_above_mat_top: float) -> np.ndarray:
        """Pinch target that puts the toolbox origin over the mat centre at the given height."""
        held = self.measured_tool() - self.scene.body_pose(TOOLBOX)[0]
        mat = self.scene.body_pose(MAT)[0]
        return mat + held + np.array([0.0, 0.0, MAT_TOP + bottom_above_mat_top])

    def _box_over_mat(self, tol: float) -> bool:
        box, mat = self.scene.body_pose(TOOLBOX)[0], self.scene.body_pose(MAT)[0]
        return bool(np.max(np.abs(box[:2] - mat[:2])) < tol)

    # ------------------------------------------------------------------ phases
    def waypoint(self) -> Waypoint:
        self._track_tool_speed()
        grasp = self.scene.geom_pose(HANDLE)[0] - np.array([0.0, 0.0, self.grasp_depth])
        if self.phase is Phase.ABOVE:
            target = grasp + np.array([0.0, 0.0, self.approach_height])
            if self.reached(target, 0.01):
                self.phase = Phase.DESCEND
            return Waypoint(target, self._rot, self.open_gripper)
        if self.phase is Phase.DESCEND:
            if self._arrived(grasp, 0.003):
                self.phase = Phase.CLOSE
                self._grasp = grasp.copy()
            return Waypoint(self._slowly(grasp, self.grasp_speed), self._rot, self.open_gripper)
        if self.phase is Phase.CLOSE:
            if self._gripper_settled():
                self.phase = Phase.LIFT
            return Waypoint(self._grasp, self._rot, self.closed_gripper)
        if self.phase is Phase.LIFT:
            target = np.array([*self._grasp[:2], self._over_mat(self.carry_clearance)[2]])
            if self.reached(target, 0.01):
                self.phase = Phase.CARRY
            return Waypoint(target, self._rot, self.closed_gripper)
        if self.phase is Phase.CARRY:
            target = self._over_mat(self.carry_clearance)
            if self._arrived(target, 0.01) and self._box_over_mat(0.005):
                self.phase = Phase.LOWER
                self._place = self._over_mat(self.place_height)
            return Waypoint(target, self._rot, self.closed_gripper)
        if self.phase is Phase.LOWER:
            if self.env.task.is_success(self.scene):
                self.phase = Phase.RELEASE
                self._count = 0
                self._release = self._ref_pos.copy()
            target = self._slowly(self._place, self.place_speed)
            return Waypoint(target, self._rot, self.closed_gripper)
        if self.phase is Phase.RELEASE:
            if self._gripper_settled():
                self.phase = Phase.RETREAT
            return Waypoint(self._release, self._rot, self.open_gripper)
        target = self._release + np.array([0.0, 0.0, self.approach_height])
        return Waypoint(target, self._rot, self.open_gripper)

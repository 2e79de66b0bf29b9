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

import numpy as np
from scipy.spatial.transform import Rotation

from rmb_lerobot.envs.experts.base import top_down_rotation
from rmb_lerobot.envs.experts.carry import CarryExpert, CarryPhase
from rmb_lerobot.envs.tasks.toolbox import HANDLE, MAT, MAT_TOP, TOOLBOX

Phase = CarryPhase  # Toolbox's phases are the carry sequence's


class ToolboxExpert(CarryExpert):
    """Tool point: the gripper's pinch point; the carry sequence with Toolbox's hooks."""

    approach_height = 0.08  # pre-grasp height of the pinch point above the bar (m)
    grasp_depth = 0.0  # pinch point below the bar's axis when closing (m)
    carry_clearance = 0.06  # toolbox bottom above the mat top while carrying (m)
    place_height = 0.0005  # toolbox bottom above the mat top at the end of lowering (m)
    grasp_speed, place_speed = 0.05, 0.03  # m/s: the last ``slow_zone`` to the bar, the mat

    def on_reset(self) -> None:
        super().on_reset()
        _, eef_rot = self.eef_world()
        self.rot = self._grasp_rotation(eef_rot)

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

    # ------------------------------------------------------------------ carry hooks
    def grasp_point(self) -> np.ndarray:
        """On the handle bar's axis (``grasp_depth`` below it)."""
        return self.scene.geom_pose(HANDLE)[0] - np.array([0.0, 0.0, self.grasp_depth])

    def above_grasp(self, grasp: np.ndarray) -> np.ndarray:
        """``approach_height`` above the bar."""
        return grasp + np.array([0.0, 0.0, self.approach_height])

    def lift_target(self, grasp: np.ndarray) -> np.ndarray:
        """Straight up until the box's bottom is ``carry_clearance`` above the mat top."""
        return np.array([*grasp[:2], self._over_mat(self.carry_clearance)[2]])

    def carry_target(self) -> np.ndarray:
        """The box over the mat centre, ``carry_clearance`` above it."""
        return self._over_mat(self.carry_clearance)

    def ready_to_lower(self, target: np.ndarray) -> bool:
        """The hand at rest over the mat and the box hanging centred over it."""
        return self._arrived(target, 0.01) and self._box_over_mat(0.005)

    def place_target(self) -> np.ndarray:
        """The box's bottom ``place_height`` above the mat top."""
        return self._over_mat(self.place_height)

    def placed(self) -> bool:
        """The box rests on the mat (the task's success test)."""
        return bool(self.env.task.is_success(self.scene))

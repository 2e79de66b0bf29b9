"""Scripted expert for TactoSawyerSpoon: pinch the spoon's upper end, sort it into its box.

Privileged: it reads the spoon's pose from the simulator (where its upper end is) and the world
index (the goal box: red for bowl down, green for bowl up), which a learned policy has to feel
with the fingertip sensors instead.

Measured (``reset(seed=i, options={"world_idx": i % 2})``, no cameras): 100 / 100 episodes in
``action_mode="joint"`` (mean 225.0 steps to success: 240 in world 0, 210 in world 1) and
100 / 100 in ``"eef_rel"`` (mean 222.6); with a 0.03 m random shift 50 / 50 in each mode (mean
222 steps, at most 245).
"""

from __future__ import annotations

from enum import Enum

import numpy as np

from rmb_lerobot.envs.experts.base import GripperExpert, Waypoint, top_down_rotation
from rmb_lerobot.envs.tasks.tacto_spoon import (
    BOWL_HALF_LENGTH,
    BOX_FLOOR_TOP,
    BOX_WALL_TOP,
    GOAL_BOXES,
    HANDLE_END,
    SPOON,
    SPOON_LENGTH,
    SPOON_THICKNESS,
)


class Phase(Enum):
    ABOVE = "above"
    DESCEND = "descend"
    CLOSE = "close"
    LIFT = "lift"
    CARRY = "carry"
    LOWER = "lower"
    RELEASE = "release"
    RETREAT = "retreat"


class TactoSpoonExpert(GripperExpert):
    """Tool point: the pinch point between the pads. Phases: above the spoon's upper end (the
    handle's tip in world 0, the bowl's rim in world 1) with the gripper open as RMB's pre-motion
    (0.04), the hand turned so the pads close across the spoon's thickness; down until the pinch
    point is ``grasp_depth`` below that end (the 30 mm pads then cover the top 27 mm: the 9 mm
    handle or the 36 mm wide end of the bowl); close fully (20 N; RMB's pre-motion closes to
    0.01, which squeezes a 4.8 mm spoon with the same force); lift until the spoon's lower end
    clears the start box's walls; carry it over the goal box; lower it until its lower end is
    just above the box floor; open; retreat upwards.

    The spoon hangs from the pads as it was held (it may lean a few degrees), so the carry and
    the lowering aim its measured middle at the box centre and its measured lower end at the
    floor, each measured once when the phase starts (following the swinging spoon continuously
    would feed its swing back into the hand).
    """

    release_gripper = 0.04  # RMB's pre-motion opening: a 52 mm pad gap around a 5 mm spoon
    approach_height = 0.06  # pinch point above the grasp point before descending (m)
    grasp_depth = 0.012  # pinch point below the spoon's upper end along the spoon (m)
    wall_clearance = 0.06  # the spoon's lower end above the walls' tops when carried (m)
    release_height = 0.02  # the spoon's lower end above the goal box's floor when let go (m)
    retreat_height = 0.1  # pinch point rise after letting go (m)
    grasp_speed = 0.05  # m/s for the last centimetres of the descent and of the lowering

    def on_reset(self) -> None:
        super().on_reset()
        self.phase = Phase.ABOVE
        self._goal = np.asarray(self.scene.body_pose(GOAL_BOXES[self.env.task.world_idx])[0])
        _, spoon_rot = self.scene.body_pose(SPOON)
        # Pads closing along the spoon's face normal (across its 4.8 mm thickness).
        self._rot = top_down_rotation(spoon_rot[:, 2], self.eef_world()[1])
        self._grasp = self._grasp_point()
        self._lift_z = BOX_WALL_TOP + self.wall_clearance + SPOON_LENGTH - self.grasp_depth
        self._target = self._grasp.copy()

    def _spoon_point(self, along: float) -> np.ndarray:
        """World position of the spoon's mid-thickness point at ``along`` on its frame's y axis
        (0: the bowl's centre, :data:`HANDLE_END`: the handle's tip)."""
        pos, rot = self.scene.body_pose(SPOON)
        return pos + rot @ np.array([0.0, along, SPOON_THICKNESS / 2])

    def _ends(self) -> tuple[np.ndarray, np.ndarray]:
        """The spoon's two ends on its axis, upper first."""
        handle = self._spoon_point(HANDLE_END)
        bowl = self._spoon_point(-BOWL_HALF_LENGTH)
        return (handle, bowl) if handle[2] > bowl[2] else (bowl, handle)

    def _grasp_point(self) -> np.ndarray:
        """``grasp_depth`` below the upper end, along the spoon."""
        upper, lower = self._ends()
        return upper + (lower - upper) * (self.grasp_depth / SPOON_LENGTH)

    def waypoint(self) -> Waypoint:
        self._track_tool_speed()
        if self.phase is Phase.ABOVE:
            self._grasp = self._grasp_point()
            target = self._grasp + np.array([0.0, 0.0, self.approach_height])
            if self.reached(target, 0.01):
                self.phase = Phase.DESCEND
            return Waypoint(target, self._rot, self.release_gripper)
        if self.phase is Phase.DESCEND:
            self._grasp = self._grasp_point()
            if self._arrived(self._grasp, 0.003):
                self.phase = Phase.CLOSE
                self._count = 0
            target = self._slowly(self._grasp, self.grasp_speed)
            return Waypoint(target, self._rot, self.release_gripper)
        if self.phase is Phase.CLOSE:
            if self._gripper_settled():
                self.phase = Phase.LIFT
                self._target = np.array([*self._grasp[:2], self._lift_z])
            return Waypoint(self._grasp, self._rot, self.closed_gripper)
        if self.phase is Phase.LIFT:
            if self.reached(self._target, 0.01):
                self.phase = Phase.CARRY
                middle = np.mean(self._ends(), axis=0)
                self._target = self._target.copy()
                self._target[:2] = self._goal[:2] + self.measured_tool()[:2] - middle[:2]
            return Waypoint(self._target, self._rot, self.closed_gripper)
        if self.phase is Phase.CARRY:
            if self._arrived(self._target, 0.01):
                self.phase = Phase.LOWER
                _, lower = self._ends()
                drop = lower[2] - (BOX_FLOOR_TOP + self.release_height)
                self._target = self.measured_tool() - np.array([0.0, 0.0, drop])
            return Waypoint(self._target, self._rot, self.closed_gripper)
        if self.phase is Phase.LOWER:
            if self._arrived(self._target, 0.005):
                self.phase = Phase.RELEASE
                self._count = 0
            target = self._slowly(self._target, self.grasp_speed)
            return Waypoint(target, self._rot, self.closed_gripper)
        if self.phase is Phase.RELEASE:
            if self._gripper_settled():
                self.phase = Phase.RETREAT
                self._target = self._target + np.array([0.0, 0.0, self.retreat_height])
            return Waypoint(self._target, self._rot, self.release_gripper)
        return Waypoint(self._target, self._rot, self.release_gripper)

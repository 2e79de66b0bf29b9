"""Scripted expert for TactoSawyerInsert: pull the board out, stand it up, lower it in the slot."""

from __future__ import annotations

from enum import Enum

import numpy as np
from scipy.spatial.transform import Rotation

from rmb_lerobot.envs.experts.base import GripperExpert, Waypoint, top_down_rotation
from rmb_lerobot.envs.tasks.tacto_insert import (
    BOARD,
    BOARD_HALF_SIZE,
    BOX,
    SLOT_FLOOR_Z,
)


class Phase(Enum):
    ABOVE = "above"
    DESCEND = "descend"
    CLOSE = "close"
    PULL = "pull"
    RAISE = "raise"
    STAND = "stand"
    CARRY = "carry"
    ALIGN = "align"
    LOWER = "lower"


def _align_to_vertical(axis: np.ndarray) -> Rotation:
    """The smallest rotation that turns the unit vector ``axis`` onto world +z."""
    up = np.array([0.0, 0.0, 1.0])
    cross = np.cross(axis, up)
    sin, cos = np.linalg.norm(cross), float(axis @ up)
    if sin < 1e-9:
        return Rotation.identity()
    return Rotation.from_rotvec(cross / sin * np.arctan2(sin, cos))


class TactoInsertExpert(GripperExpert):
    """Tool point: the pinch point between the pads, which squeeze the board's 30 mm width.

    Phases: the hand above a point ``grasp_below_top`` below the board's top end (on its axis),
    turned about world y (the grasp axis) by the board's pitch where that is positive (fingers
    along the board), down along the fingers to it, close, pull the board out along its own
    axis (it slides off the block it leans on), up to ``carry_z``, turn the hand about the grasp
    axis by the board's measured lean so the board hangs vertical, over the slot, align the
    board's measured lower end and axis over the slot centre, lower it in until the success
    test holds.

    Why not follow a negative pitch too (worlds 3 and 4, the board's top leaning towards the
    robot): a hand pointing away from the robot straightens the Sawyer's wrist (``right_j5``
    within 0.02 rad of 0 from -20 deg on, 0.27 at -10, 0.53 top-down: the arm's IK followed
    from home to the board), where the damped IK let ``right_j4`` / ``right_j6`` wind up until
    ``right_j4`` hit its limit and the hand could not turn back (world 3 stuck, world 4 knocked
    the board over). There the hand grasps top-down, at up to 40 deg to the board, and stands
    it up by pointing back towards the robot (``right_j5`` grows: the comfortable side); the
    fingers then stay 14.5 mm clear of the box (16.4 mm top-down; measured, worlds 0-4).
    """

    grasp_below_top = 0.04  # pinch point below the board's top end, along the board (m)
    approach = 0.06  # start of the descent along the board, above the grasp point (m)
    grasp_speed = 0.05  # m/s for the last centimetres of the descent
    pull = 0.12  # pull-out along the board's axis (m): its lower end clears the blocks
    carry_z = 0.30  # pinch height while turning and carrying (the board's end 0.13 m below)
    clearance = 0.03  # board's lower end above the box's rim before lowering (m)
    align_tol = 0.002  # board end over the slot centre before lowering (m)
    tilt_tol = np.deg2rad(1.0)  # board axis from vertical before lowering
    lower_speed = 0.06  # m/s while lowering into the slot
    final_depth = 0.004  # board end above the floor at the lowest target (m)

    def on_reset(self) -> None:
        super().on_reset()
        self.phase = Phase.ABOVE
        self._top_down = top_down_rotation(np.array([0.0, 1.0, 0.0]), self.eef_world()[1])
        _, board_rot = self.scene.body_pose(BOARD)
        axis = board_rot[:, 2] if board_rot[2, 2] > 0 else -board_rot[:, 2]
        pitch = float(np.arctan2(axis[0], axis[2]))
        self._grasp_rot = Rotation.from_euler("y", max(pitch, 0.0)) * self._top_down
        self._stand_rot = self._top_down  # until the board's lean in the grasp is measured

    # ------------------------------------------------------------------ board geometry
    def _board_axis(self) -> tuple[np.ndarray, np.ndarray]:
        """The board's centre and its long axis pointing up (world)."""
        pos, rot = self.scene.body_pose(BOARD)
        axis = rot[:, 2]
        return pos, axis if axis[2] > 0 else -axis

    def _board_end(self) -> np.ndarray:
        """Centre of the board's lower end face (world)."""
        pos, axis = self._board_axis()
        return pos - BOARD_HALF_SIZE[2] * axis

    def _grasp_point(self) -> tuple[np.ndarray, np.ndarray]:
        pos, axis = self._board_axis()
        return pos + (BOARD_HALF_SIZE[2] - self.grasp_below_top) * axis, axis

    def _slot_entry(self) -> np.ndarray:
        """Where the board's lower end waits, ``clearance`` above the slot's opening."""
        box = self.scene.body_pose(BOX)[0]
        rim = box[2] - SLOT_FLOOR_Z  # the box is as tall above its centre as the slot is deep
        return np.array([box[0], box[1], rim + self.clearance])

    def _pinch_for_end(self, end_target: np.ndarray) -> np.ndarray:
        """The pinch point that puts the board's lower end at ``end_target``, with the board
        where the hand holds it now."""
        return end_target + (self.pinch_point() - self._board_end())

    # ------------------------------------------------------------------ phases
    def waypoint(self) -> Waypoint:
        self._track_tool_speed()
        open_, closed = self.open_gripper, self.closed_gripper
        if self.phase is Phase.ABOVE:
            grasp, _ = self._grasp_point()
            target = grasp - self.approach * self._grasp_rot.apply([0.0, 0.0, 1.0])
            if self.reached(target, 0.01) and self._rot_close(self._grasp_rot):
                self.phase = Phase.DESCEND
            return Waypoint(target, self._grasp_rot, open_)
        if self.phase is Phase.DESCEND:
            grasp, _ = self._grasp_point()
            if self._arrived(grasp, 0.004):
                self.phase = Phase.CLOSE
                self._count = 0
                self._grasp = grasp.copy()
            return Waypoint(self._slowly(grasp, self.grasp_speed), self._grasp_rot, open_)
        if self.phase is Phase.CLOSE:
            if self._gripper_settled():
                self.phase = Phase.PULL
                _, axis = self._board_axis()
                self._pulled = self._grasp + self.pull * axis
            return Waypoint(self._grasp, self._grasp_rot, closed)
        if self.phase is Phase.PULL:
            if self.reached(self._pulled, 0.01):
                self.phase = Phase.RAISE
            return Waypoint(self._pulled, self._grasp_rot, closed)
        if self.phase is Phase.RAISE:
            target = np.array([*self._pulled[:2], self.carry_z])
            if self.reached(target, 0.01):
                self.phase = Phase.STAND
                self._stand_at = target
                _, axis = self._board_axis()
                self._stand_rot = _align_to_vertical(axis) * self.eef_world()[1]
            return Waypoint(target, self._grasp_rot, closed)
        if self.phase is Phase.STAND:
            if self._rot_close(self._stand_rot):
                self.phase = Phase.CARRY
            return Waypoint(self._stand_at, self._stand_rot, closed)
        if self.phase is Phase.CARRY:
            entry = self._slot_entry()
            target = self._pinch_for_end(entry)
            target[2] = max(target[2], self.carry_z)
            if self.reached(target, 0.01, xy_only=True):
                self.phase = Phase.ALIGN
            return Waypoint(target, self._stand_rot, closed)
        if self.phase is Phase.ALIGN:
            entry = self._slot_entry()
            _, axis = self._board_axis()
            end = self._board_end()
            tilt = float(np.arccos(np.clip(axis[2], -1.0, 1.0)))
            if tilt > self.tilt_tol and self._tool_speed < self.still_speed:
                # Turn the hand by what the board still leans (it may slip in the grasp).
                _, hand = self.eef_world()
                self._stand_rot = _align_to_vertical(axis) * hand
            if (
                tilt <= self.tilt_tol
                and np.linalg.norm(end[:2] - entry[:2]) < self.align_tol
                and self._tool_speed < self.still_speed
            ):
                self.phase = Phase.LOWER
            return Waypoint(self._pinch_for_end(entry), self._stand_rot, closed)
        box = self.scene.body_pose(BOX)[0]
        # The slot floor is 3 mm below the ground (RMB's box sinks 1 cm into it): the board
        # stands on the ground there.
        floor = max(box[2] + SLOT_FLOOR_Z, self.table_z())
        bottom = np.array([box[0], box[1], floor + self.final_depth])
        target = self._pinch_for_end(bottom)
        step = self.lower_speed * self.dt
        delta = target - self._ref_pos
        dist = np.linalg.norm(delta)
        if dist > step:
            target = self._ref_pos + delta * (step / dist)
        return Waypoint(target, self._stand_rot, closed)

    def _rot_close(self, rot: Rotation, tol: float = np.deg2rad(2.0)) -> bool:
        """Whether the reference and the measured hand are within ``tol`` of ``rot``."""
        _, hand = self.eef_world()
        ref_err = (rot * self._ref_rot.inv()).magnitude()
        meas_err = (rot * hand.inv()).magnitude()
        return bool(ref_err < tol and meas_err < tol)

"""Scripted expert for the Cloth task: pinch the hanging cloth's hem and lay it over the board.

The cloth hangs in a vertical plane, so the only pinch that does not push the sheet away is one
with the fingers closing across the sheet and the hand in the sheet's plane. The hand is held
horizontal, pointing along the hem (the board's long axis), which the UR5e reaches from its
start pose (RMB's start pose points the gripper roughly that way):

1. Move below the middle of the hem, on the robot's side, then forward so that the open fingers
   straddle the sheet's plane under the hem. The palm (5.5 cm behind the pads, 3.8 cm around
   the tool axis) must pass under the hem, hence ``below``; the hand keeps the finger
   orientation nearer its start, so it never rolls the fingers through the cloth.
2. Rise until the pads are ``grasp_depth`` above the hem, and close. The palm lifts the cloth
   behind the pads a little on the way up; grasping well above the hem keeps cloth between the
   pads anyway.
3. Lift the hem up along the robot's side of the board to above the board, turning the hand
   to point away from the robot (the hem's direction is out of reach beyond the board). The
   cloth, held up in a loop, usually already meets RMB's success test here (every cloth point
   at most 0.092 m below the board, none pulled towards the robot).
4. Carry the hem over the board to just beyond its far edge and let go: the cloth then lies on
   the board and stays there (the success test holds after letting go too).
5. Back off straight up, so the open fingers do not drag the cloth back.

The cloth and board poses are read from the simulator (privileged), so the path adapts to every
world and random shift.
"""

from __future__ import annotations

from enum import Enum

import numpy as np
from scipy.spatial.transform import Rotation

from rmb_lerobot.envs.experts.base import GripperExpert, Waypoint
from rmb_lerobot.envs.tasks.cloth import BOARD, BOARD_HALF_SIZE, CLOTH_COLUMNS, CLOTH_ROWS


class Phase(Enum):
    BEHIND = "behind"
    UNDER = "under"
    GRASP = "grasp"
    CLOSE = "close"
    LIFT = "lift"
    OVER = "over"
    RELEASE = "release"
    RETREAT = "retreat"


def pointing(approach: np.ndarray, closing: np.ndarray) -> Rotation:
    """Eef orientation with the tool axis (eef z) along ``approach`` and the fingers closing
    along ``closing`` (made orthogonal to the approach)."""
    z = np.asarray(approach, dtype=np.float64)
    z = z / np.linalg.norm(z)
    x = np.asarray(closing, dtype=np.float64)
    x = x - (x @ z) * z
    x /= np.linalg.norm(x)
    return Rotation.from_matrix(np.column_stack([x, np.cross(z, x), z]))


class ClothExpert(GripperExpert):
    """Tool point: the gripper's pinch point."""

    behind = 0.1  # pre-grasp distance on the robot's side of the sheet (m)
    below = 0.05  # pinch point below the hem while moving under it: the palm clears the hem (m)
    grasp_depth = 0.05  # pinch point above the hem when closing (the palm lifts the hem a bit, m)
    side_clearance = 0.06  # pinch point this far from the board's near edge while lifting (m)
    over_height = 0.07  # pinch point above the board's top while carrying (m)
    beyond = 0.01  # release point beyond the board's far edge (m)
    retreat_height = 0.1  # straight up after letting go, so the fingers do not drag the cloth (m)

    def on_reset(self) -> None:
        super().on_reset()
        self.phase = Phase.BEHIND
        _, eef_rot = self.eef_world()
        board, rot = self.scene.body_pose(BOARD)
        self._board = board.copy()
        self._across = rot[:, 0].copy()  # board x: from the robot's side to the far side
        self._along = rot[:, 1].copy()  # board y: along the hem
        robot = self.scene.body_pose(self.arm.root_frame)[0]
        if self._across @ (robot - self._board) > 0:  # make it point away from the robot
            self._across, self._along = -self._across, -self._along
        # Of the two finger orientations closing across the sheet, the one nearer the hand's.
        closing = (
            self._across if eef_rot.apply([1.0, 0.0, 0.0]) @ self._across > 0 else -self._across
        )
        self._grasp_rot = pointing(self._along, closing)
        # Carrying, the hand points away from the robot (+x): the grasp turned about the vertical.
        yaw = -np.arctan2(self._along[1], self._along[0])
        self._carry_rot = Rotation.from_euler("z", yaw) * self._grasp_rot
        self._hem = self._hem_middle()  # the cloth hangs at rest: plan the grasp once
        self._hold = self._hem + np.array([0.0, 0.0, self.grasp_depth])

    def _hem_middle(self) -> np.ndarray:
        points = self.env.task.cloth_points(self.scene)
        bottom = points[(CLOTH_ROWS - 1) * CLOTH_COLUMNS :]
        return bottom.mean(axis=0)

    def _carried_to(self, target: np.ndarray) -> bool:
        """The hand is at ``target``, or as near as the cloth lets it: the pinned, inextensible
        cloth (RMB's 2.1 kg) can hold the hand back a few cm short of it (seen in 1 of 30
        episodes in eef_rel mode), and then the reference is there and the hand has stopped."""
        self._track_tool_speed()
        if self.reached(target, 0.01):
            return True
        held = np.linalg.norm(self._ref_pos - target) < 0.01
        return held and self._tool_speed < self.still_speed

    def _board_frame(self, across: float, along: float, up: float) -> np.ndarray:
        return self._board + across * self._across + along * self._along + np.array([0, 0, up])

    def waypoint(self) -> Waypoint:
        hx, _, hz = BOARD_HALF_SIZE
        below = self._hem - np.array([0.0, 0.0, self.below])
        if self.phase is Phase.BEHIND:
            target = below - self.behind * self._across
            if self.reached(target, 0.01):
                self.phase = Phase.UNDER
            return Waypoint(target, self._grasp_rot, self.open_gripper)
        if self.phase is Phase.UNDER:
            if self.reached(below, 0.005):
                self.phase = Phase.GRASP
            return Waypoint(below, self._grasp_rot, self.open_gripper)
        if self.phase is Phase.GRASP:
            if self.reached(self._hold, 0.005):
                self.phase = Phase.CLOSE
                self._count = 0
            return Waypoint(self._hold, self._grasp_rot, self.open_gripper)
        if self.phase is Phase.CLOSE:
            if self._gripper_settled():
                self.phase = Phase.LIFT
            return Waypoint(self._hold, self._grasp_rot, self.closed_gripper)
        along = (self._hold - self._board) @ self._along
        if self.phase is Phase.LIFT:
            target = self._board_frame(-hx - self.side_clearance, along, hz + self.over_height)
            if self._carried_to(target):
                self.phase = Phase.OVER
            return Waypoint(target, self._carry_rot, self.closed_gripper)
        if self.phase is Phase.OVER:
            target = self._board_frame(hx + self.beyond, along, hz + self.over_height)
            if self._carried_to(target):
                self.phase = Phase.RELEASE
                self._count = 0
                self._hold = target
            return Waypoint(target, self._carry_rot, self.closed_gripper)
        if self.phase is Phase.RELEASE:
            if self._gripper_settled():
                self.phase = Phase.RETREAT
            return Waypoint(self._hold, self._carry_rot, self.open_gripper)
        target = self._hold + np.array([0.0, 0.0, self.retreat_height])
        return Waypoint(target, self._carry_rot, self.open_gripper)

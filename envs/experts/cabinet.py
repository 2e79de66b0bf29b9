"""Scripted experts for the two Cabinet tasks: hook the closed fingers behind the part and push.

A parallel gripper cannot keep a grasp on a lid that turns by more than 120 degrees, and a
sliding door only needs a sideways push, so neither expert grasps: the gripper stays closed and
its fingertip block is used as a hook, which tolerates position errors of the size of the
fingers instead of requiring a precise pinch.

* Slide: the hand points forward and 45 degrees down (a horizontal hand this low would drag the
  wrist over the robot's stand), the closed fingers go in front of the door on the -y side of the
  tab handle and push it along +y past the success distance.
* Hinge: the hand points forward horizontally, fingers closing sideways so the fingertip block is
  flat enough for the notch; the fingertips enter the notch just under the lid's front edge,
  then the block's upper front corner follows the lid's arc about the hinge, lifting the lid
  through vertical until gravity flips it open. The arc's reference angle leads the measured
  lid angle by a bounded amount, so the hand never runs away from the lid.
"""

from __future__ import annotations

from enum import Enum
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from rmb_lerobot.envs.experts.base import ScriptedExpert, Waypoint
from rmb_lerobot.envs.tasks.cabinet import (
    CABINET,
    HALF_DEPTH,
    HANDLE,
    HANDLE_DEPTH,
    HANDLE_HALF_THICKNESS,
    HINGE,
    LID,
    SLIDE,
)

# The closed Robotiq 2F-85's fingertip block, measured on the model in the pinch-site frame
# (x across the pads, y the closing direction, z the tool axis): the pads reach PAD_TIP beyond
# the pinch point and PAD_HALF_WIDTH to each side; everything within 5 cm of the tip stays
# within FINGER_HALF_WIDTH across the pads, but the followers stand out FOLLOWER_HALF_SPAN along
# the closing direction, up to FOLLOWER_TIP beyond the pinch point.
PAD_TIP = 0.018
PAD_HALF_WIDTH = 0.011
FINGER_HALF_WIDTH = 0.017
FOLLOWER_TIP = 0.011
FOLLOWER_HALF_SPAN = 0.032


class CabinetExpert(ScriptedExpert):
    """Shared set-up: closed gripper, a fixed hand orientation, a tool point on the fingers.

    The hand orientation is given for the pinch frame: tool axis along +x pitched
    ``tool_pitch_deg`` down, closing direction along world y (``closing_along_y``) or in the
    vertical plane through the tool axis.
    """

    initial_phase: Enum
    tool_pitch_deg: float
    closing_along_y: bool
    tool_in_pinch = np.zeros(3)  # tool point in the pinch-site frame
    approach_speed = 0.05  # m/s when moving in next to the part: little lag, so no overshoot

    def __init__(self, env: Any, **kwargs: Any) -> None:
        super().__init__(env, **kwargs)
        self._cruise_step = self.max_step

    def on_reset(self) -> None:
        self.phase = self.initial_phase
        pinch_pos, pinch_mat = self.tcp_world()
        eef_pos, eef_rot = self.eef_world()
        pinch_rot = Rotation.from_matrix(pinch_mat)
        self._offset = eef_rot.inv().apply(
            pinch_pos - eef_pos + pinch_rot.apply(self.tool_in_pinch)
        )
        pitch = np.deg2rad(self.tool_pitch_deg)
        axis = np.array([np.cos(pitch), 0.0, -np.sin(pitch)])
        across = np.array([0.0, 1.0, 0.0])
        closing = across if self.closing_along_y else np.cross(across, axis)
        pinch_goal = Rotation.from_matrix(np.column_stack([np.cross(closing, axis), closing, axis]))
        self._rot = pinch_goal * (eef_rot.inv() * pinch_rot).inv()  # as an eef-site orientation

    def tool_offset(self) -> np.ndarray:
        return self._offset

    def measured_tool(self) -> np.ndarray:
        eef_pos, eef_rot = self.eef_world()
        return eef_pos + eef_rot.apply(self._offset)

    def aligned(self, target: np.ndarray, tol: float, max_angle_deg: float = 2.0) -> bool:
        """Tool within ``tol`` of ``target`` and the hand turned to the task orientation."""
        _, rot = self.eef_world()
        angle = np.degrees((rot * self._rot.inv()).magnitude())
        return self.reached(target, tol) and angle < max_angle_deg

    def waypoint_at(self, pos: np.ndarray, slow: bool = False) -> Waypoint:
        self.max_step = self.approach_speed * self.dt if slow else self._cruise_step
        return Waypoint(pos, self._rot, self.arm.gripper.closed)


class SlidePhase(Enum):
    ALIGN = "align"
    HOOK = "hook"
    PUSH = "push"


class CabinetSlideExpert(CabinetExpert):
    """Tool point: the pinch point. The pads face the tab with their narrow side."""

    initial_phase = SlidePhase.ALIGN
    tool_pitch_deg = 45.0
    closing_along_y = False
    # Bound on how far the closed fingers reach beyond the pinch point along world +x at this
    # pitch (the followers, tilted up towards the door, can reach further than the pads).
    reach = (
        np.cos(np.deg2rad(tool_pitch_deg)) * FOLLOWER_TIP
        + np.sin(np.deg2rad(tool_pitch_deg)) * FOLLOWER_HALF_SPAN
    )
    front_gap = 0.006  # front-most finger part to the door's front face (m)
    side_gap = 0.006  # fingers to the tab while moving in (m)
    stand_off = 0.05  # align this far in front of the hook point (m)
    push_distance = 0.14  # door travel aimed at (success: 0.12, limit 0.15)
    max_lead = 0.03  # how far the push reference may run ahead of the door (m)

    def _hook_point(self, back: float = 0.0) -> np.ndarray:
        """Pinch point beside the tab (its -y side), ``back`` further from the door."""
        handle = self.scene.geom_pose(HANDLE)[0]
        face_x = handle[0] + HANDLE_DEPTH / 2
        y = handle[1] - HANDLE_HALF_THICKNESS - FINGER_HALF_WIDTH - self.side_gap
        return np.array([face_x - self.front_gap - self.reach - back, y, handle[2]])

    def waypoint(self) -> Waypoint:
        if self.phase is SlidePhase.ALIGN:
            target = self._hook_point(self.stand_off)
            if self.aligned(target, 0.01):
                self.phase = SlidePhase.HOOK
            return self.waypoint_at(target)
        if self.phase is SlidePhase.HOOK:
            target = self._hook_point()
            if self.reached(target, 0.004):
                self.phase = SlidePhase.PUSH
                self._push_start = target
            return self.waypoint_at(target, slow=True)
        opened = float(self.scene.joint_position(SLIDE)[0])
        travel = min(self.push_distance, opened + self.max_lead) + self.side_gap
        return self.waypoint_at(self._push_start + np.array([0.0, travel, 0.0]))


class HingePhase(Enum):
    ALIGN = "align"
    ENTER = "enter"
    LIFT = "lift"


class CabinetHingeExpert(CabinetExpert):
    """Tool point: the upper front corner of the closed fingertips (what touches the lid)."""

    initial_phase = HingePhase.ALIGN
    tool_pitch_deg = 0.0
    closing_along_y = True
    tool_in_pinch = np.array([-PAD_HALF_WIDTH, 0.0, PAD_TIP])  # pinch x points down
    stand_off = 0.04  # align this far in front of the notch (m)
    entry_depth = 0.03  # fingertips this far behind the front face (m)
    below_lid = 0.008  # corner below the lid's underside (m)
    goal_angle = np.deg2rad(125.0)
    lift_rate = 0.8  # rad/s of the arc reference
    max_lead = np.deg2rad(12.0)  # how far the reference may run ahead of the lid

    def _hinge(self) -> np.ndarray:
        return self.scene.body_pose(LID)[0].copy()

    def _entry_point(self, depth: float) -> np.ndarray:
        """Corner ``depth`` behind the front face, centred in the notch, just under the lid."""
        hinge = self._hinge()
        face_x = self.scene.body_pose(CABINET)[0][0] - HALF_DEPTH
        return np.array([face_x + depth, hinge[1], hinge[2] - self.below_lid])

    def _arc_point(self, theta: float) -> np.ndarray:
        """Corner under the lid at the entry radius with the lid at ``theta``."""
        along = np.array([-np.cos(theta), 0.0, np.sin(theta)])
        below = np.array([-np.sin(theta), 0.0, -np.cos(theta)])
        return self._hinge() + self._radius * along + self.below_lid * below

    def waypoint(self) -> Waypoint:
        if self.phase is HingePhase.ALIGN:
            target = self._entry_point(-self.stand_off)
            if self.aligned(target, 0.01):
                self.phase = HingePhase.ENTER
            return self.waypoint_at(target)
        if self.phase is HingePhase.ENTER:
            target = self._entry_point(self.entry_depth)
            if self.reached(target, 0.004):
                self.phase = HingePhase.LIFT
                self._radius = self._hinge()[0] - target[0]
                self._theta_ref = 0.0
            return self.waypoint_at(target, slow=True)
        angle = float(self.scene.joint_position(HINGE)[0])
        theta = self._theta_ref + self.lift_rate * self.dt
        self._theta_ref = min(theta, angle + self.max_lead, self.goal_angle)
        return self.waypoint_at(self._arc_point(self._theta_ref))

"""Scripted expert for the Door task: grasp the bar handle from the front, pull it along its arc.

The door's bar handle sits half-way up a 29 cm leaf, 15 cm above the table, so the gripper
comes from the front and above, pitched ``approach_pitch_deg`` below horizontal (a horizontal
hand would drag the wrist over the table), fingers closing in the vertical plane through the
approach direction; the pad behind the bar then also pushes on it when pulling. The pull
reference leads the measured door angle by a bounded amount, so the hand never drags the bar
far from where the hinge lets it be, and the gripper turns about the vertical with the leaf
(by ``yaw_follow`` of its angle: the pads clamp the bar across its axis, which tolerates a yaw
mismatch and keeps the wrist away from its singularity).
"""

from __future__ import annotations

from enum import Enum

import numpy as np
from scipy.spatial.transform import Rotation

from rmb_lerobot.envs.experts.base import ScriptedExpert, Waypoint
from rmb_lerobot.envs.tasks.door import DOOR, DOOR_LEAF, HANDLE_BAR_X


class Phase(Enum):
    PRE_GRASP = "pre_grasp"
    APPROACH = "approach"
    CLOSE = "close"
    PULL = "pull"


class DoorExpert(ScriptedExpert):
    """Tool point: the gripper's pinch point."""

    grasp_y = -0.135  # along the leaf, away from the stem at -0.17 (leaf frame, m)
    grasp_depth = 0.0  # pinch point beyond the bar's axis (m)
    stand_off = 0.10  # pre-grasp distance in front of the bar (m)
    min_close_steps = 10
    goal_angle = np.deg2rad(-65.0)
    pull_rate = 0.4  # rad/s of door opening
    min_lead, max_lead = 0.02, 0.1  # rad the reference runs ahead of the measured angle
    yaw_follow = 0.75
    approach_pitch_deg = 30.0

    def on_reset(self) -> None:
        self.phase = Phase.PRE_GRASP
        self._close_count = 0
        self._last_gripper = 0.0
        self._theta_ref = 0.0
        eef_pos, eef_rot = self.eef_world()
        self._offset = eef_rot.inv().apply(self.tcp_world()[0] - eef_pos)
        # The gripper-down orientation pitched up about the world y axis towards the door.
        pitch = -(90.0 - self.approach_pitch_deg)
        self._grasp_rot = Rotation.from_euler("y", pitch, degrees=True) * Rotation.from_matrix(
            [[-1, 0, 0], [0, 1, 0], [0, 0, -1]]
        )
        self._approach = self._grasp_rot.apply([0.0, 0.0, 1.0])  # eef z, world frame

    def tool_offset(self) -> np.ndarray:
        return self._offset

    def measured_tool(self) -> np.ndarray:
        return self.tcp_world()[0]

    def _door_angle(self) -> float:
        return float(self.scene.joint_position(DOOR)[0])

    def _leaf_point(self, theta: float, x: float) -> np.ndarray:
        """World position of leaf-frame point ``(x, grasp_y, 0)`` with the leaf at ``theta``."""
        leaf_pos, leaf_rot = self.scene.body_pose(DOOR_LEAF)
        closed = Rotation.from_matrix(leaf_rot) * Rotation.from_euler("z", -self._door_angle())
        local = Rotation.from_euler("z", theta).apply([x, self.grasp_y, 0.0])
        return leaf_pos + closed.apply(local)

    def waypoint(self) -> Waypoint:
        grasp_x = HANDLE_BAR_X + self.grasp_depth
        if self.phase is Phase.PRE_GRASP:
            target = self._leaf_point(0.0, grasp_x) - self.stand_off * self._approach
            if self.reached(target, 0.01):
                self.phase = Phase.APPROACH
            return Waypoint(target, self._grasp_rot, self.open_gripper)
        if self.phase is Phase.APPROACH:
            target = self._leaf_point(0.0, grasp_x)
            if self.reached(target, 0.004):
                self.phase = Phase.CLOSE
            return Waypoint(target, self._grasp_rot, self.open_gripper)
        if self.phase is Phase.CLOSE:
            self._close_count += 1
            gripper = self.env.measured_joint_pos()[self.gripper_index]
            settled = abs(gripper - self._last_gripper) < 0.5
            self._last_gripper = gripper
            if self._close_count >= self.min_close_steps and settled:
                self.phase = Phase.PULL
            return Waypoint(self._leaf_point(0.0, grasp_x), self._grasp_rot, self.closed_gripper)
        angle = self._door_angle()
        theta = min(self._theta_ref - self.pull_rate * self.dt, angle - self.min_lead)
        self._theta_ref = max(theta, angle - self.max_lead, self.goal_angle)
        rot = Rotation.from_euler("z", self.yaw_follow * self._theta_ref) * self._grasp_rot
        return Waypoint(self._leaf_point(self._theta_ref, grasp_x), rot, self.closed_gripper)

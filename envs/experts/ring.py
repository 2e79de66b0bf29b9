"""Scripted expert for the Ring task: pinch the ring's bottom, slide it off the hook, turn it flat
and lower it around the pole.

1. Turn the hand (pointing along +x, RMB's start pose) so the fingers close vertically, and
   approach the ring's bottom segment from the robot's side: one finger passes under it, the
   other through the ring.
2. Close, lift the ring off the pegs and pull it towards the robot far enough that the ring,
   swinging out in front of the fingers while the hand turns (step 3), cannot catch on them.
3. Lift it and pitch the hand down by 90 degrees: the ring, clamped at its bottom segment, turns
   with the hand from standing upright to lying flat (in front of the fingers).
4. Carry it so that the ring's measured centre is over the pole, lower it until the whole ring
   is below the pole's top, open the fingers (the ring drops onto the table around the pole)
   and back off upwards.

The ring's position is read from the simulator (privileged) when each phase starts, so the
expert adapts to every world, random shift and to how the ring sits in the grasp.
"""

from __future__ import annotations

from enum import Enum
from typing import Any, ClassVar

import numpy as np
from scipy.spatial.transform import Rotation

from rmb_lerobot.envs.experts.base import GripperExpert, Waypoint
from rmb_lerobot.envs.tasks.ring import POLE, POLE_HEIGHT, RING_RADIUS, TUBE_RADIUS


class Phase(Enum):
    ALIGN = "align"
    APPROACH = "approach"
    CLOSE = "close"
    UNHOOK = "unhook"
    PULL = "pull"
    RAISE = "raise"
    TURN = "turn"
    CARRY = "carry"
    DESCEND = "descend"
    LAYDOWN = "laydown"
    RELEASE = "release"
    NUDGE = "nudge"
    RETREAT = "retreat"


def grip_rotation(close: np.ndarray, tool: np.ndarray, closing_axis: int) -> Rotation:
    """Eef orientation with the tool axis (eef z) along ``tool`` and the fingers closing along
    ``close`` (orthogonal unit vectors); the fingers close along eef x (``closing_axis`` 0) or
    eef y (1), depending on how the gripper is mounted."""
    if closing_axis == 0:
        return Rotation.from_matrix(np.column_stack([close, np.cross(tool, close), tool]))
    return Rotation.from_matrix(np.column_stack([np.cross(close, tool), close, tool]))


def down_rotation(across: np.ndarray, current: Rotation, closing_axis: int) -> Rotation:
    """Gripper pointing down with the fingers closing along the horizontal direction
    ``across``; of the two such orientations, the one nearer the ``current`` hand (as
    :func:`~rmb_lerobot.envs.experts.base.top_down_rotation`, for either closing axis)."""
    across = np.array([across[0], across[1], 0.0])
    across /= np.linalg.norm(across)
    if across @ current.apply(np.eye(3)[closing_axis]) < 0:
        across = -across
    return grip_rotation(across, np.array([0.0, 0.0, -1.0]), closing_axis)


class RingExpert(GripperExpert):
    """Tool point: the gripper's pinch point.

    The class attributes are the UR5e's tuning; :attr:`robot_tuning` overrides some of them for
    other robots (their grippers and reach differ), applied when the expert is made.
    """

    approach_distance = 0.08  # pre-grasp distance of the pinch point before the ring (m)
    grasp_depth = 0.02  # pinch point beyond the tube: the tube sits between the pads (m)
    unhook_lift = 0.015  # lift off the pegs before pulling (m)
    pull_distance = 0.16  # towards the robot: the ring clears the pegs, also while turning (m)
    turn_height = 1.08  # pinch height while turning the ring flat (m)
    carry_clearance = 0.03  # ring's lowest point above the pole's top while carrying (m)
    ring_radius = RING_RADIUS
    laydown_angle = np.deg2rad(65.0)  # how far the ring is tipped over before letting go
    laydown_points = 5
    nudge = 0.04  # after letting go, the hand moves this far outwards to push the ring over (m)
    approach_speed, lower_speed = 0.08, 0.06  # m/s
    closing_axis = 0  # the eef axis the fingers close along (the 2F-85 on the UR5e: x)
    robot_tuning: ClassVar[dict[str, dict[str, Any]]] = {
        "xarm7": {
            "closing_axis": 1,  # the xArm gripper's fingers open along its base's (and eef) y
            # Its pads' faces open towards the palm by ~3 degrees when closed on the tube, which
            # works the tube inwards under load: grasp at the fingertips (the pads reach ~1 cm
            # short of its TCP, ``link_tcp``), where the tube has the pads' length to go.
            "grasp_depth": 0.005,
        },
    }

    def on_reset(self) -> None:
        super().on_reset()
        self.phase = Phase.ALIGN
        _, eef_rot = self.eef_world()
        # Hand along +x with the fingers closing vertically (the nearer of the two such rolls).
        close = np.array([0.0, 0.0, 1.0])
        if close @ eef_rot.apply(np.eye(3)[self.closing_axis]) < 0:
            close = -close
        tool = np.array([1.0, 0.0, 0.0])
        self._grasp_rot = grip_rotation(close, tool, self.closing_axis)
        # The ring is tipped over away from the robot (along the horizontal line from the
        # robot's base to the pole): the hand is high only on the near side of the pole, where
        # the arm reaches easily. Hanging from the hand, the ring faces the fingers' closing
        # axis, so the hand points down with its fingers closing along that line.
        base = self.scene.body_pose(self.arm.root_frame)[0]
        outward = self._pole() - base
        outward[2] = 0.0
        self._outward = outward / np.linalg.norm(outward)
        pitched = Rotation.from_euler("y", np.pi / 2) * self._grasp_rot
        self._hang_rot = down_rotation(self._outward, pitched, self.closing_axis)
        self._hold = np.zeros(3)
        self._laydown: list[np.ndarray] = []

    # ------------------------------------------------------------------ helpers
    def _ring(self) -> np.ndarray:
        return self.env.task.ring_points(self.scene)

    def _grasp_point(self) -> np.ndarray:
        """Middle of the ring's lowest segment (the two lowest vertices)."""
        points = self._ring()
        lowest = points[np.argsort(points[:, 2])[:2]]
        return lowest.mean(axis=0) + np.array([self.grasp_depth, 0.0, 0.0])

    def _pole(self) -> np.ndarray:
        return self.scene.body_pose(POLE)[0].copy()

    def _hanging_target(self, touch: np.ndarray, lowest_z: float) -> np.ndarray:
        """Pinch target that puts the hanging ring's lowest point at ``touch`` (xy) and height
        ``lowest_z``."""
        points = self._ring()
        low = points[np.argmin(points[:, 2])]
        target = self.measured_tool()
        target[:2] += touch[:2] - low[:2]
        target[2] += lowest_z - low[2]
        return target

    def _plan_laydown(self) -> list[np.ndarray]:
        """Pinch targets along a quarter circle about the ring's contact with the table, towards
        the robot: the ring tips over about that point and comes to lie centred on the pole."""
        points = self._ring()
        contact = points[np.argmin(points[:, 2])]
        tool = self.measured_tool()
        radius = float(np.linalg.norm(tool - contact))
        angles = np.linspace(0.0, self.laydown_angle, self.laydown_points + 1)[1:]
        up = np.array([0.0, 0.0, 1.0])
        return [contact + radius * (np.cos(a) * up + np.sin(a) * self._outward) for a in angles]

    # ------------------------------------------------------------------ phases
    def waypoint(self) -> Waypoint:
        closed, opened = self.closed_gripper, self.open_gripper
        if self.phase is Phase.ALIGN:
            target = self._grasp_point() - np.array([self.approach_distance, 0.0, 0.0])
            if self.reached(target, 0.01):
                self.phase = Phase.APPROACH
                self.max_step = self.approach_speed * self.dt
                self._hold = self._grasp_point()  # fixed: the fingers may nudge the ring
            return Waypoint(target, self._grasp_rot, opened)
        if self.phase is Phase.APPROACH:
            target = self._hold
            if self.reached(target, 0.003):
                self.phase = Phase.CLOSE
                self._hold = target
                self.max_step = self._cruise_step
            return Waypoint(target, self._grasp_rot, opened)
        if self.phase is Phase.CLOSE:
            if self._gripper_settled():
                self.phase = Phase.UNHOOK
                self._hold = self._hold + np.array([0.0, 0.0, self.unhook_lift])
            return Waypoint(self._hold, self._grasp_rot, closed)
        if self.phase is Phase.UNHOOK:
            if self.reached(self._hold, 0.005):
                self.phase = Phase.PULL
                self._hold = self._hold - np.array([self.pull_distance, 0.0, 0.0])
            return Waypoint(self._hold, self._grasp_rot, closed)
        if self.phase is Phase.PULL:
            if self.reached(self._hold, 0.01):
                self.phase = Phase.RAISE
                self._hold = np.array([*self._hold[:2], self.turn_height])
            return Waypoint(self._hold, self._grasp_rot, closed)
        if self.phase is Phase.RAISE:
            if self.reached(self._hold, 0.01):
                self.phase = Phase.TURN
            return Waypoint(self._hold, self._grasp_rot, closed)
        if self.phase is Phase.TURN:
            _, rot = self.eef_world()
            if (rot * self._hang_rot.inv()).magnitude() < 0.05:
                self.phase = Phase.CARRY
            return Waypoint(self._hold, self._hang_rot, closed)
        if self.phase is Phase.CARRY:
            touch = self._pole() - self.ring_radius * self._outward
            high = self._pole()[2] + POLE_HEIGHT + self.carry_clearance
            target = self._hanging_target(touch, high)
            if self.reached(target, 0.01):
                self.phase = Phase.DESCEND
                self.max_step = self.lower_speed * self.dt
                self._hold = self._hanging_target(touch, self.table_z() + TUBE_RADIUS - 0.002)
            return Waypoint(target, self._hang_rot, closed)
        if self.phase is Phase.DESCEND:
            if self.reached(self._hold, 0.004):
                self.phase = Phase.LAYDOWN
                self._laydown = self._plan_laydown()
            return Waypoint(self._hold, self._hang_rot, closed)
        if self.phase is Phase.LAYDOWN:
            target = self._laydown[0]
            # Only the reference must get there: the hand may lag, pressing on the ring.
            if np.linalg.norm(self._ref_pos - target) < 0.005:
                self._laydown.pop(0)
                if not self._laydown:
                    self.phase = Phase.RELEASE
                    self._count = 0
                    self._hold = target
                    self.max_step = self._cruise_step
            return Waypoint(target, self._hang_rot, closed)
        if self.phase is Phase.RELEASE:
            if self._gripper_settled():
                self.phase = Phase.NUDGE
                self._hold = self._hold + self.nudge * self._outward
            return Waypoint(self._hold, self._hang_rot, opened)
        if self.phase is Phase.NUDGE:
            if self.reached(self._hold, 0.01):
                self.phase = Phase.RETREAT
            return Waypoint(self._hold, self._hang_rot, opened)
        target = self._hold + np.array([0.0, 0.0, 0.1])
        return Waypoint(target, self._hang_rot, opened)

"""Scripted expert for the Particle task: grasp the scoop, scoop particles up, pour them out.

1. Grasp the scoop's handle from above, the fingers closing along x (across the handle, in
   the plane the scoop later tilts in, so the pads clamp against the tilting torque instead of
   relying on torsional friction).
2. Carry the scoop over the source container behind the particle block and lower it until its
   plate skims the table.
3. Push it open side first through the block: the particles ride over the thin plate's edge
   into the scoop.
4. Tilt it lip up (the particles slide against the back wall) and lift it over the walls.
5. Carry it over the goal container and tilt it lip down by 50 degrees: the particles slide
   out (beyond ~27 degrees; steeper pours put the arm near the edge of its reach, as the hand
   then points back at the robot).

The tool point is the gripper's pinch point until the grasp, then the scoop's plate centre
(the scoop's body origin, measured in the simulator), so the scoop is tilted about its own
centre. The route is planned once, at the grasp, from the containers' positions.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

import numpy as np
from scipy.spatial.transform import Rotation

from rmb_lerobot.envs.experts.base import GripperExpert, Waypoint, top_down_rotation
from rmb_lerobot.envs.tasks.particle import (
    CASE_WALL_HALF_THICKNESS,
    GOAL,
    HANDLE_POS,
    SCOOP,
    SCOOP_HANDLE,
    SCOOP_PLATE_HALF,
    SOURCE,
    SOURCE_HALF_SIDE,
)

PAD_HALF_WIDTH = 0.011  # the Robotiq 2F-85's finger pads, across the closing direction (m)


@dataclass(frozen=True)
class Leg:
    """Move the scoop's plate centre to ``pos`` (world) at ``speed`` (m/s), tilted by
    ``pitch`` (rad about world y; positive lowers the open side)."""

    pos: np.ndarray
    pitch: float
    speed: float


class Phase(Enum):
    CLEAR = "clear"
    ABOVE = "above"
    DESCEND = "descend"
    CLOSE = "close"
    ROUTE = "route"


class ParticleExpert(GripperExpert):
    """Tool point: the pinch point until the handle is grasped, then the scoop's plate centre."""

    clear_height = 0.05  # first move: straight up from the start pose, off the handle (m)
    approach_height = 0.06  # pre-grasp height of the pinch point above the grasp point (m)
    grasp_above_centre = 0.008  # pinch point above the handle's centre (pads clear the wall)
    carry_height = 0.1  # plate centre above the table while carrying (m)
    skim_height = 0.003  # plate bottom above the table while pushing (m)
    start_clearance = 0.01  # the scoop's back (handle + pad) this far from the source wall
    end_clearance = 0.012  # the lip stops this far from the far wall (m)
    tilt_up = np.deg2rad(20.0)  # lip up while lifting and carrying
    pour_pitch = np.deg2rad(50.0)  # lip down over the goal
    pour_back = 0.04  # plate centre this far before (-x) the goal's centre when pouring (m)
    travel_speed, lower_speed, push_speed, lift_speed = 0.15, 0.08, 0.05, 0.05  # m/s
    back_extent = PAD_HALF_WIDTH - HANDLE_POS[0]  # plate centre to the back of the pads (m)

    def on_reset(self) -> None:
        super().on_reset()
        self.phase = Phase.CLEAR
        self._route: list[Leg] = []
        self._leg = 0
        self._on_scoop = False
        self._hold = np.zeros(3)  # pinch target while closing
        _, eef_rot = self.eef_world()
        self._clear = self.pinch_point() + np.array([0.0, 0.0, self.clear_height])
        self._grasp_rot = top_down_rotation(np.array([1.0, 0.0, 0.0]), eef_rot)

    def measured_tool(self) -> np.ndarray:
        if self._on_scoop:
            return self.scene.body_pose(SCOOP)[0].copy()
        return self.pinch_point()

    # ------------------------------------------------------------------ helpers
    def _grasp_point(self) -> np.ndarray:
        return self.scene.geom_pose(SCOOP_HANDLE)[0] + np.array([0, 0, self.grasp_above_centre])

    def _take_scoop(self) -> None:
        """Switch the tool point to the scoop's plate centre. The reference jumps to the
        measured scoop, so the commanded eef pose (and the integral correction) stay put."""
        eef_pos, eef_rot = self.eef_world()
        self._on_scoop = True
        scoop = self.measured_tool()
        self._offset = eef_rot.inv().apply(scoop - eef_pos)
        self._ref_pos = scoop

    def plan_route(self) -> list[Leg]:
        """The legs after the grasp, for the current container positions."""
        source, goal = self.scene.body_pose(SOURCE)[0], self.scene.body_pose(GOAL)[0]
        scoop = self.scene.body_pose(SCOOP)[0]
        inner = SOURCE_HALF_SIDE - CASE_WALL_HALF_THICKNESS
        carry = self.table_z() + self.carry_height
        skim = self.table_z() + SCOOP_PLATE_HALF[2] + self.skim_height
        start_x = source[0] - inner + self.start_clearance + self.back_extent
        end_x = source[0] + inner - self.end_clearance - SCOOP_PLATE_HALF[0]
        y = source[1]
        up, travel = -self.tilt_up, self.travel_speed
        return [
            Leg(np.array([scoop[0], scoop[1], carry]), 0.0, travel),
            Leg(np.array([start_x, y, carry]), 0.0, travel),
            Leg(np.array([start_x, y, skim]), 0.0, self.lower_speed),
            Leg(np.array([end_x, y, skim]), 0.0, self.push_speed),
            Leg(np.array([end_x, y, skim + 0.03]), up, self.lift_speed),
            Leg(np.array([end_x, y, carry]), up, self.lift_speed),
            Leg(np.array([goal[0] - self.pour_back, goal[1], carry]), up, travel),
            Leg(np.array([goal[0] - self.pour_back, goal[1], carry]), self.pour_pitch, travel),
        ]

    def _rotation(self, pitch: float) -> Rotation:
        return Rotation.from_rotvec([0.0, pitch, 0.0]) * self._grasp_rot

    # ------------------------------------------------------------------ phases
    def waypoint(self) -> Waypoint:
        if self.phase is Phase.CLEAR:
            if self.reached(self._clear, 0.01):
                self.phase = Phase.ABOVE
            return Waypoint(self._clear, self._grasp_rot, self.open_gripper)
        if self.phase is Phase.ABOVE:
            target = self._grasp_point() + np.array([0.0, 0.0, self.approach_height])
            if self.reached(target, 0.005):
                self.phase = Phase.DESCEND
            return Waypoint(target, self._grasp_rot, self.open_gripper)
        if self.phase is Phase.DESCEND:
            target = self._grasp_point()
            if self.reached(target, 0.003):
                self.phase = Phase.CLOSE
                self._hold = target
            return Waypoint(target, self._grasp_rot, self.open_gripper)
        if self.phase is Phase.CLOSE:
            if not self._gripper_settled():
                return Waypoint(self._hold, self._grasp_rot, self.closed_gripper)
            self.phase = Phase.ROUTE
            self._take_scoop()
            self._route = self.plan_route()
        leg = self._route[self._leg]
        self.max_step = leg.speed * self.dt
        if self._leg < len(self._route) - 1 and self.reached(leg.pos, 0.01):
            self._leg += 1
        return Waypoint(leg.pos, self._rotation(leg.pitch), self.closed_gripper)

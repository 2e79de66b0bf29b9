"""Scripted expert for TidyUp on a mobile robot: drive, pick a bottle, drive, place it; twice.

For each bottle in turn (bottle 1 into container 1, then bottle 2 into container 2) the expert
runs the carry sequence (:class:`~rmb_lerobot.envs.experts.carry.CarryExpert`: grasp from above
-> close -> lift -> carry -> lower -> release -> retreat) with the base driven in between:

- before the grasp, the base drives (facing +x) to where the bottle is straight ahead of the
  hand's reach;
- after the lift, it drives around the containers' side (a corridor at ``y = container y +
  reach``, clear of the other bottle) and turns by -90 degrees, so that the held bottle hangs
  over its container;
- after the retreat, it drives back through the corridor to the next bottle.

While the base drives, the arm holds its last command in the base's frame (the bottle rides
along); the base is steered by a proportional law on its planar pose, through waypoints, and
stands still while the arm works. The hand keeps one orientation in the base frame (pointing
down, fingers closing along the base's x axis), so the reach found at reset (inverse
kinematics for that orientation) holds for every grasp and placement: the HSR's five arm
joints give a top-down hand only at one lateral offset from the base, which the base supplies.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from rmb_lerobot.envs.experts.base import Waypoint, top_down_rotation
from rmb_lerobot.envs.experts.carry import CarryExpert, CarryPhase
from rmb_lerobot.envs.tasks.tidyup import (
    BOTTLE_HALF_SIZE,
    BOTTLES,
    CONTAINER_FLOOR_HALF_THICKNESS,
    CONTAINERS,
)

BasePose = tuple[float, float, float]  # x, y, yaw in the world


def _wrap(angle: float) -> float:
    return float((angle + np.pi) % (2 * np.pi) - np.pi)


class TidyUpExpert(CarryExpert):
    """The carry sequence per bottle with base drives in between (see the module docstring)."""

    reach = 0.44  # tool point ahead of the base centre while grasping and placing (m)
    grasp_below_top = 0.06  # tool point below the bottle top when closing: near its middle (m)
    approach_height = 0.08  # pre-grasp height of the tool point above the grasp point (m)
    carry_bottom = 0.22  # held bottle's bottom above the floor while driving (m)
    place_clearance = 0.004  # bottle bottom above the container floor at the end of lowering
    retreat_z = 0.33  # tool point height after letting go (m)
    place_yaw = -np.pi / 2  # base yaw while placing: the arm reaches over a container's side
    grasp_tol = 0.006  # the base places the hand sideways to within its final tolerance
    hand_opening = 0.8  # open hand command (RMB's start value; 1.24 would sweep wide)
    # Base steering: gain (1/s), speed limits, arrival tolerances (intermediate, final).
    base_gain = 2.0
    base_speed, base_turn_rate = 0.35, 0.5
    via_tol, final_tol, final_yaw_tol = 0.03, 0.002, 0.01

    def __init__(self, env: Any, **kwargs: Any) -> None:
        # The arm's servos are soft (RMB's gains: about 0.2 s behind a moving target) and the
        # arm is gravity-compensated: a slow integral, only for what a held bottle sags.
        kwargs.setdefault("integral_gain", 0.05)
        kwargs.setdefault("max_correction", 0.03)
        super().__init__(env, **kwargs)
        if self.env.robot.base is None:
            raise ValueError(
                f"{type(self).__name__} drives a mobile base; {self.env.robot.name!r} has none"
            )
        self.open_gripper = self.hand_opening

    # ------------------------------------------------------------------ reset
    def on_reset(self) -> None:
        super().on_reset()
        self.bottle = 0  # index of the bottle being tidied (the last one stays when done)
        _, eef_rot = self.eef_world()
        base_rot = self._base_rotation()
        # Hand pointing down, fingers closing along the base's x axis (in the base frame).
        root_eef = base_rot.inv() * eef_rot
        self._hand_in_base = top_down_rotation(np.array([1.0, 0.0, 0.0]), root_eef)
        self._reach_y = self._lateral_reach()
        self.rot = base_rot * self._hand_in_base
        self._route: list[BasePose] = []
        self._start_drive(self._to_pick())

    def _lateral_reach(self) -> float:
        """The tool point's y in the base frame with the hand in its grasp orientation
        ``reach`` ahead: the only lateral offset a top-down hand has on this arm.

        The IK's answer for the ideal top-down pose is taken as it is reached (its forward
        kinematics): that orientation and that eef y are then exactly reachable at every
        height and reach, so later targets never ask the five joints for the impossible.
        Sets :attr:`_eef_y` and refines :attr:`_hand_in_base`.
        """
        rot = self._hand_in_base
        tool = np.array([self.reach, self._tool_in_base()[1], 0.25])
        eef = tool - rot.apply(self.tool_offset())
        target = np.concatenate([eef, np.roll(rot.as_quat(), 1)])
        q = self.sim.ik(self.arm_index, target, self.env.command[self._arm_joints])
        reached = self.sim.fk(self.arm_index, q)
        self._hand_in_base = Rotation.from_quat(np.roll(reached[3:], -1))
        self._eef_y = float(reached[1])
        return float((reached[:3] + self._hand_in_base.apply(self.tool_offset()))[1])

    def _tool_in_base(self) -> np.ndarray:
        """The measured tool point in the base frame."""
        pos, _ = self._base_pose_world()
        return self._base_rotation().inv().apply(self.measured_tool() - pos)

    # ------------------------------------------------------------------ base
    def _base_pose_world(self) -> tuple[np.ndarray, float]:
        pos, mat = self.scene.body_pose(self.env.robot.base.frame)
        return pos, float(np.arctan2(mat[1, 0], mat[0, 0]))

    def _base_rotation(self) -> Rotation:
        return Rotation.from_euler("z", self._base_pose_world()[1])

    def _stand_for(self, target_xy: np.ndarray, yaw: float) -> BasePose:
        """The base pose that puts the tool point over ``target_xy`` at base yaw ``yaw``."""
        c, s = np.cos(yaw), np.sin(yaw)
        rx, ry = self.reach, self._reach_y
        return (target_xy[0] - (c * rx - s * ry), target_xy[1] - (s * rx + c * ry), yaw)

    def _corridor_y(self) -> float:
        container = self.scene.body_pose(CONTAINERS[0])[0]
        return float(container[1] + self.reach + 0.02)

    def _to_pick(self) -> list[BasePose]:
        bottle = self.scene.body_pose(BOTTLES[self.bottle])[0]
        stand = self._stand_for(bottle[:2], 0.0)
        if self.bottle == 0:
            return [stand]
        return [(stand[0], self._corridor_y(), 0.0), stand]

    def _to_place(self) -> list[BasePose]:
        container = self.scene.body_pose(CONTAINERS[self.bottle])[0]
        stand = self._stand_for(container[:2], self.place_yaw)
        x, _ = self._base_pose_world()[0][:2]
        return [(x, self._corridor_y(), 0.0), stand]

    def _start_drive(self, route: list[BasePose]) -> None:
        self._route = list(route)

    def base_velocity(self) -> np.ndarray:
        """Steer towards the next waypoint of the route (base frame); zero when there is none."""
        if not self._route:
            return np.zeros(3)
        pos, yaw = self._base_pose_world()
        goal = self._route[0]
        err = np.array([goal[0] - pos[0], goal[1] - pos[1], _wrap(goal[2] - yaw)])
        last = len(self._route) == 1
        tol = self.final_tol if last else self.via_tol
        yaw_tol = self.final_yaw_tol if last else 0.05
        speed = self.env.measured_base_velocity()
        still = not last or float(np.linalg.norm(speed[:2])) < 0.01
        if np.linalg.norm(err[:2]) < tol and abs(err[2]) < yaw_tol and still:
            self._route.pop(0)
            if not self._route:
                self._end_drive()
                return np.zeros(3)
            return self.base_velocity()
        world = self.base_gain * err
        lin = np.linalg.norm(world[:2])
        if lin > self.base_speed:
            world[:2] *= self.base_speed / lin
        world[2] = np.clip(world[2], -self.base_turn_rate, self.base_turn_rate)
        c, s = np.cos(yaw), np.sin(yaw)
        return np.array([c * world[0] + s * world[1], -s * world[0] + c * world[1], world[2]])

    def _end_drive(self) -> None:
        """The base has arrived: take over the arm's held pose as the reference, so the arm
        goes on from where it is held (the integral correction kept)."""
        base_pos, _ = self._base_pose_world()
        base_rot = self._base_rotation()
        pose = self.env.command_eef_pose
        eef_rot = base_rot * Rotation.from_quat(np.roll(pose[3:], -1))
        eef_pos = base_pos + base_rot.apply(pose[:3])
        self._ref_pos = eef_pos + eef_rot.apply(self.tool_offset()) - self._correction
        self._ref_rot = eef_rot
        self.rot = base_rot * self._hand_in_base
        self._last_tool = self.measured_tool()

    # ------------------------------------------------------------------ policy
    def select_action(self, observation: Any = None) -> np.ndarray:
        """While the base drives, hold the arm's command (in the base frame); else the carry
        sequence with the base at rest."""
        if self._route:
            velocity = self.base_velocity()
            if self._route:  # still driving
                gripper = float(self.env.command[self.gripper_index])
                action = self._held_action(self.env.command_eef_pose, gripper)
                action[-3:] = velocity
                return action
        # The arm cannot move the hand sideways (the base does): no integral action that way.
        lateral = self._base_rotation().apply([0.0, 1.0, 0.0])
        self._correction -= (self._correction @ lateral) * lateral
        return super().select_action(observation)

    def _held_action(self, pose: np.ndarray, gripper: float) -> np.ndarray:
        return super()._action(pose, gripper)

    def _action(self, pose: np.ndarray, gripper: float) -> np.ndarray:
        """The carry sequence's target with its lateral offset (base frame) set to the one a
        top-down hand has: a pose the five joints reach exactly."""
        pose = pose.copy()
        pose[1] = self._eef_y
        return super()._action(pose, gripper)

    def waypoint(self) -> Waypoint:
        """The carry sequence's waypoint; starts the drives between its phases."""
        phase = self.phase
        wp = super().waypoint()
        if phase is CarryPhase.LIFT and self.phase is CarryPhase.CARRY:
            self._start_drive(self._to_place())
        retreated = phase is CarryPhase.RETREAT and self.reached(wp.pos, self.reach_tol)
        if retreated and self.bottle + 1 < len(BOTTLES):
            self.bottle += 1
            self.phase = CarryPhase.ABOVE
            self._start_drive(self._to_pick())
        return wp

    # ------------------------------------------------------------------ carry hooks
    def _bottle(self) -> np.ndarray:
        return self.scene.body_pose(BOTTLES[self.bottle])[0]

    def grasp_point(self) -> np.ndarray:
        """``grasp_below_top`` under the bottle's top, on its axis."""
        top = 2 * BOTTLE_HALF_SIZE[2]
        return self._bottle() + np.array([0.0, 0.0, top - self.grasp_below_top])

    def above_grasp(self, grasp: np.ndarray) -> np.ndarray:
        return grasp + np.array([0.0, 0.0, self.approach_height])

    def _held_over(self, xy: np.ndarray, bottom: float) -> np.ndarray:
        """Tool target that puts the held bottle's origin over ``xy`` with its bottom at
        height ``bottom``."""
        held = self.measured_tool() - self._bottle()
        return np.array([xy[0] + held[0], xy[1] + held[1], bottom + held[2]])

    def lift_target(self, grasp: np.ndarray) -> np.ndarray:
        """Straight up until the held bottle's bottom is at ``carry_bottom``."""
        held = self.measured_tool() - self._bottle()
        return np.array([grasp[0], grasp[1], self.carry_bottom + held[2]])

    def _container(self) -> np.ndarray:
        return self.scene.body_pose(CONTAINERS[self.bottle])[0]

    def carry_target(self) -> np.ndarray:
        return self._held_over(self._container()[:2], self.carry_bottom)

    def ready_to_lower(self, target: np.ndarray) -> bool:
        bottle, container = self._bottle(), self._container()
        centred = np.max(np.abs(bottle[:2] - container[:2])) < 0.02
        return self._arrived(target, self.reach_tol) and bool(centred)

    def place_target(self) -> np.ndarray:
        floor = self._container()[2] + 2 * CONTAINER_FLOOR_HALF_THICKNESS
        return self._held_over(self._container()[:2], floor + self.place_clearance)

    def placed(self) -> bool:
        """The bottle stands on its container's floor, inside it."""
        floor = self._container()[2] + 2 * CONTAINER_FLOOR_HALF_THICKNESS
        inside = self.env.task.bottles_in_place(self.scene)[self.bottle]
        return bool(inside and self._bottle()[2] < floor + 0.01)

    def retreat_target(self) -> np.ndarray:
        return np.array([self._release[0], self._release[1], self.retreat_z])

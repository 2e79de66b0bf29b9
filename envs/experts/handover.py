"""Scripted two-arm expert for ALOHA Handover: the left arm picks the object up and holds it
out, the right arm takes it from the side and sets it down on the second mat.

Each arm runs the carry sequence (:class:`~rmb_lerobot.envs.experts.carry.CarryExpert`: above
-> descend -> close -> lift -> carry -> lower -> release -> retreat) with its own hooks, as an
:class:`~rmb_lerobot.envs.experts.multi_arm.ArmTargets` expert; :class:`HandoverExpert`
hands the object over between them:

1. The left arm (the object and mat 1 are in front of it) grasps the handle near its top with
   the gripper pointing down and the fingers closing along x, lifts it and carries it to the
   handover point, midway between the arms (:data:`HANDOVER_XY`), where it holds it.
2. The right arm meanwhile turns its gripper horizontal (pointing +y, towards the other arm,
   fingers along x) and waits behind the handle. Once the left hand is at rest at the handover
   point, it moves in and closes on the lower part of the handle, below the left fingers.
3. The left arm then opens and rises clear; the right arm carries the object over mat 2 and
   lowers it until the task's success test holds (the base plate inside mat 2's box), lets go
   and backs off along -y.

Both arms grasp the handle with the fingers along x: its faces are axis-aligned, so the pads
close flat on two faces. Heights are relative to the handle's centre (its top is 7 cm above).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from rmb_lerobot.envs.experts.base import Waypoint, top_down_rotation
from rmb_lerobot.envs.experts.carry import CarryExpert, CarryPhase
from rmb_lerobot.envs.experts.multi_arm import ArmTargets, MultiArmExpert
from rmb_lerobot.envs.tasks.handover import MAT2, MAT_HALF_SIZE, OBJECT, OBJECT_HANDLE

LEFT, RIGHT = 0, 1  # arm indices of the ALOHA record (envs/robots/aloha.py)
HANDOVER_XY = (0.0, 0.0)  # where the left arm holds the object out (world, m)
# Left pinch point above the table there (m). At 0.3 m the left arm, pointing down 0.47 m out
# from its base, was near full stretch (wrist 0.587 m from the shoulder of 0.606 m reach) and
# its IK stopped converging (measured).
HANDOVER_HEIGHT = 0.2
INTEGRAL_GAIN = 0.1  # of the tool-position correction, per step (see HandoverExpert)


class LeftHandoverArm(ArmTargets, CarryExpert):
    """Pick the object up from above, hold it out at the handover point, let go when told."""

    arm_index = LEFT
    grasp_above_centre = 0.035  # pinch point above the handle's centre (m; its top is 0.07)
    approach_height = 0.08  # pre-grasp height above the grasp point; retreat height (m)
    lift_height = 0.08  # straight up this far before carrying (m)

    def on_reset(self) -> None:
        super().on_reset()
        _, eef_rot = self.eef_world()
        self.rot = top_down_rotation(np.array([1.0, 0.0, 0.0]), eef_rot)
        self.release_now = False  # set by the coordinator once the right arm holds the object
        self.handover = np.array([*HANDOVER_XY, self.table_z() + HANDOVER_HEIGHT])
        self._start = self.measured_tool()
        self._turned = False

    def waypoint(self) -> Waypoint:
        """First turn the hand down where it starts, then the carry sequence.

        Turning and moving to the object (off to the side) at once, the IK's path went through
        the wrist's flipped solution (forearm_roll at its pi limit, the waist shaking); turned
        first, in the arm's own plane, only the waist and wrist_rotate move on the way.
        """
        if not self._turned:
            self._track_tool_speed()
            angle = (self.rot * self._ref_rot.inv()).magnitude()
            self._turned = bool(angle < 0.02)
            return Waypoint(self._start, self.rot, self.open_gripper)
        return super().waypoint()

    @property
    def holding_out(self) -> bool:
        """At rest at the handover point with the object."""
        return self.phase is CarryPhase.CARRY and self._arrived(self.handover, 0.01)

    @property
    def clear(self) -> bool:
        """Opened and risen off the handle: the right arm may carry the object away."""
        return self.phase is CarryPhase.RETREAT and self.reached(self.retreat_target(), 0.02)

    def grasp_point(self) -> np.ndarray:
        return self.scene.geom_pose(OBJECT_HANDLE)[0] + np.array(
            [0.0, 0.0, self.grasp_above_centre]
        )

    def above_grasp(self, grasp: np.ndarray) -> np.ndarray:
        return grasp + np.array([0.0, 0.0, self.approach_height])

    def lift_target(self, grasp: np.ndarray) -> np.ndarray:
        return grasp + np.array([0.0, 0.0, self.lift_height])

    def carry_target(self) -> np.ndarray:
        return self.handover

    def ready_to_lower(self, target: np.ndarray) -> bool:
        return self.release_now

    def place_target(self) -> np.ndarray:
        """Stay where the hand is: the right arm holds the object now."""
        return self._ref_pos.copy()

    def placed(self) -> bool:
        return True


class RightHandoverArm(ArmTargets, CarryExpert):
    """Wait behind the held object, take it from the side, set it down on mat 2."""

    arm_index = RIGHT
    grasp_below_centre = 0.03  # pinch point below the handle's centre (m)
    approach_distance = 0.1  # wait this far back along the approach from the grasp point (m)
    # The approach points +y and this far down (rad). Horizontal keeps wrist_angle near -1.3
    # rad at the handover and -1.6 over mat 2; tilted 45 deg down it crosses 0, where the two
    # roll joints align and the IK drifted to their +-pi limits (measured).
    approach_tilt = 0.0
    # Object bottom above the mat top while carrying (m): its base plate's centre is then 0.1 m
    # up, above RMB's 0.08 m success box, so the episode ends with the object lowered onto the
    # mat's centre, not as it swings in over a corner of the box.
    carry_clearance = 0.09
    place_height = 0.002  # object bottom above the mat top when lowering ends (m)
    place_speed = 0.05  # m/s over the last ``slow_zone`` to the mat

    def on_reset(self) -> None:
        super().on_reset()
        # Gripper pointing +y (towards the other arm) and down, fingers along x, its top (eef
        # y) up: with the fingers along +x instead the gripper is upside down, which the wrist
        # reaches only with forearm_roll at its +-pi limit (IK measured: no convergence).
        tilt = self.approach_tilt
        self.approach = np.array([0.0, np.cos(tilt), -np.sin(tilt)])
        approach, fingers = self.approach, np.array([-1.0, 0.0, 0.0])
        self.rot = Rotation.from_matrix(
            np.column_stack([fingers, np.cross(approach, fingers), approach])
        )
        self.may_grasp = False  # set by the coordinator: the left hand holds the object out
        # Until then, wait behind where the handle will be at the handover.
        below_pinch = LeftHandoverArm.grasp_above_centre + self.grasp_below_centre
        grasp = np.array([*HANDOVER_XY, self.table_z() + HANDOVER_HEIGHT - below_pinch])
        self._wait = self.above_grasp(grasp)
        self.may_carry = False  # set by the coordinator: the left hand is clear of the handle

    def waypoint(self) -> Waypoint:
        if self.phase is CarryPhase.ABOVE and not self.may_grasp:
            self._track_tool_speed()
            return Waypoint(self._wait, self.rot, self.open_gripper)
        return super().waypoint()

    def _object_at(self, bottom_above_mat_top: float) -> np.ndarray:
        """Pinch target that puts the object's origin (its bottom) over mat 2's centre."""
        held = self.measured_tool() - self.scene.body_pose(OBJECT)[0]
        mat = self.scene.body_pose(MAT2)[0]
        return mat + held + np.array([0.0, 0.0, 2 * MAT_HALF_SIZE[2] + bottom_above_mat_top])

    def grasp_point(self) -> np.ndarray:
        return self.scene.geom_pose(OBJECT_HANDLE)[0] - np.array(
            [0.0, 0.0, self.grasp_below_centre]
        )

    def above_grasp(self, grasp: np.ndarray) -> np.ndarray:
        """Back from the grasp point along the approach."""
        return grasp - self.approach_distance * self.approach

    def lift_target(self, grasp: np.ndarray) -> np.ndarray:
        """Hold still where the fingers closed (the left hand still holds the object)."""
        return grasp

    def carry_target(self) -> np.ndarray:
        if not self.may_carry:
            return self._grasp
        return self._object_at(self.carry_clearance)

    def ready_to_lower(self, target: np.ndarray) -> bool:
        if not self.may_carry or not self._arrived(target, 0.01):
            return False
        obj, mat = self.scene.body_pose(OBJECT)[0], self.scene.body_pose(MAT2)[0]
        return bool(np.max(np.abs(obj[:2] - mat[:2])) < 0.01)

    def place_target(self) -> np.ndarray:
        return self._object_at(self.place_height)

    def placed(self) -> bool:
        """The object stands on mat 2 (the task's success test)."""
        return bool(self.env.task.is_success(self.scene))

    def retreat_target(self) -> np.ndarray:
        """Back off along the approach, away from the handle."""
        return self._release - self.approach_distance * self.approach


class HandoverExpert(MultiArmExpert):
    """The two ViperX arms handing the object over (module docstring)."""

    def __init__(self, env: Any, **kwargs: Any) -> None:
        # The ViperX's soft servos (kp 10-265) lag the reference by ~1 s: the default integral
        # gain (0.3 per step) then swung the hands by +-4 mm about their targets (measured).
        kwargs.setdefault("integral_gain", INTEGRAL_GAIN)
        robot = env.unwrapped.robot
        if len(robot.arms) != 2:
            raise ValueError(
                f"the Handover expert drives two arms; robot {robot.name!r} has {len(robot.arms)}"
            )
        self.left = LeftHandoverArm(env, **kwargs)
        self.right = RightHandoverArm(env, **kwargs)
        super().__init__(env, (self.left, self.right))

    def coordinate(self) -> None:
        left, right = self.left, self.right
        if not right.may_grasp and left.holding_out:
            right.may_grasp = True
        if right.may_grasp and right.phase in (CarryPhase.LIFT, CarryPhase.CARRY):
            left.release_now = True  # the right fingers have settled on the handle
        if left.clear:
            right.may_carry = True

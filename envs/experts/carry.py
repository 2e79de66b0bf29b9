"""The pick-and-place phase sequence, in one place: grasp -> close -> lift -> carry -> set down.

Every expert that moves a held object (Pick's object into a basket, Toolbox's box onto the
mat, and the tasks to come: a handover, a tidy-up) runs the same sequence of
:class:`CarryPhase` s with the gripper's pinch point as the tool point:

1. ``ABOVE``: over the grasp point (open), at a height the task chooses;
2. ``DESCEND``: down to the grasp point, the last centimetres slowly, until the hand is at
   rest there;
3. ``CLOSE``: close until the fingers have settled on the object;
4. ``LIFT``: straight up to the carrying height;
5. ``CARRY``: to over the place point, until the task says it may lower;
6. ``LOWER``: down to the place point, the last centimetres slowly, until the task says it is
   placed;
7. ``RELEASE``: open until the fingers have settled;
8. ``RETREAT``: back off upwards.

What differs per task are the hooks: where to grasp (:meth:`CarryExpert.grasp_point`) and
approach it from (:meth:`CarryExpert.above_grasp`), how high to lift
(:meth:`CarryExpert.lift_target`), where to carry (:meth:`CarryExpert.carry_target`), when to
lower (:meth:`CarryExpert.ready_to_lower`), where to set down
(:meth:`CarryExpert.place_target`), when to let go (:meth:`CarryExpert.placed`) and where to
retreat (:meth:`CarryExpert.retreat_target`). The hand keeps one orientation (``self.rot``,
set by the task's :meth:`~rmb_lerobot.envs.experts.base.ScriptedExpert.on_reset`).
"""

from __future__ import annotations

from abc import abstractmethod
from enum import Enum

import numpy as np
from scipy.spatial.transform import Rotation

from rmb_lerobot.envs.experts.base import GripperExpert, Waypoint


class CarryPhase(Enum):
    """The phases of :class:`CarryExpert`, in order."""

    ABOVE = "above"
    DESCEND = "descend"
    CLOSE = "close"
    LIFT = "lift"
    CARRY = "carry"
    LOWER = "lower"
    RELEASE = "release"
    RETREAT = "retreat"


class CarryExpert(GripperExpert):
    """Grasp an object, carry it and set it down: the phase machine, with the task as hooks.

    Subclasses set ``self.rot`` (the hand's orientation for the whole sequence) in their
    :meth:`on_reset` (after calling this one) and implement the hooks. The tolerances are the
    ones the experts were tuned with: a reached target is within 1 cm, the grasp within 3 mm.
    """

    approach_height = 0.05  # retreat this far above where the gripper opened (m)
    grasp_speed = 0.05  # m/s over the last ``slow_zone`` to the grasp point
    place_speed = 0.05  # m/s over the last ``slow_zone`` to the place point
    grasp_tol = 0.003  # hand at rest within this of the grasp point before closing (m)
    reach_tol = 0.01  # the approach and lift targets count as reached within this (m)

    def on_reset(self) -> None:
        """Start at ``ABOVE`` with no grasp, place or release point yet."""
        super().on_reset()
        self.phase = CarryPhase.ABOVE
        self.rot = Rotation.identity()  # the task's on_reset sets the hand orientation
        self._grasp = np.zeros(3)  # pinch target while closing
        self._place = np.zeros(3)  # pinch target while lowering
        self._release = np.zeros(3)  # pinch target while opening

    # ------------------------------------------------------------------ task hooks
    @abstractmethod
    def grasp_point(self) -> np.ndarray:
        """Where the pinch point closes on the object (world frame), read every step of the
        approach (the object may still move)."""

    @abstractmethod
    def above_grasp(self, grasp: np.ndarray) -> np.ndarray:
        """The approach target above ``grasp``: clear of whatever the way there passes."""

    @abstractmethod
    def lift_target(self, grasp: np.ndarray) -> np.ndarray:
        """Where to lift to from ``grasp`` (where the gripper closed), before carrying."""

    @abstractmethod
    def carry_target(self) -> np.ndarray:
        """The pinch target while carrying (read every step, so it can follow the held
        object's slip or swing)."""

    @abstractmethod
    def ready_to_lower(self, target: np.ndarray) -> bool:
        """Whether the carry to ``target`` is done and the lowering may start."""

    @abstractmethod
    def place_target(self) -> np.ndarray:
        """Where the pinch point goes to set the object down (read once, when lowering
        starts: the hand must not chase the object once it touches down)."""

    @abstractmethod
    def placed(self) -> bool:
        """Whether the object is set down and the gripper may open."""

    def retreat_target(self) -> np.ndarray:
        """Where the open hand goes last: ``approach_height`` above where it let go."""
        return self._release + np.array([0.0, 0.0, self.approach_height])

    # ------------------------------------------------------------------ phases
    def waypoint(self) -> Waypoint:
        """The current target of the sequence; advances the phase when its condition holds."""
        self._track_tool_speed()
        if self.phase is CarryPhase.ABOVE:
            target = self.above_grasp(self.grasp_point())
            if self.reached(target, self.reach_tol):
                self.phase = CarryPhase.DESCEND
            return Waypoint(target, self.rot, self.open_gripper)
        if self.phase is CarryPhase.DESCEND:
            grasp = self.grasp_point()
            if self._arrived(grasp, self.grasp_tol):
                self.phase = CarryPhase.CLOSE
                self._grasp = grasp.copy()
            return Waypoint(self._slowly(grasp, self.grasp_speed), self.rot, self.open_gripper)
        if self.phase is CarryPhase.CLOSE:
            if self._gripper_settled():
                self.phase = CarryPhase.LIFT
            return Waypoint(self._grasp, self.rot, self.closed_gripper)
        if self.phase is CarryPhase.LIFT:
            target = self.lift_target(self._grasp)
            if self.reached(target, self.reach_tol):
                self.phase = CarryPhase.CARRY
            return Waypoint(target, self.rot, self.closed_gripper)
        if self.phase is CarryPhase.CARRY:
            target = self.carry_target()
            if self.ready_to_lower(target):
                self.phase = CarryPhase.LOWER
                self._place = self.place_target()
            return Waypoint(target, self.rot, self.closed_gripper)
        if self.phase is CarryPhase.LOWER:
            if self.placed():
                self.phase = CarryPhase.RELEASE
                self._count = 0
                self._release = self._ref_pos.copy()
            target = self._slowly(self._place, self.place_speed)
            return Waypoint(target, self.rot, self.closed_gripper)
        if self.phase is CarryPhase.RELEASE:
            if self._gripper_settled():
                self.phase = CarryPhase.RETREAT
            return Waypoint(self._release, self.rot, self.open_gripper)
        return Waypoint(self.retreat_target(), self.rot, self.open_gripper)

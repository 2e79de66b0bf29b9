"""Scripted two-arm expert for ALOHA Cable: the dual-UR5e expert's handover, tuned for the
ViperX arms and RMB's loose cable with poles up to 24 cm apart.

Success rule: RMB defines no reward for MujocoAlohaCableEnv, so the env uses RMB's UR5e Cable
rule (:meth:`rmb_lerobot.envs.tasks.cable.CableTask.is_success`) on the ALOHA layout: the
cable routed into the S shape (it crosses between the poles going +y, stays below the pole tops
+ 1 cm, and the end box lies beyond pole 2 in x and at least 5 cm on the -y side of the pole
line).

The arms share the work as the dual UR5e's do
(:class:`~rmb_lerobot.envs.experts.dual_cable.DualCableExpert`): the right arm (its base at
y = -0.469, next to the end box) drags the box through the half circle to below the gap and
lets go; the left arm (by the poles) takes it, lifts cable over the gap, lowers it beyond and
wraps it around pole 2. RMB's own demos are teleoperated with both arms (its operation script
only brings the left hand above the connector). What ALOHA needs changed, each measured:

- Both hands first turn to their grasp orientation where they start (as the Handover expert's
  left hand does): turning while moving, the IK went through the wrist's flipped solution
  (``forearm_roll`` at its pi limit) and the right hand never reached the box.
- The pinch point grasps 2.2 cm above the box centre (single-arm expert: 0.6 cm): the ViperX
  fingertips reach below the pinch point, and lower they pressed on the table.
- After lowering the box beyond the gap, the left hand first drags it ``pull`` further along
  +y, then right past pole 2: the cable is loose (its connector slides, unlike the UR5e scene's
  fixed one), so without the pull the slack in the gap slid over pole 2 as the box went right
  (worlds 4 and 5, gaps 12 and 9 cm: 1 of 6 episodes succeeded; with 0.12 m, 12 of 12 in all
  worlds, random shift 0.03, joint mode; 100 of 100 in joint and in eef_rel mode over 100
  episodes, ``benchmarks/RESULTS.md``).
- Faster lift, final and drag legs (0.15, 0.15 and 0.2 m/s): at the single-arm speeds the
  two-arm sequence ended at ~570 of the 600 steps and timed out in some worlds.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rmb_lerobot.envs.experts.base import Waypoint
from rmb_lerobot.envs.experts.cable import RIGHT, UP, Leg
from rmb_lerobot.envs.experts.dual_cable import DualCableExpert, LeftCableArm, RightCableArm
from rmb_lerobot.envs.experts.multi_arm import MultiArmExpert


class _TurnDownFirst:
    """Mixin: turn the hand to its grasp orientation where it starts before moving anywhere
    (the ViperX's IK otherwise flips the wrist on the way; module docstring)."""

    def on_reset(self) -> None:
        super().on_reset()  # type: ignore[misc]
        self._start = self.measured_tool()  # type: ignore[attr-defined]
        self._turned = False

    def waypoint(self) -> Waypoint:
        if not self._turned:
            self._track_tool_speed()  # type: ignore[attr-defined]
            rot = self._grasp_rot  # type: ignore[attr-defined]
            angle = (rot * self._ref_rot.inv()).magnitude()  # type: ignore[attr-defined]
            self._turned = bool(angle < 0.02)
            return Waypoint(self._start, rot, self.open_gripper)  # type: ignore[attr-defined]
        return super().waypoint()  # type: ignore[misc]


class AlohaRightCableArm(_TurnDownFirst, RightCableArm):
    """The right ViperX: grasp the end box, drag it below the gap, let go, park."""

    grasp_dz = 0.022  # m: the fingertips stay off the table
    drag_speed = 0.2  # m/s


class AlohaLeftCableArm(_TurnDownFirst, LeftCableArm):
    """The left ViperX: take the box over the gap, pull the cable taut, wrap it round pole 2."""

    grasp_dz = 0.022  # m
    lift_speed, final_speed = 0.15, 0.15  # m/s
    pull = 0.12  # m: drag along +y after lowering beyond the gap, before going right

    def plan_route(self) -> list[Leg]:
        """The dual expert's left route with the pull inserted after lowering: lowered ->
        ``pull`` along +y -> right past pole 2 (at that y) -> down its far side."""
        legs = super().plan_route()
        lowered, right, down = legs[-3], legs[-2], legs[-1]
        y = lowered.pos[1] + self.pull
        pulled = Leg(np.array([lowered.pos[0], y, lowered.pos[2]]), UP, right.speed)
        right = Leg(np.array([right.pos[0], y, right.pos[2]]), RIGHT, right.speed)
        return [*legs[:-2], pulled, right, down]


class AlohaCableExpert(DualCableExpert):
    """ALOHA's two arms routing the cable with a handover (module docstring)."""

    def __init__(self, env: Any, **kwargs: Any) -> None:
        robot = env.unwrapped.robot
        if len(robot.arms) != 2:
            raise ValueError(
                f"the ALOHA Cable expert drives two arms; robot {robot.name!r} has "
                f"{len(robot.arms)}"
            )
        self.left = AlohaLeftCableArm(env, **kwargs)
        self.right = AlohaRightCableArm(env, **kwargs)
        MultiArmExpert.__init__(self, env, (self.left, self.right))

"""Scripted two-arm expert for the dual-UR5e Cable task: the right arm starts the route, the
left arm finishes it after a handover on the table.

Success rule: RMB defines no reward for MujocoUR5eDualCable, so the env uses RMB's single-arm
Cable rule (:meth:`rmb_lerobot.envs.tasks.cable.CableTask.is_success`): the cable routed into
the S shape, i.e. it crosses between the poles going +y, stays below the pole tops + 1 cm, and
the end box lies beyond pole 2 in x and at least 5 cm on the right (-y) of the pole line.

Why two arms: the route of the single-arm :class:`~rmb_lerobot.envs.experts.cable.CableExpert`
spans both arms' workspaces. Its half circle reaches y ~ -0.4 (beyond the left arm's reach for
the far pole worlds, 1.6 cm short at x = -0.05, y = -0.35 with the gripper pointing down),
while its far side (y ~ +0.18, x up to 0.15 m) is out of the right arm's reach (1.7 cm short
at x = 0.15, y = 0.15; measured with the backend's IK from each arm's start pose). So:

1. The right arm (near the end box, y = -0.28) grasps the box, drags it along the single-arm
   expert's half circle and up the gap line to 11 cm before the pole line (the cable forms
   the U), lets go and backs off: up, then to a parking spot over its own side of the table.
2. Meanwhile the left arm waits beside the poles, out of the right arm's way. Once the right
   hand has risen clear of the box, it grasps the box where the right arm left it and does the
   rest of the single-arm route: drag it 4 cm on along the gap line (the cable lies straight
   on that line again), lift 0.15 m of cable, over the gap, down, right past pole 2 and down
   its far side (the cable wraps around pole 2 into the S).

Both arms reuse :class:`CableExpert`'s grasp and route planning (the left arm takes the legs
after the half circle, the right arm the legs up to it), each as an
:class:`~rmb_lerobot.envs.experts.multi_arm.ArmTargets` expert assembled into the 14-D
action by :class:`~rmb_lerobot.envs.experts.multi_arm.MultiArmExpert`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rmb_lerobot.envs.experts.base import Waypoint
from rmb_lerobot.envs.experts.cable import CableExpert, Leg, Phase
from rmb_lerobot.envs.experts.multi_arm import ArmTargets, MultiArmExpert
from rmb_lerobot.envs.tasks.cable import POLE1, POLE2

LEFT, RIGHT = 0, 1  # arm indices of the UR5E_DUAL record (envs/robots/dual_ur5e.py)


class RightCableArm(ArmTargets, CableExpert):
    """Grasp the end box, drag it through the half circle to before the gap, let go, park."""

    arm_index = RIGHT
    # The box is let go 4 cm further from the gap than the single-arm expert lifts it, so the
    # left arm drags it the last 4 cm along the gap line before lifting: the cable it lifts then
    # lies straight on that line as in one continuous drag (handing over at the lift point, the
    # relaxed cable missed the gap in ~1 of 6 episodes, landing on a pole).
    below_gap = CableExpert.below_gap + 0.04  # m
    # The free move from the start pose to above the box (no object held) at 0.25 m/s saves
    # ~25 of the 600 steps; the left arm's approach stays at 0.15 (faster, its grasps were
    # deeper and the box missed the gap more often).
    approach_speed = 0.25  # m/s
    clear_height = 0.04  # the hand is clear of the box this far above its release point (m)
    park_xy = (-0.15, -0.25)  # parking spot of the pinch point over the right half (world, m)
    park_height = 0.15  # above the table (m): clear of the cable's U on the table

    def on_reset(self) -> None:
        super().on_reset()
        self._lifted = False

    def plan_route(self) -> list[Leg]:
        """The single-arm route up to the leg that ends before the gap (its half circle)."""
        return super().plan_route()[: self.half_circle_points + 1]

    @property
    def clear_of_box(self) -> bool:
        """Let go of the box and risen clear of it: the left arm may take over."""
        return self.phase is Phase.RETREAT and self._lifted

    def waypoint(self) -> Waypoint:
        if self.phase is Phase.ABOVE:
            self.max_step = self.approach_speed * self.dt
        elif self.phase is Phase.DESCEND:
            self.max_step = self._cruise_step
        retreating = self.phase is Phase.RETREAT  # before the step that may start retreating
        wp = super().waypoint()
        if not retreating:
            return wp
        # Straight up first (the open fingers must not catch the cable trailing the box), then
        # away to the parking spot.
        if not self._lifted:
            self._lifted = self.measured_tool()[2] > self._hold[2] + self.clear_height
            return wp
        park = np.array([*self.park_xy, self.table_z() + self.park_height])
        return Waypoint(park, wp.rot, self.open_gripper)


class LeftCableArm(ArmTargets, CableExpert):
    """Wait beside the poles; after the handover grasp the box and finish the route."""

    arm_index = LEFT
    # Cable lifted to go beyond the gap (single arm: 0.2 m). Measured (joint, random shift
    # 0.03): with 0.2 m the lowered cable swung onto pole 2 in worlds 0 and 1 (poles nearest
    # the connector) and slid off it in 5 of 100 episodes; 0.15 and 0.17 m: 16 of 16 such
    # episodes and 60 of 60 in all worlds. 0.15 m lifts and lowers in ~20 fewer steps.
    hang = 0.15  # m
    # Waiting spot this far beyond (+y) the pole line (m): 16 cm from the right hand at the
    # handover, two grippers' depth (2 x ~4 cm) apart with margin.
    wait_dy = 0.05
    wait_height = 0.1  # pinch point above the table while waiting (poles: 6 cm tall)

    def on_reset(self) -> None:
        super().on_reset()
        self.waiting = True
        pole1, pole2 = self.scene.geom_pose(POLE1)[0], self.scene.geom_pose(POLE2)[0]
        gap_x = 0.5 * (pole1[0] + pole2[0])
        self._wait = Waypoint(
            np.array([gap_x, pole1[1] + self.wait_dy, self.table_z() + self.wait_height]),
            self._grasp_rot,  # fingers across the box: the box heads +y at the handover too
            self.open_gripper,
        )

    def take_over(self) -> None:
        """Start grasping the box where it lies now (grasp orientation from its pose now)."""
        CableExpert.on_reset(self)
        self.waiting = False

    def plan_route(self) -> list[Leg]:
        """The single-arm route from the leg before the gap on: drag the box the last 4 cm to
        it, lift, over, down, around pole 2."""
        return super().plan_route()[self.half_circle_points :]

    def waypoint(self) -> Waypoint:
        return self._wait if self.waiting else super().waypoint()


class DualCableExpert(MultiArmExpert):
    """The two arms of the dual UR5e routing the cable with a handover (module docstring)."""

    def __init__(self, env: Any, **kwargs: Any) -> None:
        self.left = LeftCableArm(env, **kwargs)
        self.right = RightCableArm(env, **kwargs)
        super().__init__(env, (self.left, self.right))

    def coordinate(self) -> None:
        if self.left.waiting and self.right.clear_of_box:
            self.left.take_over()

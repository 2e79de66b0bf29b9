"""Scripted expert of the G1 Bottles task: each hand grasps its bottle from above and lifts it.

Each arm runs the :class:`~rmb_lerobot.envs.experts.carry.CarryExpert` sequence up to the
carry (there is nothing to set down: success is both bottles held up), with the hand turned
palm down, fingers pointing forward: over the bottle, down until the bottle's top is inside the
hand (the record's ``<side>_grasp`` point on the bottle's axis, :attr:`BottleArm.grip_depth`
below its top), close, lift by :attr:`BottleArm.lift`. The left hand takes ``bottle1``, the
right hand ``bottle2``; :class:`BottlesExpert` assembles the two arms' targets into the 16-D
action (:mod:`~rmb_lerobot.envs.experts.multi_arm`) and starts the lift only once both hands
hold their bottle, so neither lifted bottle swings into the other hand's way.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from rmb_lerobot.envs.experts.carry import CarryExpert, CarryPhase
from rmb_lerobot.envs.experts.multi_arm import ArmTargets, MultiArmExpert
from rmb_lerobot.envs.tasks.bottles import BOTTLE_HALF_HEIGHT, BOTTLES

# The hands' orientation (palm link axes in the world): palm down, fingers forward turned by
# FINGER_YAW towards the middle and tilted FINGER_TILT down, which keeps every arm joint at
# least 0.5 rad inside its limits from the approach to the lift (fingers straight forward
# need the wrist pitch at its limit). The left palm faces its -y axis, the right its +y axis.
FINGER_YAW = 50.0  # deg
FINGER_TILT = 20.0  # deg


def hand_rotation(arm_index: int) -> Rotation:
    """Palm-down grasp orientation of the left (0) or right (1) hand in the world."""
    sign = 1.0 if arm_index == 0 else -1.0
    return (
        Rotation.from_euler("z", -sign * FINGER_YAW, degrees=True)
        * Rotation.from_euler("y", FINGER_TILT, degrees=True)
        * Rotation.from_euler("x", sign * 90.0, degrees=True)
    )


class BottleArm(ArmTargets, CarryExpert):
    """One hand of the G1: grasp bottle ``BOTTLES[arm_index]`` at its top and lift it."""

    grip_depth = 0.03  # m: the grasp point below the bottle's top
    approach = 0.08  # m: above the grasp point before descending
    lift = 0.16  # m: lifted above the grasp point

    def __init__(self, env: Any, arm_index: int, **kwargs: Any) -> None:
        self.arm_index = arm_index
        super().__init__(env, **kwargs)
        self.bottle = BOTTLES[arm_index]
        self.may_lift = False  # set by BottlesExpert once both hands hold their bottle

    def on_reset(self) -> None:
        super().on_reset()
        self.rot = hand_rotation(self.arm_index)
        self.may_lift = False

    def grasp_point(self) -> np.ndarray:
        pos, _ = self.scene.body_pose(self.bottle)
        return pos + np.array([0.0, 0.0, 2 * BOTTLE_HALF_HEIGHT - self.grip_depth])

    def above_grasp(self, grasp: np.ndarray) -> np.ndarray:
        return grasp + np.array([0.0, 0.0, self.approach])

    def lift_target(self, grasp: np.ndarray) -> np.ndarray:
        return grasp + np.array([0.0, 0.0, self.lift if self.may_lift else 0.0])

    def carry_target(self) -> np.ndarray:
        return self.lift_target(self._grasp)

    def ready_to_lower(self, target: np.ndarray) -> bool:
        return False  # hold the bottle up: the task ends when both are up

    def place_target(self) -> np.ndarray:
        return self.carry_target()

    def placed(self) -> bool:
        return False

    @property
    def holding(self) -> bool:
        """Whether the hand has closed on the bottle (lifting or holding)."""
        return self.phase in (CarryPhase.LIFT, CarryPhase.CARRY)


class BottlesExpert(MultiArmExpert):
    """The two hands of the G1, each on its bottle; both lift once both hold."""

    def __init__(self, env: Any, **kwargs: Any) -> None:
        super().__init__(env, [BottleArm(env, i, **kwargs) for i in range(2)])

    def coordinate(self) -> None:
        both = all(arm.holding for arm in self.arms)
        for arm in self.arms:
            arm.may_lift = arm.may_lift or both

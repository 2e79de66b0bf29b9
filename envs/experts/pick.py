"""Scripted expert for the Pick task: grasp the named object from above, drop it into the basket.

The instruction is read from the task (privileged, like the object poses): the expert grasps
``task.target_object`` with the gripper pointing down and its fingers closing along a direction
whose finger zone is clear of the neighbours (:func:`~rmb_lerobot.envs.tasks.pick.best_grasp_yaw`;
across the short side for boxes and the banana), lifts it until its base clears every other
object and the baskets' rims, carries it over the named basket's centre, lowers it to just above
the basket floor and lets go. While carrying, targets are placed so that the *object* ends up
centred (the measured pinch-to-object offset absorbs any slip or swing in the grasp), and the
last centimetres to the grasp and to the floor are covered slowly (no overshoot).
"""

from __future__ import annotations

import numpy as np

from rmb_lerobot.envs.experts.base import top_down_rotation
from rmb_lerobot.envs.experts.carry import CarryExpert, CarryPhase
from rmb_lerobot.envs.tasks.pick import FINGER_REACH, PickTask, best_grasp_yaw, grasp_yaws

Phase = CarryPhase  # Pick's phases are the carry sequence's


class PickExpert(CarryExpert):
    """Tool point: the gripper's pinch point; the carry sequence with Pick's hooks."""

    approach_height = 0.05  # pinch point above the tallest object on the way to a grasp (m)
    carry_clearance = 0.03  # object base above the objects on its way and the rims (m)
    path_margin = 0.02  # objects nearer the carrying path than this (plus sizes) count (m)
    wall_margin = 0.015  # object's side to the basket's near wall at the drop point (m)
    drop_height = 0.01  # object base above the basket floor when let go (m)
    grasp_speed, place_speed = 0.05, 0.05  # m/s

    def on_reset(self) -> None:
        super().on_reset()
        task: PickTask = self.env.task
        self._obj = task.target_object
        self._basket = task.target_basket
        index = task.objects.index(self._obj)
        positions = np.array([self.scene.body_pose(o.body)[0][:2] for o in task.objects])
        yaw = best_grasp_yaw(index, positions, task.objects)
        yaw = grasp_yaws(self._obj)[0] if yaw is None else yaw
        _, eef_rot = self.eef_world()
        self.rot = top_down_rotation(np.array([np.cos(yaw), np.sin(yaw), 0.0]), eef_rot)
        tallest = max(o.height for o in task.objects)
        self._transit_z = self.table_z() + tallest + self.approach_height
        self._carry_base_z = self._carry_height(positions, index)
        self._drop = self._drop_xy()

    # ------------------------------------------------------------------ helpers
    def _carry_height(self, positions: np.ndarray, index: int) -> float:
        """Height of the object's base while carrying: clear of the baskets' rims and of every
        object near the straight path to the basket (the gripper is above the object)."""
        task: PickTask = self.env.task
        start = positions[index]
        goal = self.scene.body_pose(self._basket.body)[0][:2]
        reach = max(*self._obj.footprint, FINGER_REACH)
        heights = [b.height for b in task.baskets]
        for i, other in enumerate(task.objects):
            if i == index:
                continue
            t = np.clip((positions[i] - start) @ (goal - start) / np.sum((goal - start) ** 2), 0, 1)
            distance = np.linalg.norm(positions[i] - (start + t * (goal - start)))
            if distance < reach + max(other.footprint) + self.path_margin:
                heights.append(other.height)
        return self.table_z() + max(heights) + self.carry_clearance

    def _drop_xy(self) -> np.ndarray:
        """Where the object's base centre goes: in the basket, as near the robot as its walls
        allow (the far basket is at the edge of the arm's reach)."""
        basket = self.scene.body_pose(self._basket.body)[0][:2]
        axes = self.scene.body_pose(self._obj.body)[1][:2, :2]
        half_x = np.abs(axes[0]) @ np.asarray(self._obj.footprint)  # extent along world x
        slack = max(0.0, self._basket.inner[0] - half_x - self.wall_margin)
        return basket - np.array([slack, 0.0])

    def _over_basket(self, base_z: float) -> np.ndarray:
        """Pinch target that puts the object's base centre over the drop point at ``base_z``."""
        held = self.measured_tool() - self.scene.body_pose(self._obj.body)[0]
        return np.array([*(self._drop + held[:2]), base_z + held[2]])

    def _object_over_drop(self, tol: float) -> bool:
        rel = self.scene.body_pose(self._obj.body)[0][:2] - self._drop
        return bool(np.max(np.abs(rel)) < tol)

    # ------------------------------------------------------------------ carry hooks
    def grasp_point(self) -> np.ndarray:
        """The object's grasp point (its record's, in the object's frame)."""
        pos, rot = self.scene.body_pose(self._obj.body)
        return pos + rot @ np.asarray(self._obj.grasp)

    def above_grasp(self, grasp: np.ndarray) -> np.ndarray:
        """Above the tallest object: the way there may pass over any of them."""
        return np.array([*grasp[:2], self._transit_z])

    def lift_target(self, grasp: np.ndarray) -> np.ndarray:
        """Straight up until the object's base is at the carrying height."""
        return np.array([*grasp[:2], self._over_basket(self._carry_base_z)[2]])

    def carry_target(self) -> np.ndarray:
        """The object's base centre over the drop point, at the carrying height."""
        return self._over_basket(self._carry_base_z)

    def ready_to_lower(self, target: np.ndarray) -> bool:
        """Over the drop point and at rest, the object too. Only xy matters here (the lowering
        follows): near the edge of the arm's reach, the hand may hang a centimetre below a
        high carrying target."""
        still = self._tool_speed < self.still_speed
        return self.reached(target, 0.01, xy_only=True) and still and self._object_over_drop(0.01)

    def place_target(self) -> np.ndarray:
        """The object's base ``drop_height`` above the basket floor."""
        floor = self.scene.body_pose(self._basket.body)[0][2] + self._basket.floor
        return self._over_basket(floor + self.drop_height)

    def placed(self) -> bool:
        """At the place point and at rest."""
        return self._arrived(self._place, 0.005)

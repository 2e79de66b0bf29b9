"""The carry sequence (grasp -> close -> lift -> carry -> lower -> release -> retreat) with a
task of its own: the hooks are all a new pick-and-place expert writes.

The world is made up here in plain numpy: a point hand (its three joints are the pinch point's
world position, reached in one step) with a gripper that closes at a bounded rate, and a box
that the closed gripper carries when it closed around the box's centre. The task: put the box
on a goal spot on the table.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from rmb_lerobot.envs.base import RmbEnv
from rmb_lerobot.envs.experts.carry import CarryExpert, CarryPhase
from rmb_lerobot.envs.point_arm import PointArmBackend, point_arm_robot
from rmb_lerobot.envs.scene import SceneState
from rmb_lerobot.envs.tasks.base import Task
from rmb_lerobot.envs.workspace import RMB_TABLE

TOP = RMB_TABLE.table.top_z
HALF = 0.02  # the box's half height (m)
BOX_START = np.array([0.15, -0.1, TOP + HALF])
GOAL = np.array([-0.1, 0.15])
HAND = point_arm_robot("hand", home=(0.0, 0.0, TOP + 0.3), root_frame="world", tip="pinch")


class BoxBackend(PointArmBackend):
    """The hand reaches its target in one step; the gripper moves 0.2 a step; a held box
    moves with the hand and, let go, rests on the table."""

    joint_bound = 2.0

    def __init__(self, task: Task) -> None:
        super().__init__(task, HAND, control_dt=0.05)
        self.box, self.grip_offset = BOX_START.copy(), None

    def poses(self) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        return {"pinch": (self.q[:3].copy(), np.eye(3)), "box": (self.box.copy(), np.eye(3))}

    def reset(self, world_offset: np.ndarray, home: np.ndarray) -> None:
        super().reset(world_offset, home)
        self.box, self.grip_offset = BOX_START + world_offset, None

    def step(self) -> None:
        self.q[:3] = self.target[:3]
        self.q[3] += np.clip(self.target[3] - self.q[3], -0.2, 0.2)
        hand = self.q[:3]
        if self.q[3] > 0.5 and self.grip_offset is None:
            if np.linalg.norm(hand - self.box) < 0.005:
                self.grip_offset = self.box - hand
        elif self.q[3] <= 0.5:
            self.grip_offset = None
        if self.grip_offset is not None:
            self.box = hand + self.grip_offset
        else:
            self.box[2] = max(TOP + HALF, self.box[2] - 0.05)  # let go: it falls to the table
        self.t += self.control_dt

    def world_to_root(self, arm: int, pos: np.ndarray, rot: np.ndarray) -> np.ndarray:
        return np.array([*pos, *Rotation.from_matrix(rot).as_quat(scalar_first=True)])


class BoxOnGoal(Task):
    """The box on the table within 5 mm of the goal spot, let go."""

    name = "box_on_goal"
    description = "Put the box on the goal spot."
    world_offsets = np.array([[0.0, 0.0, 0.0], [0.05, 0.1, 0.0], [-0.1, 0.05, 0.0]])
    max_episode_steps = 400

    def is_success(self, scene: SceneState) -> bool:
        box = scene.body_pose("box")[0]
        on_table = abs(box[2] - (TOP + HALF)) < 1e-6
        return bool(np.linalg.norm(box[:2] - GOAL) < 0.005 and on_table)


class BoxExpert(CarryExpert):
    """The hooks for :class:`BoxOnGoal`: all the task-specific code a carry expert needs."""

    carry_height = 0.15  # box centre above the table while carrying (m)

    def on_reset(self) -> None:
        super().on_reset()
        self.rot = Rotation.from_euler("x", np.pi)  # pointing down

    def _held(self) -> np.ndarray:
        return self.measured_tool() - self.scene.body_pose("box")[0]

    def grasp_point(self) -> np.ndarray:
        return self.scene.body_pose("box")[0]

    def above_grasp(self, grasp: np.ndarray) -> np.ndarray:
        return grasp + np.array([0.0, 0.0, 0.1])

    def lift_target(self, grasp: np.ndarray) -> np.ndarray:
        return np.array([*grasp[:2], TOP + self.carry_height])

    def carry_target(self) -> np.ndarray:
        return np.array([*GOAL, TOP + self.carry_height]) + self._held()

    def ready_to_lower(self, target: np.ndarray) -> bool:
        return self._arrived(target, 0.005)

    def place_target(self) -> np.ndarray:
        return np.array([*GOAL, TOP + HALF]) + self._held()

    def placed(self) -> bool:
        return self._arrived(self._place, 0.002)


@pytest.mark.parametrize("mode", ["joint", "eef_rel"])
@pytest.mark.parametrize("world", [0, 1, 2])
def test_the_carry_sequence_puts_the_box_on_the_goal_in_order(world, mode):
    task = BoxOnGoal(RMB_TABLE)
    env = RmbEnv(task, BoxBackend(task), action_mode=mode, cameras=(), terminate_on_success=False)
    obs, _ = env.reset(seed=world, options={"world_idx": world})
    expert = BoxExpert(env)
    expert.reset()
    phases = [expert.phase]
    for _ in range(task.max_episode_steps):
        obs, _, _, _, info = env.step(expert(obs))
        if expert.phase is not phases[-1]:
            phases.append(expert.phase)
        if expert.phase is CarryPhase.RETREAT and info["is_success"]:
            break
    assert phases == list(CarryPhase)  # every phase once, in order
    assert info["is_success"], env.sim.box
    # Closed on the box's centre: the hand let go where the box now rests.
    np.testing.assert_allclose(expert._release, env.sim.box, atol=0.005)

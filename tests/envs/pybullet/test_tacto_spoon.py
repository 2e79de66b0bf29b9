"""TactoSawyerSpoon in PyBullet: RMB's success rule, which end each world puts up, a still spoon.

One physics-only env serves the module (building it takes about a second). The expert's success
rate is measured outside the tests (100 episodes per action mode: see the expert's module).
"""

from __future__ import annotations

import numpy as np
import pybullet as p
import pytest

from rmb_lerobot.envs.base import RmbEnv
from rmb_lerobot.envs.registry import compose
from rmb_lerobot.envs.tasks.tacto_spoon import (
    BOWL_HALF_LENGTH,
    BOX_FLOOR_TOP,
    BOX_INNER_HALF,
    GREEN_BOX_POS,
    HANDLE_END,
    RED_BOX_POS,
    SPOON,
    SPOON_RPY_DEG,
    SPOON_THICKNESS,
    START_BOX_POS,
    TactoSpoonTask,
    spoon_quat_wxyz,
)

LYING = (1.0, 0.0, 0.0, 0.0)  # the spoon flat on its back (handle along +y)
STANDING_BOWL_DOWN = spoon_quat_wxyz(0)
SETTLE_STEPS = 67  # 2 s at 0.03 s per step


@pytest.fixture(scope="module")
def env():
    env = compose(TactoSpoonTask(), robot="sawyer", simulator="pybullet", cameras=())
    yield env
    env.close()


def _success_with_spoon_at(env: RmbEnv, world_idx: int, position, quat_wxyz=LYING) -> bool:
    env.reset(seed=0, options={"world_idx": world_idx})
    env.sim.reset_body(SPOON, position, quat_wxyz)
    return env.task.is_success(env.sim.scene)


def _at(box, dz: float, dx: float = 0.0, dy: float = 0.0) -> np.ndarray:
    return np.array(box) + np.array([dx, dy, dz])


@pytest.mark.parametrize(
    ("world_idx", "goal", "wrong"),
    [(0, RED_BOX_POS, GREEN_BOX_POS), (1, GREEN_BOX_POS, RED_BOX_POS)],
)
def test_spoon_in_the_worlds_goal_box_succeeds_and_in_the_other_box_does_not(
    env, world_idx, goal, wrong
):
    assert _success_with_spoon_at(env, world_idx, _at(goal, -0.03))
    assert _success_with_spoon_at(env, world_idx, _at(goal, 0.0), STANDING_BOWL_DOWN)
    assert not _success_with_spoon_at(env, world_idx, _at(wrong, -0.03))
    assert not _success_with_spoon_at(env, world_idx, _at(START_BOX_POS, -0.03))


def test_goal_heights_follow_rmbs_reward(env):
    """RMB: below 0.3 - 0.1 m in world 0 (red), below 0.3 + 0.1 m in world 1 (green)."""
    assert _success_with_spoon_at(env, 0, _at(RED_BOX_POS, 0.09))  # z 0.19
    assert not _success_with_spoon_at(env, 0, _at(RED_BOX_POS, 0.11))  # z 0.21
    assert _success_with_spoon_at(env, 1, _at(GREEN_BOX_POS, 0.29))  # z 0.39
    assert not _success_with_spoon_at(env, 1, _at(GREEN_BOX_POS, 0.31))  # z 0.41


def test_goal_box_area_is_rmbs_plus_minus_twelve_centimetres(env):
    assert _success_with_spoon_at(env, 0, _at(RED_BOX_POS, -0.03, dx=0.11, dy=-0.11))
    assert not _success_with_spoon_at(env, 0, _at(RED_BOX_POS, -0.03, dx=0.13))
    assert not _success_with_spoon_at(env, 1, _at(GREEN_BOX_POS, -0.03, dy=0.13))


def test_spoon_quaternion_is_pybullets_euler_of_rmbs_angles():
    for world_idx, rpy in enumerate(SPOON_RPY_DEG):
        x, y, z, w = p.getQuaternionFromEuler(np.deg2rad(rpy).tolist())
        np.testing.assert_allclose(spoon_quat_wxyz(world_idx), [w, x, y, z], atol=1e-12)


@pytest.mark.parametrize(("world_idx", "handle_up"), [(0, True), (1, False)])
def test_world_puts_the_end_up_rmbs_world_does(env, world_idx, handle_up):
    """RMB: roll +90 deg stands the spoon on its bowl (handle up), roll -90 deg on its handle."""
    env.reset(seed=0, options={"world_idx": world_idx})
    _, rot = env.sim.scene.body_pose(SPOON)
    handle_axis_z = rot[2, 1]  # the spoon frame's +y runs from the bowl to the handle's tip
    assert (handle_axis_z > 0.99) == handle_up
    assert (handle_axis_z < -0.99) == (not handle_up)


@pytest.mark.parametrize("world_idx", [0, 1])
def test_spoon_rests_upright_in_the_start_box(env, world_idx):
    """Over 2 s with the robot holding its start pose the spoon settles within 1 cm of RMB's
    pose (measured: 4 mm in world 0, 8 mm in world 1, where it leans on the -x and -y walls'
    top edges) and stops, still upright, its lower end on the start box's floor."""
    env.reset(seed=0, options={"world_idx": world_idx})
    start, _ = env.sim.scene.body_pose(SPOON)
    hold = env.command.astype(np.float32)
    for _ in range(SETTLE_STEPS):
        env.step(hold)
    pos, rot = env.sim.scene.body_pose(SPOON)
    speed = np.linalg.norm(env.sim.scene.joint_velocity(SPOON))
    assert np.linalg.norm(pos - start) < 0.01
    assert speed < 1e-3
    assert abs(rot[2, 1]) > 0.95  # still standing: the spoon's axis within 18 deg of vertical
    ends = [
        pos + rot @ np.array([0.0, y, SPOON_THICKNESS / 2]) for y in (-BOWL_HALF_LENGTH, HANDLE_END)
    ]
    lower = min(ends, key=lambda end: end[2])
    assert np.all(np.abs(lower[:2] - np.array(START_BOX_POS[:2])) < BOX_INNER_HALF)
    assert abs(lower[2] - BOX_FLOOR_TOP) < 0.005

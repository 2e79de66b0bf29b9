"""ALOHA Handover: RMB's success rule on constructed states, the worlds, stability.

The generic promises (start pose, determinism, random actions, expert success, env checker,
LeRobot type) are in ``test_contract.py``; the expert's own test is
``tests/envs/experts/test_handover.py``.
"""

import mujoco
import numpy as np
import pytest

from rmb_lerobot.envs.base import RmbEnv
from rmb_lerobot.envs.registry import ENVS
from rmb_lerobot.envs.tasks.handover import (
    MAT1,
    MAT2,
    OBJECT,
    OBJECT_BASE,
    OBJECT_HEIGHT,
    OBJECT_JOINT,
    HandoverTask,
)
from rmb_lerobot.envs.workspace import ALOHA_TABLE


@pytest.fixture(scope="module")
def handover_env():
    env = ENVS["aloha_handover"].make(cameras=())
    yield env
    env.close()


def _place_object(env: RmbEnv, offset_from_mat2: tuple[float, float, float]) -> None:
    """The object (its origin: the bottom of its base plate) at mat 2's origin + offset."""
    qpos = env.sim.data.joint(OBJECT_JOINT).qpos
    qpos[:3] = env.sim.data.body(MAT2).xpos + np.asarray(offset_from_mat2)
    mujoco.mj_kinematics(env.sim.model, env.sim.data)


@pytest.mark.parametrize(
    ("offset", "expected"),
    [
        ((0.0, 0.0, OBJECT_HEIGHT), True),  # standing on mat 2
        ((0.09, -0.09, OBJECT_HEIGHT), True),  # near a corner: base centre within 0.1
        ((0.0, 0.0, 0.06), True),  # RMB's box reaches 0.08 m up: held just over the mat
        ((0.11, 0.0, OBJECT_HEIGHT), False),  # base centre beyond the mat in x
        ((0.0, -0.11, OBJECT_HEIGHT), False),  # in y
        ((0.0, 0.0, 0.08), False),  # base centre 9 cm up: out of the box
    ],
)
def test_success_is_rmbs_box_around_mat2(handover_env, offset, expected):
    handover_env.reset(seed=0)
    _place_object(handover_env, offset)
    assert handover_env.task.is_success(handover_env.sim.scene) is expected


def test_the_object_starts_on_mat1_not_on_mat2(handover_env):
    _, info = handover_env.reset(seed=0, options={"world_idx": 0})
    data = handover_env.sim.data
    np.testing.assert_allclose(data.body(OBJECT).xpos[:2], data.body(MAT1).xpos[:2])
    assert not info["is_success"]
    base = data.geom(OBJECT_BASE).xpos
    assert base[2] == pytest.approx(ALOHA_TABLE.table.top_z + OBJECT_HEIGHT + 0.01)


@pytest.mark.parametrize("world_idx", [0, 3, 5])
def test_worlds_move_the_object_and_mat1_one_way_and_mat2_the_other(handover_env, world_idx):
    handover_env.reset(seed=0, options={"world_idx": world_idx})
    data, task = handover_env.sim.data, HandoverTask(ALOHA_TABLE)
    offset = HandoverTask.world_offsets[world_idx]
    assert offset[1] == pytest.approx(-0.02 * world_idx)  # RMB: 0 .. -0.10 m in y
    np.testing.assert_allclose(data.body(OBJECT).xpos, task.object_nominal_pos + offset)
    np.testing.assert_allclose(data.body(MAT1).xpos, task.mat1_nominal_pos + offset)
    np.testing.assert_allclose(data.body(MAT2).xpos, task.mat2_nominal_pos - offset)


def test_random_shift_moves_mat2_opposite_to_the_object_and_is_seeded(handover_env):
    task = HandoverTask(ALOHA_TABLE)
    shifts = []
    for _ in range(2):
        handover_env.reset(seed=7, options={"world_idx": 2, "random_shift": 0.03})
        data = handover_env.sim.data
        shift = data.body(OBJECT).xpos - task.object_nominal_pos - HandoverTask.world_offsets[2]
        mat2 = data.body(MAT2).xpos - task.mat2_nominal_pos + HandoverTask.world_offsets[2]
        np.testing.assert_allclose(mat2, -shift, atol=1e-12)
        shifts.append(shift)
    np.testing.assert_array_equal(shifts[0], shifts[1])
    assert np.all(np.abs(shifts[0][:2]) <= 0.03) and shifts[0][2] == 0.0


@pytest.mark.parametrize(("seed", "world_idx"), [(0, 0), (1, 5)])
def test_random_actions_keep_the_simulation_stable(handover_env, random_actions, seed, world_idx):
    handover_env.reset(seed=seed, options={"world_idx": world_idx})
    for _ in random_actions(handover_env, steps=150, seed=seed):
        pass
    obj = handover_env.sim.data.body(OBJECT).xpos
    # Wherever the arms knocked it, the object stays in the scene, above the floor.
    assert np.all(np.isfinite(obj)) and obj[2] > 0.0


def test_render_shows_overhead_cam_in_a_scene_without_front():
    env = ENVS["aloha_handover"].make(cameras=("worms_eye_cam",), image_size=(32, 24))
    try:
        env.reset(seed=0)
        assert env.render_camera == "overhead_cam"  # RMB's ALOHA has no ``front`` camera
        assert env.render().shape == (24, 32, 3)
    finally:
        env.close()

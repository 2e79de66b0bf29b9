"""G1 Bottles: the scene, the success rule on constructed states, the random shift."""

import mujoco
import numpy as np
import pytest

from rmb_lerobot.envs.base import RmbEnv
from rmb_lerobot.envs.registry import ENVS, compose
from rmb_lerobot.envs.tasks.bottles import BOTTLE_XY, BOTTLES, BottlesTask
from rmb_lerobot.envs.workspace import G1_TABLE


@pytest.fixture(scope="module")
def bottles_env():
    env = compose(BottlesTask(), "g1", cameras=())
    yield env
    env.close()


def _place(env: RmbEnv, bottle: str, height: float, tilt_deg: float = 0.0) -> None:
    """Stand ``bottle`` at its start, its bottom ``height`` above the table, tilted about x."""
    joint = env.sim.data.joint(bottle)
    joint.qpos[2] = G1_TABLE.table.top_z + height
    half = np.deg2rad(tilt_deg) / 2
    joint.qpos[3:] = (np.cos(half), np.sin(half), 0.0, 0.0)
    mujoco.mj_kinematics(env.sim.model, env.sim.data)


def test_registered_as_rmbs_g1_bottles():
    entry = ENVS["g1_bottles"]
    assert entry.rmb_env_name == "MujocoG1Bottles" and entry.env_attr == "MujocoG1BottlesEnv"
    assert entry.lerobot_type == "rmb_g1_bottles" and entry.workspace is G1_TABLE
    assert BottlesTask.world_offsets.shape == (1, 3)  # RMB's one world


def test_bottles_stand_on_the_table_in_front_of_the_robot(bottles_env):
    _, info = bottles_env.reset(seed=0)
    assert not info["is_success"]
    for bottle, (x, y) in zip(BOTTLES, BOTTLE_XY, strict=True):
        np.testing.assert_allclose(
            bottles_env.sim.data.body(bottle).xpos, (x, y, G1_TABLE.table.top_z)
        )
    # A few steps with the robot holding home: the bottles stay where they stand.
    for _ in range(10):
        bottles_env.step(bottles_env.home_command.astype(np.float32))
    for bottle, (x, y) in zip(BOTTLES, BOTTLE_XY, strict=True):
        pos = bottles_env.sim.data.body(bottle).xpos
        assert np.hypot(pos[0] - x, pos[1] - y) < 1e-3
        assert abs(pos[2] - G1_TABLE.table.top_z) < 2e-3


@pytest.mark.parametrize(
    ("left", "right", "expected"),
    [
        ((0.12, 0.0), (0.12, 0.0), True),  # both up, upright
        ((0.12, 25.0), (0.15, -25.0), True),  # both up, tilted within 30 deg
        ((0.12, 0.0), (0.0, 0.0), False),  # only the left one up
        ((0.0, 0.0), (0.12, 0.0), False),  # only the right one up
        ((0.08, 0.0), (0.12, 0.0), False),  # the left one not high enough
        ((0.12, 40.0), (0.12, 0.0), False),  # the left one up but tipped over
    ],
)
def test_success_is_both_bottles_up_and_upright(bottles_env, left, right, expected):
    bottles_env.reset(seed=0)
    for bottle, (height, tilt) in zip(BOTTLES, (left, right), strict=True):
        _place(bottles_env, bottle, height, tilt)
    assert bottles_env.task.is_success(bottles_env.sim) is expected


def test_random_shift_moves_both_bottles_together_in_the_plane(bottles_env):
    starts = []
    for seed in (3, 3, 4):
        bottles_env.reset(seed=seed, options={"random_shift": 0.03})
        starts.append([bottles_env.sim.data.body(b).xpos.copy() for b in BOTTLES])
    np.testing.assert_array_equal(starts[0], starts[1])  # seeded
    for positions in starts:
        table = G1_TABLE.table.top_z
        shifts = [pos - (x, y, table) for pos, (x, y) in zip(positions, BOTTLE_XY, strict=True)]
        np.testing.assert_allclose(shifts[0], shifts[1])
        assert np.all(np.abs(shifts[0][:2]) <= 0.03) and shifts[0][2] == 0.0
    assert not np.allclose(starts[0], starts[2])


def test_cameras_are_the_robots_head_and_a_front_overview():
    env = compose(BottlesTask(), "g1", image_size=(64, 48))
    try:
        assert env.available_cameras == ("front", "head")
        env.reset(seed=0)
        head = env.sim.render(["head"])[0]["head"]
        assert head.shape == (48, 64, 3) and head.std() > 0  # a picture, not one colour
    finally:
        env.close()

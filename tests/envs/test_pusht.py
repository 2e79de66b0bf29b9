"""PushT (xArm7): RMB's placement per world, the success criterion on constructed poses, the
block resting on the table, and the expert's push model."""

import mujoco
import numpy as np
import pytest

from rmb_lerobot.envs.experts.pusht import (
    CORNERS,
    candidate_pushes,
    distance_to_block,
    predict_pushes,
)
from rmb_lerobot.envs.registry import ENVS
from rmb_lerobot.envs.tasks.pusht import GOAL, TBLOCK, TBLOCK_JOINT, block_mass, yaw_of

# MujocoXarm7PushtEnv.py / env_xarm7_pusht.xml: block start, goal and the six world offsets.
RMB_BLOCK = np.array([0.15, 0.0, 0.76])
RMB_BLOCK_YAW = 1.4
RMB_GOAL = np.array([0.0, 0.1, 0.74])
RMB_GOAL_YAW = -1.0
RMB_WORLD_Y = (-0.06, -0.03, 0.0, 0.03, 0.06, 0.09)


@pytest.fixture(scope="module")
def env():
    env = ENVS["xarm7_pusht"].make(cameras=())
    yield env
    env.close()


@pytest.mark.parametrize("world", range(6))
def test_block_and_goal_where_rmb_puts_them(env, world):
    env.reset(seed=0, options={"world_idx": world})
    pos, rot = env.sim.body_pose(TBLOCK)
    assert pos == pytest.approx(RMB_BLOCK + np.array([0.0, RMB_WORLD_Y[world], 0.0]), abs=1e-6)
    assert yaw_of(rot) == pytest.approx(RMB_BLOCK_YAW, abs=1e-6)
    goal, goal_rot = env.sim.body_pose(GOAL)
    assert goal == pytest.approx(RMB_GOAL, abs=1e-9)
    assert yaw_of(goal_rot) == pytest.approx(RMB_GOAL_YAW, abs=1e-9)


def test_block_is_rmbs_red_default_density_block(env):
    assert env.sim.model.body(TBLOCK).mass[0] == pytest.approx(0.576)  # 1000 kg/m^3
    assert block_mass() == pytest.approx(0.576)
    for name in ("tblock1", "tblock2"):
        geom = env.sim.model.geom(name)
        assert geom.friction[0] == 1.0
        assert tuple(env.sim.model.mat_rgba[geom.matid[0]]) == (1.0, 0.0, 0.0, 1.0)
    for name in ("target_region1", "target_region2"):  # drawn only
        geom = env.sim.model.geom(name)
        assert geom.contype[0] == 0 and geom.conaffinity[0] == 0


def test_random_shift_moves_the_block_on_the_table_only(env):
    for seed in range(4):
        env.reset(seed=seed, options={"world_idx": 2, "random_shift": 0.03})
        pos = env.sim.body_pose(TBLOCK)[0]
        assert np.all(np.abs(pos[:2] - RMB_BLOCK[:2]) <= 0.03)
        assert pos[2] == pytest.approx(RMB_BLOCK[2])


def place_block(env, dxy=(0.0, 0.0), dyaw_deg=0.0) -> bool:
    """Put the block at the goal pose moved by ``dxy`` and turned by ``dyaw_deg`` (no physics)."""
    goal = env.sim.body_pose(GOAL)[0]
    yaw = RMB_GOAL_YAW + np.deg2rad(dyaw_deg)
    qpos = env.sim.data.joint(TBLOCK_JOINT).qpos
    qpos[:3] = [goal[0] + dxy[0], goal[1] + dxy[1], RMB_BLOCK[2]]
    qpos[3:] = [np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)]
    mujoco.mj_kinematics(env.sim.model, env.sim.data)
    return env.task.is_success(env.sim)


@pytest.mark.parametrize(
    ("state", "expected"),
    [
        ({}, True),
        ({"dxy": (0.02, -0.02)}, True),  # 2.8 cm off
        ({"dyaw_deg": 4.5}, True),
        ({"dyaw_deg": -4.5}, True),
        ({"dxy": (0.04, 0.0)}, False),
        ({"dxy": (-0.0283, -0.0283)}, False),  # 4 cm off
        ({"dyaw_deg": 6.0}, False),
        ({"dyaw_deg": -6.0}, False),
        ({"dyaw_deg": 360.0}, True),  # yaw wraps
    ],
)
def test_success_criterion(env, state, expected):
    env.reset(seed=0, options={"world_idx": 1})
    assert not env.task.is_success(env.sim)  # the start is far from the goal
    assert place_block(env, **state) is expected


@pytest.mark.parametrize("seed", range(3))
def test_block_rests_on_the_table(env, seed):
    env.reset(seed=seed, options={"world_idx": seed * 2, "random_shift": 0.03})
    start, start_rot = env.sim.body_pose(TBLOCK)
    for _ in range(60):  # ~2 s with the arm holding its home pose
        env.step(env.home_command)
    pos, rot = env.sim.body_pose(TBLOCK)
    assert np.linalg.norm(pos - start) < 1e-3
    assert abs(yaw_of(rot) - yaw_of(start_rot)) < 1e-3
    assert rot[2, 2] > 0.9999  # flat, right side up
    assert np.linalg.norm(env.sim.joint_velocity(TBLOCK_JOINT)) < 1e-3


def test_distance_to_block_follows_the_t_outline():
    pos, yaw = np.array([0.1, 0.2]), np.pi / 2  # bar along world y, stem towards -x
    assert distance_to_block(pos, pos, yaw) == 0.0
    past_bar, past_stem = pos + np.array([0.05, 0.0]), pos + np.array([-0.2, 0.0])
    assert distance_to_block(past_bar, pos, yaw) == pytest.approx(0.03)
    assert distance_to_block(past_stem, pos, yaw) == pytest.approx(0.02)
    corners = pos + CORNERS @ np.array([[0.0, 1.0], [-1.0, 0.0]])  # rotated by +90 degrees
    assert np.allclose(distance_to_block(corners, pos, yaw), 0.0)


def test_push_model_moves_and_turns_the_block_as_expected():
    """Pushing the bar's underside through the centre of mass translates the block; pushing
    the bar off its centre turns it (counter-clockwise right of the centre)."""
    cand = candidate_pushes(0.0, 0.01, (0.0,), 0.006, 0.02)
    pos = np.zeros(2)
    p_pos, p_yaw, valid = predict_pushes(pos, 0.0, cand, 6, 0.005, 0.08, 0.8)
    under = np.flatnonzero((cand.normal[:, 1] == 1.0) & (cand.contact[:, 1] < 0))
    centre = under[np.argmin(np.abs(cand.contact[under, 0]))]
    right = under[np.argmin(np.abs(cand.contact[under, 0] - 0.07))]  # 7 cm off the centre
    assert valid[-1, centre] and valid[-1, right]
    assert p_pos[-1, centre] == pytest.approx([0.0, 0.03], abs=1e-3)  # pushed 3 cm along +y
    assert abs(p_yaw[-1, centre]) < 1e-3
    assert p_yaw[-1, right] > np.deg2rad(5.0)
    assert 0.0 < p_pos[-1, right, 1] < 0.03

"""Toolbox: success criterion on constructed states, worlds, stability and the scripted expert."""

import mujoco
import numpy as np
import pytest

from rmb_lerobot.envs.base import RmbEnv
from rmb_lerobot.envs.experts.toolbox import ToolboxExpert
from rmb_lerobot.envs.registry import compose
from rmb_lerobot.envs.tasks.toolbox import MAT, MAT_TOP, TOOLBOX, ToolboxTask


@pytest.fixture(scope="module")
def toolbox_env():
    env = compose(ToolboxTask(), cameras=())
    yield env
    env.close()


def _place_toolbox(env: RmbEnv, offset_from_mat: tuple[float, float, float]) -> None:
    qpos = env.sim.data.joint(TOOLBOX).qpos
    qpos[:3] = ToolboxTask().mat_pos + np.asarray(offset_from_mat)
    mujoco.mj_kinematics(env.sim.model, env.sim.data)


@pytest.mark.parametrize(
    ("offset", "expected"),
    [
        ((0.0, 0.0, MAT_TOP), True),  # resting on the mat
        ((0.025, -0.025, MAT_TOP), True),  # off-centre, within 0.03 on each axis
        ((0.035, 0.0, MAT_TOP), False),  # too far in x
        ((0.0, -0.035, MAT_TOP), False),  # too far in y
        ((0.0, 0.0, 0.02), False),  # held above the mat
        ((0.0, -0.4, 0.0), False),  # still at its start
    ],
)
def test_success_criterion(toolbox_env, offset, expected):
    toolbox_env.reset(seed=0)
    _place_toolbox(toolbox_env, offset)
    assert toolbox_env.task.is_success(toolbox_env.sim) is expected


@pytest.mark.parametrize("world_idx", [0, 5])
def test_worlds_shift_the_toolbox_only(toolbox_env, world_idx):
    _, info = toolbox_env.reset(seed=0, options={"world_idx": world_idx})
    expected = ToolboxTask().toolbox_nominal_pos + ToolboxTask.world_offsets[world_idx]
    assert toolbox_env.sim.data.body(TOOLBOX).xpos == pytest.approx(expected)
    assert toolbox_env.sim.data.body(MAT).xpos == pytest.approx(ToolboxTask().mat_pos)
    assert not info["is_success"]


def test_random_shift_is_bounded_planar_and_seeded(toolbox_env):
    nominal = ToolboxTask().toolbox_nominal_pos + ToolboxTask.world_offsets[3]
    positions = []
    for _ in range(2):
        toolbox_env.reset(seed=7, options={"world_idx": 3, "random_shift": 0.03})
        positions.append(toolbox_env.sim.data.body(TOOLBOX).xpos.copy())
    shift = positions[0] - nominal
    assert np.all(np.abs(shift[:2]) <= 0.03) and np.any(np.abs(shift[:2]) > 1e-4)
    assert shift[2] == 0.0  # the box starts on the table, not in or above it
    assert positions[1] == pytest.approx(positions[0])


def test_toolbox_rests_stably(toolbox_env):
    toolbox_env.reset(seed=0, options={"world_idx": 0})
    start = toolbox_env.sim.data.body(TOOLBOX).xpos.copy()
    for _ in range(100):
        toolbox_env.step(toolbox_env.home_command.astype(np.float32))
    assert np.all(np.isfinite(toolbox_env.sim.data.qpos))
    assert toolbox_env.sim.data.body(TOOLBOX).xpos == pytest.approx(start, abs=1e-3)


@pytest.mark.parametrize("world", [0, 5])
def test_expert_places_the_toolbox_on_the_mat(toolbox_env, run_expert, world):
    info = run_expert(toolbox_env, ToolboxExpert, world)  # seed = world
    upright = toolbox_env.sim.data.body(TOOLBOX).xmat.reshape(3, 3)[2, 2]
    assert info["is_success"], (
        f"world {world}: toolbox at {toolbox_env.sim.data.body(TOOLBOX).xpos}"
    )
    assert upright > np.cos(np.deg2rad(5.0))

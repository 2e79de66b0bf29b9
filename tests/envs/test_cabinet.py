"""Cabinet (hinge and slide): worlds, success criteria on constructed states, the experts."""

import mujoco
import numpy as np
import pytest

from rmb_lerobot.envs.base import RmbEnv
from rmb_lerobot.envs.registry import compose
from rmb_lerobot.envs.tasks.cabinet import (
    CABINET,
    HINGE,
    SLIDE,
    CabinetHingeTask,
    CabinetSlideTask,
    CabinetTask,
)

# RMB's MujocoUR5eCabinetEnv cabinet_pos_offsets (y only).
RMB_Y_OFFSETS = (-0.06, -0.03, 0.0, 0.03, 0.06, 0.09)


@pytest.fixture(scope="module")
def hinge_env():
    env = compose(CabinetHingeTask(), cameras=())
    yield env
    env.close()


@pytest.fixture(scope="module")
def slide_env():
    env = compose(CabinetSlideTask(), cameras=())
    yield env
    env.close()


@pytest.fixture(params=["hinge_env", "slide_env"])
def cabinet_env(request):
    return request.getfixturevalue(request.param)


def _set_joints(env: RmbEnv, hinge: float, slide: float) -> bool:
    """Put the lid and the door at the given positions; return the task's success."""
    env.reset(seed=0)
    env.sim.data.joint(HINGE).qpos[0] = hinge
    env.sim.data.joint(SLIDE).qpos[0] = slide
    mujoco.mj_kinematics(env.sim.model, env.sim.data)
    return env.task.is_success(env.sim)


@pytest.mark.parametrize(
    ("hinge_deg", "slide", "expected"),
    [(0, 0.0, False), (119, 0.0, False), (121, 0.0, True), (179, 0.0, True), (0, 0.15, False)],
)
def test_hinge_success_criterion(hinge_env, hinge_deg, slide, expected):
    assert _set_joints(hinge_env, np.deg2rad(hinge_deg), slide) is expected


@pytest.mark.parametrize(
    ("hinge_deg", "slide", "expected"),
    [(0, 0.0, False), (0, 0.119, False), (0, 0.121, True), (0, 0.15, True), (150, 0.0, False)],
)
def test_slide_success_criterion(slide_env, hinge_deg, slide, expected):
    assert _set_joints(slide_env, np.deg2rad(hinge_deg), slide) is expected


@pytest.mark.parametrize("world_idx", range(6))
def test_worlds_shift_the_cabinet_as_rmb(cabinet_env, world_idx):
    _, info = cabinet_env.reset(seed=0, options={"world_idx": world_idx, "random_shift": 0.0})
    expected = CabinetHingeTask().cabinet_nominal_pos + np.array(
        [0.0, RMB_Y_OFFSETS[world_idx], 0.0]
    )
    assert cabinet_env.sim.data.body(CABINET).xpos == pytest.approx(expected)
    assert cabinet_env.sim.data.joint(HINGE).qpos[0] == 0.0
    assert cabinet_env.sim.data.joint(SLIDE).qpos[0] == 0.0
    assert info["is_success"] is False


def test_random_shift_stays_on_the_table_and_is_seeded(cabinet_env):
    options = {"world_idx": 2, "random_shift": 0.03}
    cabinet_env.reset(seed=7, options=options)
    first = cabinet_env.sim.data.body(CABINET).xpos.copy()
    shift = first - CabinetHingeTask().cabinet_nominal_pos - CabinetTask.world_offsets[2]
    assert np.all(np.abs(shift[:2]) <= 0.03) and np.any(shift[:2] != 0.0)
    assert shift[2] == 0.0
    cabinet_env.reset(seed=7, options=options)
    assert cabinet_env.sim.data.body(CABINET).xpos == pytest.approx(first)


def test_closed_cabinet_stays_closed_and_finite(cabinet_env):
    obs, _ = cabinet_env.reset(seed=1, options={"world_idx": 5, "random_shift": 0.03})
    for _ in range(60):
        obs, *_ = cabinet_env.step(cabinet_env.home_command.astype(np.float32))
    assert np.all(np.isfinite(cabinet_env.sim.data.qpos)) and np.all(np.isfinite(obs["agent_pos"]))
    assert abs(cabinet_env.sim.data.joint(HINGE).qpos[0]) < np.deg2rad(1.0)
    assert abs(cabinet_env.sim.data.joint(SLIDE).qpos[0]) < 1e-3

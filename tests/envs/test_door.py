"""Door: worlds, the success criterion on constructed states, and the scripted expert."""

import mujoco
import numpy as np
import pytest

from rmb_lerobot.envs.registry import compose
from rmb_lerobot.envs.tasks.door import DOOR, DoorTask


@pytest.fixture(scope="module")
def door_env():
    env = compose(DoorTask(), cameras=())
    yield env
    env.close()


@pytest.mark.parametrize(("angle_deg", "expected"), [(0, False), (-44, False), (-45.5, True)])
def test_success_criterion(door_env, angle_deg, expected):
    door_env.reset(seed=0)
    door_env.sim.data.joint(DOOR).qpos[0] = np.deg2rad(angle_deg)
    mujoco.mj_kinematics(door_env.sim.model, door_env.sim.data)
    assert door_env.task.is_success(door_env.sim) is expected


@pytest.mark.parametrize("world_idx", [0, 5])
def test_worlds_shift_the_door(door_env, world_idx):
    door_env.reset(seed=0, options={"world_idx": world_idx})
    expected = DoorTask().door_nominal_pos + DoorTask.world_offsets[world_idx]
    assert door_env.sim.data.body(DOOR).xpos == pytest.approx(expected)
    assert door_env.sim.data.joint(DOOR).qpos[0] == 0.0

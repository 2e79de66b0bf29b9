"""Door: worlds, the success criterion on constructed states, and the scripted expert."""

import mujoco
import numpy as np
import pytest
from rmb_lerobot.envs.base import RmbEnv
from rmb_lerobot.envs.experts.door import DoorExpert
from rmb_lerobot.envs.tasks.door import DOOR, DoorTask


@pytest.fixture(scope="module")
def door_env():
    env = RmbEnv(DoorTask(), cameras=())
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


def test_start_pose_is_rmbs(door_env):
    obs, _ = door_env.reset(seed=0)
    assert obs["agent_pos"][:6] == pytest.approx(DoorTask.start_poses["ur5e"][0], abs=1e-6)


def test_expert_opens_the_door(door_env):
    expert = DoorExpert(door_env)
    for world in (1, 4):
        obs, _ = door_env.reset(seed=world, options={"world_idx": world, "random_shift": 0.02})
        expert.reset()
        for _ in range(door_env.task.max_episode_steps):
            obs, _, terminated, _, info = door_env.step(expert(obs))
            if terminated:
                break
        assert info["is_success"], f"world {world}: door at {door_env.sim.data.joint(DOOR).qpos}"

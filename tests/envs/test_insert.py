"""Insert: the success criterion on constructed states, and the scripted expert."""

import mujoco
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from rmb_lerobot.envs.tasks.insert import HOLE, PEG, PEG_HALF_LENGTH


def place_peg(env, dxy=(0.0, 0.0), end_height=0.005, tilt_deg=0.0):
    """Put the peg with its lower end ``end_height`` above the hole floor (no physics)."""
    hole = env.sim.data.body(HOLE).xpos.copy()
    rot = Rotation.from_euler("x", 180 + tilt_deg, degrees=True)  # z axis down, as held
    axis = rot.apply([0, 0, 1])
    centre = hole + np.array([dxy[0], dxy[1], end_height + PEG_HALF_LENGTH * abs(axis[2])])
    qpos = env.sim.data.joint(PEG).qpos
    qpos[:3] = centre
    qpos[3:] = rot.as_quat(scalar_first=True)
    mujoco.mj_kinematics(env.sim.model, env.sim.data)
    return env.task.is_success(env.sim)


@pytest.mark.parametrize(
    ("state", "expected"),
    [
        ({}, True),
        ({"dxy": (0.008, -0.008)}, True),  # 11.3 mm off the axis
        ({"dxy": (0.01, 0.01)}, False),  # 14.1 mm off the axis
        ({"end_height": 0.009}, True),
        ({"end_height": 0.02}, False),  # only 2 cm inside
        ({"tilt_deg": 8.0}, True),
        ({"tilt_deg": 12.0}, False),
    ],
)
def test_success_criterion(physics_env, state, expected):
    physics_env.reset(seed=0, options={"world_idx": 1})
    assert place_peg(physics_env, **state) is expected


def test_peg_starts_in_the_gripper_and_stays_there(physics_env):
    physics_env.reset(seed=0)
    tcp = physics_env.sim.data.site(physics_env.robot.arms[0].tcp_frame)
    gap = physics_env.sim.data.body(PEG).xpos - tcp.xpos
    for _ in range(20):
        physics_env.step(physics_env.home_command)
    assert np.linalg.norm(physics_env.sim.data.body(PEG).xpos - tcp.xpos - gap) < 0.005

"""TactoSawyerGrasp: RMB's success rule, and what the fingertip sensors show during a grasp."""

from __future__ import annotations

import numpy as np
import pybullet as p
import pytest

from rmb_lerobot.envs.registry import ENVS
from rmb_lerobot.envs.tasks.tacto_grasp import BOX, BOX_HALF_SIZE

GRASP = ENVS["pybullet_sawyer_grasp"]


@pytest.fixture(scope="module")
def env():
    env = GRASP.make(
        cameras=("tactile_left", "tactile_right"),
        tactile_size=(80, 60),
        tactile_noise=False,
        renderer="tiny",
    )
    yield env
    env.close()


def _place_box(env, z: float, velocity=(0.0, 0.0, 0.0)) -> bool:
    env.sim.reset_body(BOX, (0.6, 0.0, z))
    p.resetBaseVelocity(
        env.sim.body_id(BOX), list(velocity), [0, 0, 0], physicsClientId=env.sim.client_id
    )
    return env.task.is_success(env.sim.scene)


def test_success_is_lifted_and_at_rest(env):
    env.reset(seed=0)
    assert not env.task.is_success(env.sim.scene)  # on the floor
    assert env.sim.scene.body_pose(BOX)[0][2] == pytest.approx(BOX_HALF_SIZE[2], abs=1e-6)
    assert _place_box(env, 0.15)
    assert not _place_box(env, 0.09)  # centre not above 0.1 m
    assert not _place_box(env, 0.15, velocity=(0.0, 0.0, 0.05))  # still moving


def test_the_box_rests_where_rmb_puts_it(env):
    env.reset(seed=0, options={"random_shift": 0.0})
    for _ in range(30):
        env.step(env.home_command.astype(np.float32))
    pos, rot = env.sim.scene.body_pose(BOX)
    np.testing.assert_allclose(pos, [0.6, 0.0, BOX_HALF_SIZE[2]], atol=1e-3)
    np.testing.assert_allclose(rot, np.eye(3), atol=1e-3)


def test_sensors_see_the_grasp_and_nothing_before_it(env):
    """Untouched pads show the reference gel; once the expert squeezes the box both pads show
    its face pressed in, alike (the box is centred between them)."""
    expert = GRASP.load_expert_class()(env)
    obs, _ = env.reset(seed=0)
    expert.reset()
    reference = obs["pixels"]["tactile_left"].copy()
    np.testing.assert_array_equal(obs["pixels"]["tactile_right"], reference)
    for _ in range(env.task.max_episode_steps):
        obs, _, terminated, _, _ = env.step(expert(obs))
        if terminated:
            break
    assert terminated
    left, right = (obs["pixels"][k].astype(float) for k in ("tactile_left", "tactile_right"))
    pressed_left = np.abs(left - reference).max(axis=-1) > 10
    pressed_right = np.abs(right - reference).max(axis=-1) > 10
    assert pressed_left.mean() > 0.5 and pressed_right.mean() > 0.5
    # Mirrored pads: the right image is the left one upside down (module docstring of
    # rmb_lerobot.envs.pybullet.tactile); a centred grasp presses both alike.
    assert np.mean(pressed_left == pressed_right[::-1]) > 0.9
